"""Transient ring-down of a lap-jointed specimen in Exudyn: the independent route to f(X), zeta(X).

The specimen is held in the static deflection that the modal load ``alpha M phi`` produces
(the joints loaded along their virgin curves, so the Iwan elements start virgin at those
slips) and released from rest at ``t = 0``. Several modes may be released at once: the
release state is then the sum of each mode's static deflection, each reaching its own
amplitude at the sensor, and the Iwan elements start virgin at the summed slips. Exudyn
integrates the specimen's linear bodies (1-D Timoshenko beams or reduced solid bodies, one
generic body: :mod:`~iwan_element.models.simulation.host`) with the history-dependent Iwan element
of every contact point (generalized-alpha with spectral radius 1, i.e. the trapezoidal rule: no
numerical damping), all modes through the same interface. A hammer impact instead of a
release is a force pulse on the struck point's port coordinate. Each mode's response is
separated by modal filtering, ``q_r(t) = phi_r^T M x(t)``, and expressed at the sensor
(``X_r = (S phi_r) q_r``); frequency and damping against amplitude follow from the
package's free-decay route, :func:`iwan_element.amplitude_curve` (band-pass ``(0.5, 1.5)``
times the mode's stuck frequency, Hilbert envelope and phase, straight-line fits in windows
of ``n_periods``; ``docs/free_decay.md``), the same route a measured ring-down takes. The
trapezoidal rule lengthens the period by a known amount (``w_num h / 2 = arctan(w h / 2)``);
the frequencies are corrected for it (``docs/beam_tests.md``). The time step is set by the
highest mode released.

The specimen's damping floor, one ratio per mode (``Specimen.floor``), is the modal damping
matrix of the stuck system (:mod:`~iwan_element.models.reduced.damping`); its work is booked
exactly. The specimen's vibration effects on a released mode act as a modal force
(:mod:`~iwan_element.models.simulation.modal_force`). ``docs/multi_mode.md`` describes the
multi-mode run and the coupling of the modes through the interface.
"""

from __future__ import annotations

import exudyn as exu
import numpy as np

from iwan_element.base.stages import stop_at
from iwan_element.base.validation import check_int, check_scalar

from ..modal.interface import interface_laws
from ..modal.qsma import linear_modes, static_modal_load
from ..reduced.damping import FloorWork
from ..reduced.dispatch import axis_rows, check_specimen
from ..solid.specimen import SolidSpecimen
from ..specimens.specimen import Specimen
from .host import build_host
from .impact import Impact
from .modal_force import ModalEffects
from .newton import check_newton, choose_newton
from .ringdown_records import (
    Recorder,
    build_result,
    check_run_length,
    joint_records,
    solve_timed,
    virgin_joint_energy,
)
from .ringdown_result import RingdownResult, with_energy_warning
from .solver import MAX_STEPS, solver_settings

__all__ = ["RingdownResult", "ringdown", "check_solid_release", "release_state", "preflight"]

#: Smallest share of a mode's largest z displacement along the axis that the sensor must see
#: for a solid's release amplitude to be set there.
SENSOR_SHARE = 0.05


def _amplitudes(mode, amplitude) -> dict:
    """``{mode: amplitude}`` (ascending modes) from a float with ``mode`` or a dict."""
    if isinstance(amplitude, dict):
        if mode is not None:
            raise ValueError(
                "mode must not be given with a dict amplitude (its keys are the modes)"
            )
        amp = dict(amplitude)
    else:
        amp = {1 if mode is None else mode: amplitude}
    if not amp:
        raise ValueError("amplitude must name at least one mode")
    # the package's scalar checks: numpy integers and floats count as numbers
    checked = {
        check_int("mode (1: first elastic mode)", r, 1): check_scalar(
            f"amplitude of mode {r} [m]", X, low=0.0, low_open=True
        )
        for r, X in amp.items()
    }
    return dict(sorted(checked.items()))


