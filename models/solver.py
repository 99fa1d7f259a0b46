"""Exudyn solver settings shared by the specimen's time and load-step runs.

:func:`solver_settings` is used by the ring-down (:mod:`~iwan_element.models.transient`), the
machine test (:mod:`~iwan_element.models.machine`) and the stepped sine
(:mod:`~iwan_element.models.forced`); :func:`roundoff_force` is the model's round-off level
that Newton's tolerance must not go below. The damping floor is in
:mod:`~iwan_element.models.damping`.
"""
from __future__ import annotations

import math

import exudyn as exu
import numpy as np

from .specimens import Specimen

__all__ = ["solver_settings", "roundoff_force"]


def solver_settings(*, force_scale: float, static: bool = False) -> exu.SimulationSettings:
    """Solver settings: no files, one thread, Newton tolerances in force units.

    Parameters
    ----------
    force_scale : float, keyword-only
        Size of the forces the run is about [N] (the machine force in the quasi-static test,
        the elastic forces of the beams in vibration). Newton's absolute tolerance is 1e-7
        of it for time integration and 1e-6 for the static solver. Exudyn's default
        (1e-10 N) cannot be met near round-off with the stiff contact springs, and a
        tolerance tied to a contact point's slip force would be far too loose for
        vibration, whose forces are newtons.
    static : bool, keyword-only
        Settings of ``SolveStatic`` (load steps) instead of ``SolveDynamic``
        (generalized-alpha at spectral radius 1, i.e. the trapezoidal rule, with modified
        Newton).

    Returns
    -------
    exudyn.SimulationSettings
    """
    sim = exu.SimulationSettings()
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    newton = sim.staticSolver.newton if static else sim.timeIntegration.newton
    newton.absoluteTolerance = (1e-6 if static else 1e-7) * force_scale
    newton.relativeTolerance = 1e-10
    newton.maxIterations = 50
    if static:
        sim.staticSolver.verboseMode = 0
    else:
        sim.timeIntegration.verboseMode = 0
        sim.timeIntegration.generalizedAlpha.spectralRadius = 1.0
        sim.timeIntegration.newton.useModifiedNewton = True
    return sim


def roundoff_force(L, specimen: Specimen) -> float:
    """Round-off level [N] of the residual norm of the specimen model (amplitude-independent).

    Exudyn forms the elastic forces from absolute nodal positions (up to the specimen's span
    ``2 L_beam - overlap`` from the origin), so each force carries a round-off of about
    ``eps k_max span`` with ``k_max`` the largest diagonal entry of ``K0`` (the axial
    stiffness of a beam element or a normal contact spring); the residual norm over the
    ``n`` coordinates is bounded by ``sqrt(n)`` times that. Measured on the Brake-Reuss model:
    the Newton residual stalls at 1e-6 to 2.5e-6 N whatever the amplitude, time step, normal
    stiffness or slip; this bound gives 1.4e-5 N.
    """
    K = L.K0.toarray() if hasattr(L.K0, "toarray") else np.asarray(L.K0)
    span = 2.0 * specimen.beam_length - specimen.overlap
    return float(np.finfo(float).eps * np.max(np.abs(np.diag(K))) * span * math.sqrt(K.shape[0]))
