"""Exudyn solver settings shared by the specimen's time and load-step runs.

:func:`solver_settings` is used by the ring-down
(:mod:`~iwan_element.models.simulation.transient`), the machine test
(:mod:`~iwan_element.models.simulation.machine`) and the stepped sine
(:mod:`~iwan_element.models.simulation.forced`). The damping floor is in
:mod:`~iwan_element.models.reduced.damping`. :func:`check_steps` is the cost of a time run
checked before it starts.
"""

from __future__ import annotations

import exudyn as exu

from iwan_element.base.validation import check_int

__all__ = ["solver_settings", "check_steps", "MAX_STEPS", "SECONDS_PER_STEP"]

#: Most time steps a run takes unless its caller raises ``max_steps``. A run keeps every
#: step's coordinates three times over (the records, their array, the free coordinates):
#: ``24 n`` bytes a step on ``n`` coordinates, 1.2 GB at 200,000 steps of the 253-coordinate
#: two-bolt beam, and 3-7 minutes at the 1-2 ms a step measured (``docs/transient_cost.md``).
#: The longest run the project documents takes 30,720 steps (``examples/brb_every_mode.py``,
#: 1.2 s of modes 1 and 2 at 64 steps a period of mode 2).
MAX_STEPS = 200_000

#: Wall time a step is estimated at [s]: the most measured on the presets, 1.6 ms a step
#: (``docs/transient_cost.md``, the Brake-Reuss beam's two-mode release), rounded up.
SECONDS_PER_STEP = 2e-3


def check_steps(n: int, *, n_coordinates: int | None, max_steps, what: str, shorten: str) -> int:
    """``n`` when a run of ``n`` time steps is within ``max_steps`` (an integer >= 1;
    ValueError naming it otherwise); else a ValueError that states the run's estimated wall
    time (:data:`SECONDS_PER_STEP`) and, for a run that records its ``n_coordinates``
    coordinates every step (None: it records less), its memory (``24`` bytes per coordinate
    and step, :data:`MAX_STEPS`), and what to change (``shorten``: the arguments that set its
    length).
    """
    cap = check_int("max_steps", max_steps, 1)
    if n > cap:
        wall = n * SECONDS_PER_STEP
        mem = (
            f", and about {24.0 * n_coordinates * n / 1e9:.3g} GB of records on "
            f"{n_coordinates} coordinates"
            if n_coordinates is not None
            else ""
        )
        raise ValueError(
            f"{what} would take {n:.3g} time steps (up to {wall:.3g} s = {wall / 3600:.3g} h "
            f"at {SECONDS_PER_STEP * 1e3:g} ms a step{mem}), more than max_steps = {cap}: "
            f"{shorten}, or raise max_steps if you mean it"
        )
    return n


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