def _check_args(specimen, steps_per_period, n_periods, cycles, duration):
    """Checks of :func:`ringdown`'s other arguments: ``(n_periods, cycles, duration)``."""
    check_specimen(specimen)
    check_int("steps_per_period", steps_per_period, 16)
    n_periods = check_scalar("n_periods", n_periods, low=3.0, high=1000.0)
    if cycles is not None and duration is not None:
        raise ValueError("give cycles or duration, not both")
    if duration is not None:
        return n_periods, None, check_scalar("duration", duration, low=0.0, low_open=True)
    # the least cycles the curves need is checked with the run's length (check_run_length)
    return (
        n_periods,
        check_scalar("cycles", 30.0 if cycles is None else cycles, low=0.0, low_open=True),
        None,
    )


def release_state(specimen: Specimen | SolidSpecimen, amp: dict) -> dict:
    """The release state: the sum of each mode's static deflection under ``alpha_r M phi_r``
    reaching its amplitude at the sensor (:func:`static_modal_load`), and the modes.

    A static solve that did not converge is the release stage's failure: the run stops
    here (:class:`~iwan_element.base.stages.StageFailed`, naming the mode's amplitude),
    before any time step.
    """
    sts = [static_modal_load(specimen, [X], mode=r) for r, X in amp.items()]
    lo, hi = specimen.amplitude_range
    stop_at(
        "release",
        [
            f"amplitude of mode {r} = {X:.4g} m: {w}, so the state to release from is not "
            f"known; give a smaller amplitude (the specimen's amplitude_range is "
            f"{lo:.3g}-{hi:.3g} m)"
            for (r, X), st in zip(amp.items(), sts)
            for w in st["warnings"]
        ],
    )
    return {
        "x": sum(st["x"][0] for st in sts),
        "slip": sum(st["slip"][0] for st in sts),
        "system": sts[0]["system"],
        "phi": [st["phi"] for st in sts],
        "omega0": np.array([st["omega0"] for st in sts]),
    }


def _start(specimen: Specimen | SolidSpecimen, mode, amplitude, impact, modes):
    """``(amp, state)``: ``{mode: release amplitude or None}`` and the start state (the
    release of :func:`release_state`, or rest for an impact, with the stuck modes of ``modes``).
    """
    if (amplitude is None) == (impact is None):
        raise ValueError("give amplitude (a release) or impact (a force pulse), one of them")
    if impact is None:
        if modes is not None:
            raise ValueError("modes is for an impact; a release names its modes in amplitude")
        amp = _amplitudes(mode, amplitude)
        return amp, release_state(specimen, amp)
    if not isinstance(impact, Impact):
        raise ValueError(f"impact must be an Impact, got {type(impact).__name__}")
    if mode is not None:
        raise ValueError("mode is for a release; give an impact's modes as modes=(1, 2, ...)")
    if impact.position > specimen.total_length:
        raise ValueError(
            f"impact position must lie on the assembly (<= "
            f"{specimen.total_length:.6g} m), got {impact.position!r}"
        )
    ms = (1,) if modes is None else tuple(modes)
    amp = _amplitudes(None, dict.fromkeys(ms, 1.0))  # checks the modes
    lm = [linear_modes(specimen, mode=r) for r in amp]
    L = lm[0][3]
    return dict.fromkeys(amp), {
        "x": np.zeros(L.M.shape[0]),
        "slip": np.zeros(L.G.shape[0]),
        "system": L,
        "phi": [m[1] for m in lm],
        "omega0": np.array([m[0] for m in lm]),
    }


def _initial_energy(model, rel, effs, tangential) -> tuple:
    """``(kinetic, total)`` energy [J] at the release: the bodies' strain energy, the
    springs', the joint's (the virgin backbone work at the initial slips) and the
    effects'.
    """
    kin0, pot0 = model.beam_energy()
    e0 = pot0 + model.spring_energy()
    laws = interface_laws(model.specimen)
    if tangential == "iwan" and laws is not None:  # each point's stack loaded from rest
        for el, u in zip(laws.elements(model.points.params), rel["slip"]):
            el.trial(float(u))
            el.commit()
            e0 += el.work
    elif tangential == "iwan":
        e0 += virgin_joint_energy(rel["slip"], model.points.params)
    for eff in effs:
        e0 += eff.start(eff.s * float(eff.a_free @ rel["x"]))
    return kin0, e0


