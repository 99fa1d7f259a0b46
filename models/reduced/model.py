"""One reduced model of a specimen, read by QSMA, harmonic balance and the nonlinear modes.

From the specimen's linear matrices (:func:`~iwan_element.models.reduced.dispatch.linear_system`:
mass ``M``, stiffness ``K0`` without the tangential interface, the slip map ``G``, the sensor
row ``S`` and the excitation row ``E``) and its contact points' Iwan elements:

1. the stuck tangent ``K_s = K0 + G^T diag(KT_i) G`` and all its mass-normalised modes
   (the beam models have a few hundred coordinates: the full eigenproblem is cheap);
2. the kept modes: the rigid-body modes and the lowest ``n_modes`` elastic ones, each with
   its own linear damping ratio ``specimen.floor(r)`` (modal damping: the floor per mode);
3. the ports: the contact slips ``G x``, the sensor ``S x`` and the excitation ``E x``; the
   modes not kept enter through their static residual flexibility
   ``R = sum_{r not kept} Y_r Y_r^T / w_r^2`` (MacNeal's residual flexibility), which makes
   the reduced model exact in statics and in the stuck limit at ``w = 0``.

The result is an :class:`iwan_element.harmonic.ModalSystem` (``ReducedModel.system``) with
the contact points' Iwan parameters on the slips; :func:`reduction_error` states what the
truncation costs against the full model (``docs/harmonic_balance.md`` section 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import scipy.linalg as sla

from iwan_element.base.threads import one_blas_thread
from iwan_element.harmonic import ModalSystem

from ..solid.specimen import SolidSpecimen
from ..specimens.specimen import Specimen
from .dispatch import (
    bolt_groups,
    check_kept_mode,
    check_specimen,
    contact_points,
    linear_system,
)

__all__ = ["ReducedModel", "reduced_model", "reduction_error", "stuck_modes", "stuck_key"]

_RIGID_HZ = 0.5  # modes below this are the rigid-body ones (free-free), as qsma's


@dataclass(frozen=True, eq=False)
class ReducedModel:
    """A specimen's stuck-interface modes at its ports (module docstring).

    Attributes
    ----------
    specimen : Specimen or SolidSpecimen
    system : ModalSystem
        Kept modes (rigid first), floors, port shapes, residual flexibility and the contact
        points' Iwan parameters.
    n_rigid : int
        Rigid-body modes among the kept ones (3 for a free-free specimen, else 0).
    omega_all : ndarray
        Every elastic mode's circular frequency of the full model [rad/s].
    phi : ndarray, shape (n_free, n_kept)
        The kept mode shapes on the full model's free coordinates (mass-normalised, each
        elastic one with a positive sensor displacement).
    """

    specimen: Specimen | SolidSpecimen
    system: ModalSystem
    n_rigid: int
    omega_all: np.ndarray
    phi: np.ndarray

    def mode_index(self, mode: int) -> int:
        """Column of elastic mode ``mode`` (1: lowest) among the kept modes."""
        if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode < 1:
            raise ValueError(f"mode must be an integer >= 1, got {mode!r}")
        k = self.n_rigid + int(mode) - 1
        check_kept_mode(
            self.specimen,
            k,
            name="mode",
            value=mode,
            offset=self.n_rigid,
        )
        if k >= self.system.omega.size:
            raise ValueError(
                f"mode must be <= {self.system.omega.size - self.n_rigid} (the "
                f"elastic modes kept), got {mode}"
            )
        return k

    def frequency(self, mode: int) -> float:
        """Stuck natural frequency of elastic mode ``mode`` [Hz]."""
        return float(self.system.omega[self.mode_index(mode)] / (2.0 * math.pi))


def reduced_model(specimen: Specimen | SolidSpecimen, *, n_modes: int = 8) -> ReducedModel:
    """The reduced model of a specimen (cached on the specimen).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    n_modes : int, keyword-only
        Elastic modes kept (>= 1); the others enter as static residual flexibility.

    Returns
    -------
    ReducedModel
    """
    check_specimen(specimen)
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ValueError(f"n_modes must be an integer >= 1, got {n_modes!r}")
    return _reduced(specimen, int(n_modes))


def stuck_key(specimen) -> Specimen | SolidSpecimen:
    """The specimen with the fields that do not change its stuck-interface eigenproblem
    (friction, Iwan shape, floors, ranges, effects) set to fixed values: the cache key of
    the routes that read only the stuck modes and the contact points' stiffness.
    """
    return specimen.replace(
        friction=1.0,
        chi=0.0,
        beta=0.0,
        damping_floor=0.0,
        modal_damping=(),
        amplitude_range=(1.0, 2.0),
        calibrated_range=None,
        effects=(),
        interface_effects=(),
    )


def stuck_modes(specimen: Specimen | SolidSpecimen) -> Any:
    """Every mode of the specimen with its joints stuck: ``(L, points, omega [rad/s], Phi,
    n_low)``, ``Phi`` mass-normalised (columns, each with a non-negative sensor
    displacement), ``n_low`` the modes below 0.5 Hz (rigid-body ones, or an interface that
    lets the beams slide). The one eigenproblem every route reads (cached).
    """
    return _stuck_modes(specimen)


@lru_cache(maxsize=16)
def _stuck_modes(specimen: Specimen | SolidSpecimen):
    L = linear_system(specimen)
    pts = contact_points(specimen)
    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    with one_blas_thread():  # small dense problem: threads only contend
        w2, V = sla.eigh(0.5 * (K + K.T), L.M)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, L.M @ V))[None, :]
    n_rigid = int(np.sum(w2 < (2 * math.pi * _RIGID_HZ) ** 2))
    s = np.sign(L.S @ V)
    s[s == 0] = 1.0
    V = V * s[None, :]
    return L, pts, np.sqrt(np.abs(w2)), V, n_rigid


@lru_cache(maxsize=16)
def _reduced(specimen: Specimen | SolidSpecimen, n_modes: int) -> ReducedModel:
    L, pts, w, V, n_rigid = _stuck_modes(specimen)
    w = w.copy()
    w[:n_rigid] = 0.0  # rigid-body modes: exactly zero frequency
    if L.E is None:
        raise ValueError("the specimen's linear system has no excitation row")
    n_keep = min(n_rigid + n_modes, w.size)
    ports = np.vstack([L.G, L.S[None, :], L.E[None, :]])
    Y = ports @ V
    rest = slice(n_keep, w.size)
    R = (Y[:, rest] / w[rest] ** 2) @ Y[:, rest].T
    zeta = np.array([0.0] * n_rigid + [specimen.floor(r) for r in range(1, n_keep - n_rigid + 1)])
    system = ModalSystem(
        omega=w[:n_keep],
        zeta=zeta,
        modes=Y[:, :n_keep],
        joints=pts.params,
        residual=0.5 * (R + R.T),
        n_full=L.M.shape[0],
        joint_groups=bolt_groups(specimen),
        notes=f"{specimen.name}: {n_keep - n_rigid} elastic modes kept of "
        f"{w.size - n_rigid}, {n_rigid} rigid, {len(pts)} contact points",
    )
    return ReducedModel(
        specimen=specimen,
        system=system,
        n_rigid=n_rigid,
        omega_all=w[n_rigid:].copy(),
        phi=V[:, :n_keep].copy(),
    )


def reduction_error(specimen: Specimen, *, n_modes: int = 8, frequencies=None) -> dict:
    """What keeping ``n_modes`` elastic modes costs, against every mode of the full model.

    The stuck-interface port receptances of the reduced model and of the full model (all
    modes, same floors for the kept ones and none for the rest, as the reduced model's
    residual has none) are compared at ``frequencies`` [Hz] (default: 200 from 0 to the
    middle between the highest kept mode and the next).

    Returns
    -------
    dict
        ``n_modes``, ``n_full``, ``f_max_Hz``, ``max_relative_error`` (largest port
        receptance error over the frequencies, relative to the largest receptance entry at
        that frequency), ``static_relative_error`` (at 0 Hz: round-off).
    """
    red = reduced_model(specimen, n_modes=n_modes)
    L, pts, w, V, n_rigid = _stuck_modes(specimen)
    w = w.copy()
    w[:n_rigid] = 0.0
    n_keep = red.system.omega.size
    full = ModalSystem(
        omega=w,
        zeta=np.concatenate([red.system.zeta, np.zeros(w.size - n_keep)]),
        modes=np.vstack([L.G, L.S[None, :], L.E[None, :]]) @ V,
        joints=pts.params,
    )
    top = 0.5 * (w[n_keep - 1] + w[min(n_keep, w.size - 1)]) / (2 * math.pi)
    f = np.linspace(0.0, top, 200) if frequencies is None else np.asarray(frequencies, float)
    err = []
    for fk in f:
        Hr = red.system.receptance(2 * math.pi * fk)
        Hf = full.receptance(2 * math.pi * fk)
        err.append(float(np.abs(Hr - Hf).max() / np.abs(Hf).max()))
    return {
        "n_modes": n_keep - n_rigid,
        "n_full": int(L.M.shape[0]),
        "f_max_Hz": float(f.max()),
        "max_relative_error": float(max(err)),
        "static_relative_error": float(err[0]) if f[0] == 0 else None,
    }
