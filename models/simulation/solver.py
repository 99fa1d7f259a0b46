"""Exudyn solver settings shared by the specimen's time and load-step runs.

:func:`solver_settings` is used by the ring-down
(:mod:`~iwan_element.models.simulation.transient`), the machine test
(:mod:`~iwan_element.models.simulation.machine`) and the stepped sine
(:mod:`~iwan_element.models.simulation.forced`). The damping floor is in
:mod:`~iwan_element.models.reduced.damping`.
"""

from __future__ import annotations

import exudyn as exu

__all__ = ["solver_settings"]


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