def check_solid_release(specimen: SolidSpecimen, modes) -> None:
    """Refuse a solid's release in a mode the sensor barely sees (its release amplitude at
    the sensor could not set it).
    """
    if specimen.model.axis is None:
        raise ValueError(
            "specimen.model holds no axis rows (SolidModel.axis): build the solid "
            "with models.solid.solid_specimen"
        )
    for r in modes:
        _, phi, _, L, _ = linear_modes(specimen, mode=r)
        along = np.max(np.abs(axis_rows(specimen, specimen.model.axis[0]) @ phi))
        share = abs(float(L.S @ phi)) / along
        if share < SENSOR_SHARE:
            raise ValueError(
                f"mode {r} moves the sensor's z displacement by {share:.1e} of its largest "
                "z displacement along the axis (an in-plane or torsion mode): its release "
                "amplitude at the sensor cannot set it. The solid numbers its stuck modes "
                "as natural_frequencies does (the Brake-Reuss solid: 1 first height bending, "
                "2 in-plane bending, 3 second height bending); release height-bending modes"
            )


def ringdown(
    specimen: Specimen | SolidSpecimen,
    *,
    mode: int | None = None,
    amplitude=None,
    impact: Impact | None = None,
    modes=None,
    sensors=None,
    duration: float | None = None,
    cycles: float | None = None,
    steps_per_period: int = 64,
    n_periods: float = 3.0,
    record_energy: bool = False,
    joint_elements: bool = False,
    progress: bool = False,
    tangential: str = "iwan",
    newton: str = "auto",
    max_steps: int = MAX_STEPS,
) -> RingdownResult:
    """Release the specimen from a static deflection in one or several modes' load shapes,
    or strike it (``impact``); let it ring down through the interface.

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
        A 1-D specimen (Timoshenko beams) or a solid one (its reduced bodies), in Exudyn as
        one generic body (:mod:`~iwan_element.models.simulation.host`); a solid's modes are
        numbered as its stuck modes (a released mode must move the sensor's z displacement).
    mode : int, optional, keyword-only
        Elastic mode number (1: lowest) of a single-mode release (default 1); not with a
        dict ``amplitude``.
    amplitude : float or dict, keyword-only
        Initial displacement amplitude at the sensor point [m] (> 0) of ``mode``, or
        ``{mode: amplitude}`` to release several modes at once: the sum of the modes'
        static deflections, each reaching its amplitude at ``specimen.sensor_position``.
    impact : Impact, optional, keyword-only
        Instead of a release: the specimen at rest struck by a half-sine force pulse
        (:class:`~iwan_element.models.simulation.Impact`); the step also resolves the pulse
        (at most a sixteenth of its contact time).
    modes : sequence of int, optional, keyword-only
        The modes an impact's result separates (modal filter, curves; default ``(1,)``).
    sensors : sequence of float, optional, keyword-only
        Positions [m] along the beams' axis (the axis of ``sensor_position``) where the
        displacement and acceleration are recorded (default: ``sensor_position``).
    duration : float, optional, keyword-only
        Duration [s]; or give ``cycles``. At least ``max(6, n_periods + 3)`` periods of the
        lowest mode (0.09 s for the example beam's first mode at the default ``n_periods``),
        refused before any step otherwise (:func:`~.ringdown_records.min_cycles`: the
        decay reader trims about 1.5 periods of filter end effects at each end, needs one
        window of ``n_periods`` between them and 6 periods to find the mode in its band).
        A curve of ``k`` points takes about ``3 + k n_periods`` periods.
    cycles : float, optional, keyword-only
        Duration in periods of the lowest mode's stuck frequency (default 30 when
        ``duration`` is not given), at least ``max(6, n_periods + 3)`` (6 at the default
        ``n_periods``; as ``duration``).
    steps_per_period : int, keyword-only
        Time steps per period of the highest released mode (>= 16).
    n_periods : float, keyword-only
        Periods per frequency/damping window of :func:`iwan_element.amplitude_curve`
        (range [3, 1000]; default 3, the most points a short record gives).
    record_energy : bool, keyword-only
        Record the energy terms every step (slower).
    joint_elements : bool, keyword-only
        Use one Python ``IwanJoint`` connector per point (reference route) instead of the
        compiled interface law.
    progress : bool, keyword-only
        Show a tqdm bar over the time steps with its ETA; needs tqdm.
    tangential : {"iwan", "linear"}, keyword-only
        The contact points' tangential law: the Iwan elements (default), or linear springs
        at their stuck stiffness ``KT_i`` (the same bodies with the stuck interface: the
        linear reference of cost and decay; the release state is still the Iwan one).
    newton : {"auto", "condensed", "exudyn"}, keyword-only
        How each time step's equations are solved: ``"condensed"`` on the joints' slips with
        their consistent tangents (:mod:`~iwan_element.models.simulation.newton`; a step
        costs 1.3-2.0 times a step with linear springs on the 1-D beams), ``"exudyn"`` by
        Exudyn's modified Newton on the whole model (the reference route), ``"auto"``
        (default) condensed where it can serve and pays
        (:func:`~iwan_element.models.simulation.newton.choose_newton`).
    max_steps : int, keyword-only
        Most time steps the run may take (default
        :data:`~iwan_element.models.simulation.solver.MAX_STEPS`, 200,000: about 1.2 GB of
        records on the 253-coordinate two-bolt beam and 3-7 minutes; the longest run the
        project documents takes 30,720). A longer run is refused before it starts with its
        estimated steps, wall time (2 ms a step, the most measured) and memory.

    Returns
    -------
    RingdownResult
        One decay curve per released mode (``curves``; ``curve`` is the lowest's), the
        sensors' records and the energy balance.

    Raises
    ------
    ValueError
        An argument out of its range (named), a run too short for its curves or longer than
        ``max_steps``; :class:`~iwan_element.base.stages.StageFailed` (a ValueError) when
        the release's static solve does not converge (the amplitude named): no time step
        is taken.

    Notes
    -----
    Newton (either route; relative tolerance 1e-10) stops when Exudyn's residual norm falls
    below ``1e-7 F`` [N], ``F = max |K0 x0|`` the largest elastic force of the release state
    (or an impact's peak force): it scales with the amplitude. The host's coordinates are
    displacements, so the residual's round-off stays far below that at any amplitude. No
    discontinuous iteration is involved (one per step, Exudyn's default): the compiled law is
    an explicit function of the slip given the committed state, which changes only in the
    post-step of an accepted step.
    """
    n_periods, cycles, duration = _check_args(
        specimen, steps_per_period, n_periods, cycles, duration
    )
    if tangential not in ("iwan", "linear"):
        raise ValueError(f"tangential must be 'iwan' or 'linear', got {tangential!r}")
    check_newton(newton)
    if isinstance(specimen, SolidSpecimen):
        check_solid_release(specimen, () if amplitude is None else _amplitudes(mode, amplitude))
    amp, rel = _start(specimen, mode, amplitude, impact, modes)
    h, n = check_run_length(
        rel["omega0"],
        steps_per_period,
        n_periods=n_periods,
        duration=duration,
        cycles=cycles,
        impact=impact,
        n_coordinates=rel["system"].M.shape[0],
        max_steps=max_steps,
    )
    positions = np.atleast_1d(
        np.asarray(specimen.sensor_position if sensors is None else sensors, float)
    )
    rows = axis_rows(specimen, positions)
    opts = {
        "n_periods": n_periods,
        "steps_per_period": steps_per_period,
        "grid": (h, n),
        "record_energy": record_energy,
        "joint_elements": joint_elements,
        "progress": progress,
        "tangential": tangential,
        "newton": newton,
    }
    return _run(specimen, amp, rel, rows, positions, opts, impact)


