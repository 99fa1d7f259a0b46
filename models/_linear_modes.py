"""Linearised modes of the jointed beam and the closed-form amplitude prediction
(see :mod:`.scenarios`)."""
from __future__ import annotations

import math
from dataclasses import dataclass

import exudyn as exu
import numpy as np

from iwan_element import dissipation, secant_stiffness

from ._scenario_settings import _settings
from .jointed_beam import JointedBeamConfig, JointedBeamModel, build_jointed_beam

__all__ = ["ModalResult", "modal_analysis"]


@dataclass
class ModalResult:
    """Linearised modes of the assembly (joint at ``KT``) and the closed-form prediction.

    Attributes
    ----------
    frequencies : ndarray, shape (n_modes,)
        [Hz].
    shapes : ndarray, shape (n_coordinates, n_modes)
        Mass-normalised mode shapes (Exudyn ODE2 coordinates).
    tip : ndarray, shape (n_modes,)
        Transverse tip displacement per unit modal coordinate [m].
    slip_per_q : ndarray, shape (n_points, n_modes)
        Joint slip at each contact point per unit modal coordinate [m].
    mass_matrix : ndarray, shape (n_coordinates, n_coordinates)
        Exudyn's ODE2 mass matrix (for modal filtering, ``q = shapes.T @ M @ x``).
    config : JointedBeamConfig
    """

    frequencies: np.ndarray
    shapes: np.ndarray
    tip: np.ndarray
    slip_per_q: np.ndarray
    mass_matrix: np.ndarray
    config: JointedBeamConfig

    def modal_coordinates(self, x, *, mode: int = 0) -> np.ndarray:
        """Modal coordinate history ``q(t) = phi^T M x(t)`` of a mode [sqrt(kg) m]; ``x`` has
        shape (n_times, n_coordinates). Exact modal filtering for the linearised system."""
        return np.asarray(x) @ (self.mass_matrix @ self.shapes[:, mode])

    def predict(self, tip_amplitude, *, mode: int = 0):
        """Amplitude-dependent frequency [Hz] and damping ratio [-] of a mode from the joint's
        closed forms, at tip amplitudes [m] (array_like).

        Returns
        -------
        frequency, damping : ndarray
        """
        A = np.atleast_1d(np.asarray(tip_amplitude, dtype=float))
        q = A / abs(self.tip[mode])
        w_lin2 = (2.0 * math.pi * self.frequencies[mode]) ** 2
        pj = self.config.point_joint
        w2 = np.full_like(q, w_lin2)
        D = np.zeros_like(q)
        for g in self.slip_per_q[:, mode]:
            s = abs(g) * q
            w2 -= g * g * (pj.KT - secant_stiffness(s, pj))
            D += dissipation(s, pj)
        zeta = D / (2.0 * math.pi * w2 * q * q)
        return np.sqrt(w2) / (2.0 * math.pi), zeta


def _linear_model(cfg: JointedBeamConfig) -> JointedBeamModel:
    return build_jointed_beam(cfg.replace(joint_model="linear" if cfg.joint_model == "iwan"
                                          else cfg.joint_model, boundary="clamped-free"))


def modal_analysis(config: JointedBeamConfig | None = None, *, n_modes: int = 3) -> ModalResult:
    """Linearised modes of the clamped-free assembly with the joint at ``KT`` (or rigid).

    Exudyn 1.13.6 returns no eigenvectors for ``numberOfEigenvalues=0`` together with
    ``constrainedCoordinates``; the number of modes is therefore always given explicitly.
    """
    cfg = config or JointedBeamConfig()
    model = _linear_model(cfg)
    mbs = model.mbs
    w2, shapes = mbs.ComputeODE2Eigenvalues(constrainedCoordinates=model.clamped_coordinates,
                                             ignoreAlgebraicEquations=True,
                                             numberOfEigenvalues=int(n_modes))
    shapes = np.array(shapes)
    tip = shapes[model.tip_index(1), :]
    solver = exu.MainSolverStatic()
    quiet = _settings(force_scale=1.0, static=True)          # no solution file
    solver.InitializeSolver(mbs, quiet)
    solver.ComputeMassMatrix(mbs)
    mass = np.array(solver.GetSystemMassMatrix())
    scale = 1e-6                                      # evaluate the slip in the linear range
    slips = []
    for k in range(shapes.shape[1]):
        mbs.systemData.SetODE2Coordinates(scale * shapes[:, k], configuration=exu.ConfigurationType.Current)
        slips.append(model.interface_slips() / scale)
    return ModalResult(frequencies=np.sqrt(np.abs(w2)) / (2 * math.pi), shapes=shapes, tip=tip,
                       slip_per_q=np.array(slips).T, mass_matrix=mass, config=cfg)
