"""Shared solver settings and option checks of the jointed-beam scenarios."""
from __future__ import annotations

import exudyn as exu
import numpy as np

from .jointed_beam import JointedBeamConfig


def _check_count(name: str, value, low: int) -> int:
    """An integer option ``>= low`` (bools and fractional values are rejected)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


def _check_positive(name: str, values) -> np.ndarray:
    """A non-empty 1-D array of finite values > 0."""
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name} must be a non-empty sequence of finite values > 0, got {values!r}")
    return arr


def _settings(*, force_scale: float, static: bool = False) -> exu.SimulationSettings:
    """Solver settings: no files, one thread, Newton tolerances in force units.

    ``force_scale`` [N] is the size of the forces the run is about (the machine force in the
    quasi-static test, the elastic forces of the beams in vibration); Newton's absolute
    tolerance is 1e-7 of it for time integration and 1e-6 for the static solver (which failed
    to converge at 1e-7 on this model). Exudyn's default (1e-10 N) cannot be met near round-off with the
    stiff contact springs, and a tolerance tied to the joint's slip force would be far too
    loose for vibration, whose forces are newtons.
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


def _bending_force_scale(cfg: JointedBeamConfig, tip: float) -> float:
    """Static tip force of a cantilever of the assembly's length deflected by ``tip`` [N]."""
    return 3.0 * cfg.EI * tip / cfg.total_length ** 3