def preflight(
    specimen: Specimen | SolidSpecimen,
    amplitude: dict,
    *,
    duration: float,
    steps_per_period: int,
    n_periods: float,
    max_steps: int = MAX_STEPS,
) -> int:
    """The time steps of :func:`ringdown`'s release of ``amplitude`` ({mode: X [m]}) over
    ``duration`` [s], once its release converged and its length passed the checks of
    :func:`ringdown` (the same errors); nothing is simulated. A route that runs several
    ring-downs checks them all first.
    """
    n_periods, _, duration = _check_args(specimen, steps_per_period, n_periods, None, duration)
    rel = release_state(specimen, _amplitudes(None, amplitude))
    return check_run_length(
        rel["omega0"],
        steps_per_period,
        n_periods=n_periods,
        duration=duration,
        cycles=None,
        impact=None,
        n_coordinates=rel["system"].M.shape[0],
        max_steps=max_steps,
    )[1]


def _run(specimen, amp, rel, rows, positions, opts, impact):
    """The ring-down in Exudyn (:mod:`~iwan_element.models.simulation.host`: bodies, contact points,
    floor, effects, impact) from the release ``rel`` of the modes ``amp``: :func:`ringdown`'s
    work after the checks (``opts``: its keyword options).
    """
    tangential, record_energy = opts["tangential"], opts["record_energy"]
    L, w0 = rel["system"], rel["omega0"]
    effs = [
        ModalEffects(specimen, r, L, phi, w)
        for r, phi, w in zip(amp, rel["phi"], w0)
        if any(e.mode == r for e in specimen.effects)
    ]
    fw = FloorWork(None)
    rec = Recorder(effs, fw, record_energy)
    ports = {"impact": axis_rows(specimen, [impact.position])[0]} if impact is not None else None
    model = build_host(
        specimen,
        tangential=tangential,
        post_step=rec,
        ports=ports,
        joint_elements=opts["joint_elements"],
        assemble=False,
    )
    fw.C = model.floor_C
    rec.model = model
    for eff in effs:
        eff.attach(model)
    if impact is not None:
        model.add_port_force("impact", impact.force)
        rec.impact = (impact, np.eye(model.T.shape[1])[model.ports["impact"]])
    model.mbs.Assemble()
    model.set_state(rel["x"])
    kin0, e0 = _initial_energy(model, rel, effs, tangential)
    h, n = opts["grid"]
    z0 = model.T_inv @ rel["x"]
    sim = solver_settings(
        force_scale=max(
            float(np.max(np.abs((model.Kb + model.Ks) @ z0))),
            0.0 if impact is None else abs(impact.peak_force),
        )
    )
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    step = choose_newton(model, sim, opts["newton"], other_forces=bool(effs))
    solve = solve_timed(model.mbs, sim, rec, n, opts["progress"], newton=step)
    quad = joint_records(model.interface, rec.energy, e0 + rec.work_in) if record_energy else None
    X = model.to_free(np.array(rec.coords))
    return with_energy_warning(
        build_result(
            specimen,
            amp,
            rec,
            X,
            rel,
            rows,
            positions,
            h,
            n,
            {
                "n_periods": opts["n_periods"],
                "steps_per_period": opts["steps_per_period"],
                "solve": solve,
                "e0": e0,
                "kin0": kin0,
                "quad": quad,
                "n_points": len(model.points),
                "overflow": len(getattr(model.interface, "overflow_times", ())),
                "effects": tuple(nm for eff in effs for nm in eff.names),
                "impact": impact,
                "extra": {"tangential": tangential, "n_coordinates": int(model.T.shape[1])},
            },
        )
    )
