"""The stuck-joint modes of a specimen and their sensitivities to its linear parameters.

:func:`modal_sensitivities` gives the natural frequencies, the mode shapes at sensor
positions and the drive-point modal constants with their derivatives by every parameter
(:func:`~iwan_element.models.updating.parameters.updatable`): the matrices' derivatives by
central differences of the assembled system (exact to round-off where a matrix is linear in
the parameter, as it is for all but the contact layout), then the eigenvalue derivative
``d lambda = phi^T (dK - lambda dM) phi`` and the mode-shape derivative by the expansion over
every mode of the (reduced) system (Fox and Kapoor 1968), ``d phi_r = sum_{s != r} phi_s
phi_s^T (dK - lambda_r dM) phi_r / (lambda_r - lambda_s) - (phi_r^T dM phi_r / 2) phi_r``,
exact when every mode of the finite system is in the sum, as here (Mottershead, Link,
Friswell, MSSP 25:2275-2296, 2011; docs/linear_update.md). A position (the shaker's
attachment point) also moves the excitation row ``E``: the modal constant's derivative holds
``(dE phi)`` beside ``(E dphi)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla

from iwan_element.base.threads import one_blas_thread

from ..reduced.dispatch import axis_rows, contact_points, linear_system
from .parameters import Updatable, with_parameters

__all__ = ["ModalState", "modal_state", "matrix_derivatives", "modal_sensitivities", "pair_modes"]

_RIGID_HZ = 0.5  # modes below this are not numbered (rigid-body ones), as QSMA's


@dataclass(frozen=True, eq=False)
class ModalState:
    """The stuck-joint modes of a specimen with what the targets read.

    Attributes
    ----------
    K, M : ndarray
        Stuck stiffness ``K0 + G^T diag(KT) G`` and mass on the free coordinates.
    lam : ndarray
        Every eigenvalue ``w^2`` [1/s^2], ascending.
    phi : ndarray
        Mass-normalised mode shapes (columns).
    n_rigid : int
        Modes below 0.5 Hz (not numbered).
    S, E : ndarray
        Sensor and excitation rows (the drive-point modal constant is ``(E phi)(S phi)``).
    """

    K: np.ndarray
    M: np.ndarray
    lam: np.ndarray
    phi: np.ndarray
    n_rigid: int
    S: np.ndarray
    E: np.ndarray

    def index(self, mode: int) -> int:
        """Column of elastic mode ``mode`` (1: lowest)."""
        k = self.n_rigid + int(mode) - 1
        if not 1 <= mode or k >= self.lam.size:
            raise ValueError(f"mode must be in [1, {self.lam.size - self.n_rigid}], got {mode}")
        return k

    def frequency(self, k: int) -> float:
        """[Hz] of column ``k``."""
        return math.sqrt(abs(self.lam[k])) / (2 * math.pi)


def _matrices(specimen):
    L = linear_system(specimen)
    pts = contact_points(specimen)
    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    return 0.5 * (K + K.T), np.asarray(L.M, float), L


def _excitation(L) -> np.ndarray:
    return np.asarray(L.E if L.E is not None else L.S, float)


def modal_state(specimen) -> ModalState:
    """:class:`ModalState` of ``specimen`` (every mode of its linear system)."""
    K, M, L = _matrices(specimen)
    with one_blas_thread():
        lam, V = sla.eigh(K, M)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, M @ V))[None, :]
    s = np.sign(L.S @ V)
    s[s == 0] = 1.0
    V = V * s[None, :]
    n_rigid = int(np.sum(lam < (2 * math.pi * _RIGID_HZ) ** 2))
    return ModalState(
        K=K,
        M=M,
        lam=lam,
        phi=V,
        n_rigid=n_rigid,
        S=np.asarray(L.S),
        E=_excitation(L),
    )


def _transform(u: Updatable, value: float) -> float:
    return math.log(value) if u.log else value


def _inverse(u: Updatable, theta: float) -> float:
    return math.exp(theta) if u.log else theta


def matrix_derivatives(specimen, params, *, step: float = 1e-4) -> list:
    """``[(dK, dM, dS, dE), ...]``: the stuck stiffness's, the mass's and the sensor and
    excitation rows' derivatives by each parameter's transformed value (``ln p``, or ``p``
    for a range from 0), by central differences of the assembled system (one-sided where a
    step would leave the range: a mass at 0); module docstring. The rows move only with a
    position (the shaker's attachment, where the force acts). ``params``: Updatable rows.
    """
    out = []
    for u in params:
        th = _transform(u, u.nominal)
        h = step if u.log else step * max(u.upper - u.lower, 1e-30)
        hi, lo = th + h, (th - h if u.log or u.nominal - h >= u.lower else th)
        mats = [_matrices(with_parameters(specimen, {u.name: _inverse(u, x)})) for x in (hi, lo)]
        d = [
            (a - b) / (hi - lo)
            for a, b in zip(
                (mats[0][0], mats[0][1], mats[0][2].S, _excitation(mats[0][2])),
                (mats[1][0], mats[1][1], mats[1][2].S, _excitation(mats[1][2])),
            )
        ]
        out.append(tuple(d))
    return out


def modal_sensitivities(specimen, modes, params, *, positions=(), state=None) -> dict:
    """Frequencies, shapes at sensors and modal constants of ``modes`` with their
    derivatives by every parameter's transformed value (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    modes : dict
        ``{target mode: column}`` of the modal state (which model mode answers each target).
    params : sequence of Updatable
    positions : sequence of float, keyword-only
        Sensor positions [m] along the axis where the shapes are read.
    state : ModalState, optional, keyword-only
        The specimen's (computed if not given).

    Returns
    -------
    dict
        ``f`` {mode: Hz}, ``df`` {mode: (n_params,)}, ``shape`` {mode: (n_pos,)},
        ``dshape`` {mode: (n_pos, n_params)}, ``c`` {mode: 1/kg}, ``dc`` {mode: (n_params,)},
        ``state``.
    """
    st = modal_state(specimen) if state is None else state
    D = matrix_derivatives(specimen, params)
    R = axis_rows(specimen, list(positions)) if len(positions) else np.zeros((0, st.M.shape[0]))
    out: dict[str, Any] = {k: {} for k in ("f", "df", "shape", "dshape", "c", "dc")}
    for r, k in modes.items():
        lam, p = st.lam[k], st.phi[:, k]
        f = math.sqrt(abs(lam)) / (2 * math.pi)
        gap = lam - st.lam
        gap[k] = np.inf
        dl, dphi = np.zeros(len(params)), np.zeros((p.size, len(params)))
        for j, (dK, dM, _, _) in enumerate(D):
            A = dK - lam * dM
            dl[j] = p @ A @ p
            coef = (st.phi.T @ (A @ p)) / gap
            dphi[:, j] = st.phi @ coef - 0.5 * (p @ dM @ p) * p
        out["f"][r] = f
        out["df"][r] = dl / (8 * math.pi**2 * f)
        out["shape"][r] = R @ p
        out["dshape"][r] = R @ dphi
        se, ee = float(st.S @ p), float(st.E @ p)
        out["c"][r] = se * ee
        dS = np.array([d[2] @ p for d in D])
        dE = np.array([d[3] @ p for d in D])
        out["dc"][r] = (st.S @ dphi + dS) * ee + se * (st.E @ dphi + dE)
    out["state"] = st
    return out


def pair_modes(state: ModalState, reference: ModalState, modes) -> dict:
    """``{mode: column}``: each numbered elastic ``mode`` of ``reference`` followed into
    ``state`` by the largest mass-weighted MAC (modes may change order as parameters move).
    """
    out = {}
    cross = np.abs(reference.phi.T @ (state.M @ state.phi))
    for r in modes:
        k_ref = reference.index(r)
        out[r] = int(np.argmax(cross[k_ref]))
    return out
