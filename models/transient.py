"""Transient ring-down of a lap-jointed specimen in Exudyn: the independent route to f(X), zeta(X).

The specimen is held in the static deflection that the modal load ``alpha M phi`` produces
(the joints loaded along their virgin curves, so the Iwan elements start virgin at those
slips) and released from rest at ``t = 0``. Several modes may be released at once: the
release state is then the sum of each mode's static deflection, each reaching its own
amplitude at the sensor, and the Iwan elements start virgin at the summed slips. Exudyn
integrates the geometrically nonlinear Cable2D beams with the history-dependent Iwan element
of every contact point (generalized-alpha with spectral radius 1, i.e. the trapezoidal rule:
no numerical damping), all modes through the same interface. Each mode's response is
separated by modal filtering, ``q_r(t) = phi_r^T M x(t)``, and expressed at the sensor
(``X_r = (S phi_r) q_r``); frequency and damping against amplitude follow from the
package's free-decay route, :func:`iwan_element.amplitude_curve` (band-pass ``(0.5, 1.5)``
times the mode's stuck frequency, Hilbert envelope and phase, straight-line fits in windows
of ``n_periods``; ``docs/free_decay.md``), the same route a measured ring-down takes. The
trapezoidal rule lengthens the period by a known amount (``w_num h / 2 = arctan(w h / 2)``);
the frequencies are corrected for it (``docs/beam_tests.md``). The time step is set by the
highest mode released.

The specimen's damping floor, one ratio per mode (``Specimen.floor``), is the modal damping
matrix of the stuck system (:mod:`~iwan_element.models.damping`); its work is booked exactly.
The specimen's vibration effects on a released mode act as a modal force
(:mod:`~iwan_element.models.modal_effects`). ``docs/multi_mode.md`` describes the
multi-mode run and the coupling of the modes through the interface.
"""
from __future__ import annotations

import math
import time

import exudyn as exu
import numpy as np
from exudyn.itemInterface import LoadForceVector

from iwan_element import backbone_work
from iwan_element.core.progress import finish, progress_bar, tick
from iwan_element.core.validation import check_scalar

from .assembly import axis_rows, build_specimen_model
from .damping import FloorWork, attach_floor_damping, floor_damping
from .impact import Impact
from .modal_effects import ModalEffects
from .qsma import linear_modes, static_modal_load
from .ringdown_result import RingdownResult, decay_curve, with_energy_warning
from .solver import roundoff_force, solver_settings
from .specimens import Specimen

__all__ = ["RingdownResult", "ringdown"]

_E_KEYS = ("t", "kinetic", "strain", "springs", "joint_stored", "joint_dissipated",
           "floor_dissipated", "effect_stored", "effect_dissipated", "input_work")


def _amplitudes(mode, amplitude) -> dict:
    """``{mode: amplitude}`` (ascending modes) from a float with ``mode`` or a dict."""
    if isinstance(amplitude, dict):
        if mode is not None:
            raise ValueError("mode must not be given with a dict amplitude (its keys are the "
                             "modes)")
        amp = dict(amplitude)
    else:
        amp = {1 if mode is None else mode: amplitude}
    if not amp:
        raise ValueError("amplitude must name at least one mode")
    for r, X in amp.items():
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r < 1:
            raise ValueError(f"mode must be an integer >= 1 (1: first elastic mode), got {r!r}")
        if isinstance(X, bool) or not (isinstance(X, (int, float)) and math.isfinite(X)
                                       and X > 0):
            raise ValueError(f"amplitude must be a finite displacement > 0 [m] for each mode, "
                             f"got {X!r} for mode {r}")
    return {int(r): float(amp[r]) for r in sorted(amp)}


def _check_args(specimen, steps_per_period, n_periods, cycles, duration):
    """Checks of :func:`ringdown`'s other arguments: ``(n_periods, cycles, duration)``."""
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    if isinstance(steps_per_period, bool) or not isinstance(steps_per_period, int) \
            or steps_per_period < 16:
        raise ValueError(f"steps_per_period must be an integer >= 16, got {steps_per_period!r}")
    n_periods = check_scalar("n_periods", n_periods, low=3.0, high=1000.0)
    if cycles is not None and duration is not None:
        raise ValueError("give cycles or duration, not both")
    if duration is not None:
        return n_periods, None, check_scalar("duration", duration, low=0.0, low_open=True)
    return n_periods, check_scalar("cycles", 30.0 if cycles is None else cycles, low=2.0,
                                   low_open=True), None


def _release(specimen: Specimen, amp: dict) -> dict:
    """The release state: the sum of each mode's static deflection under ``alpha_r M phi_r``
    reaching its amplitude at the sensor (:func:`static_modal_load`), and the modes."""
    sts = [static_modal_load(specimen, [X], mode=r) for r, X in amp.items()]
    return {"x": sum(st["x"][0] for st in sts), "slip": sum(st["slip"][0] for st in sts),
            "system": sts[0]["system"], "phi": [st["phi"] for st in sts],
            "omega0": np.array([st["omega0"] for st in sts])}


def _start(specimen: Specimen, mode, amplitude, impact, modes):
    """``(amp, state)``: ``{mode: release amplitude or None}`` and the start state (the
    release of :func:`_release`, or rest for an impact, with the stuck modes of ``modes``)."""
    if (amplitude is None) == (impact is None):
        raise ValueError("give amplitude (a release) or impact (a force pulse), one of them")
    if impact is None:
        if modes is not None:
            raise ValueError("modes is for an impact; a release names its modes in amplitude")
        amp = _amplitudes(mode, amplitude)
        return amp, _release(specimen, amp)
    if not isinstance(impact, Impact):
        raise ValueError(f"impact must be an Impact, got {type(impact).__name__}")
    if mode is not None:
        raise ValueError("mode is for a release; give an impact's modes as modes=(1, 2, ...)")
    if impact.position > specimen.total_length:
        raise ValueError(f"impact position must lie on the assembly (<= "
                         f"{specimen.total_length:.6g} m), got {impact.position!r}")
    ms = (1,) if modes is None else tuple(modes)
    amp = _amplitudes(None, {r: 1.0 for r in ms})          # checks the modes
    lm = [linear_modes(specimen, mode=r) for r in amp]
    L = lm[0][3]
    return {r: None for r in amp}, {
        "x": np.zeros(L.M.shape[0]), "slip": np.zeros(L.G.shape[0]), "system": L,
        "phi": [m[1] for m in lm], "omega0": np.array([m[0] for m in lm])}


def _add_impact(model, impact: Impact, rec) -> None:
    """The pulse as a load on the axis at its position; the recorder books its work."""
    model.mbs.AddLoad(LoadForceVector(
        markerNumber=model.axis_marker(impact.position), loadVector=[0.0, 0.0, 0.0],
        loadVectorUserFunction=lambda mbs_, t, lv: [0.0, impact.force(t), 0.0]))
    rec.impact = (impact, axis_rows(model.specimen, [impact.position])[0])


def _initial_energy(model, rel, effs) -> tuple:
    """``(kinetic, total)`` energy [J] at the release: the beams' strain energy, the springs',
    the joint's (the virgin backbone work at the initial slips) and the effects'."""
    kin0, pot0 = model.beam_energy()
    u0 = np.abs(rel["slip"])
    e_joint0 = float(sum(backbone_work(u, p) for u, p in zip(u0, model.points.params)))
    e0 = pot0 + model.spring_energy() + e_joint0
    for eff in effs:
        e0 += eff.start(eff.s * float(eff.a_free @ rel["x"]))
    return kin0, e0


class _Recorder:
    """The post-step function of a ring-down: the coordinates and (with
    ``record_energy``) the energy terms of every accepted step, and the effects' commits."""

    def __init__(self, L, effs, floor_work, record_energy: bool):
        self.L, self.effs, self.floor_work, self.record = L, effs, floor_work, record_energy
        self.times, self.coords = [], []
        self.energy = {k: [] for k in _E_KEYS}
        self.model = None
        self.impact = None                 # (Impact, row of its point) when one acts
        self.work_in, self.last = 0.0, None
        self.bar = None                    # a progress bar over the steps, if asked

    def __call__(self, mbs_, t):
        sd, free = mbs_.systemData, self.L.free
        self.times.append(t)
        if self.bar is not None and len(self.times) % 50 == 0:
            tick(self.bar, 50)
        self.coords.append(sd.GetODE2Coordinates())
        v = np.asarray(sd.GetODE2Coordinates_t())[free]
        e = self.energy
        for eff in self.effs:
            eff.commit(self.coords[-1][free], v)
        if self.record:
            if self.effs:
                es, ed = np.sum([eff.energy() for eff in self.effs], axis=0)
                e["effect_stored"].append(es)
                e["effect_dissipated"].append(ed)
            e["floor_dissipated"].append(self.floor_work.step(t, v))
            if self.impact is not None:
                imp, row = self.impact
                F, y = imp.force(t), float(row @ self.coords[-1][free])
                if self.last is not None:  # the trapezoidal rule's work of the load
                    self.work_in += 0.5 * (F + self.last[0]) * (y - self.last[1])
                self.last = (F, y)
                e["input_work"].append(self.work_in)
            kin, pot = self.model.beam_energy()
            e["t"].append(t)
            e["kinetic"].append(kin)
            e["strain"].append(pot)
            e["springs"].append(self.model.spring_energy())
        return True


def ringdown(specimen: Specimen, *, mode: int | None = None, amplitude=None,
             impact: Impact | None = None, modes=None, sensors=None,
             duration: float | None = None, cycles: float | None = None,
             steps_per_period: int = 64, n_periods: float = 3.0, record_energy: bool = False,
             joint_elements: bool = False, progress: bool = False) -> RingdownResult:
    """Release the specimen from a static deflection in one or several modes' load shapes,
    or strike it (``impact``); let it ring down through the interface.

    Parameters
    ----------
    specimen : Specimen
    mode : int, optional, keyword-only
        Elastic mode number (1: lowest) of a single-mode release (default 1); not with a
        dict ``amplitude``.
    amplitude : float or dict, keyword-only
        Initial displacement amplitude at the sensor point [m] (> 0) of ``mode``, or
        ``{mode: amplitude}`` to release several modes at once: the sum of the modes'
        static deflections, each reaching its amplitude at ``specimen.sensor_position``.
    impact : Impact, optional, keyword-only
        Instead of a release: the specimen at rest struck by a half-sine force pulse
        (:class:`~iwan_element.models.impact.Impact`); the step also resolves the pulse
        (at most a sixteenth of its contact time).
    modes : sequence of int, optional, keyword-only
        The modes an impact's result separates (modal filter, curves; default ``(1,)``).
    sensors : sequence of float, optional, keyword-only
        Positions [m] along the beams' axis (the axis of ``sensor_position``) where the
        displacement and acceleration are recorded (default: ``sensor_position``).
    duration : float, optional, keyword-only
        Duration [s] (> 0); or give ``cycles``.
    cycles : float, optional, keyword-only
        Duration in periods of the lowest released mode's stuck frequency (> 2; default 30
        when ``duration`` is not given).
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

    Returns
    -------
    RingdownResult
        One decay curve per released mode (``curves``; ``curve`` is the lowest's), the
        sensors' records and the energy balance.

    Notes
    -----
    Newton (modified Newton, relative tolerance 1e-10) stops when the residual norm falls
    below ``max(1e-7 F, F_ro)`` [N]: ``F = max |K0 x0|``, the largest elastic force of the
    release state, scales with the amplitude; ``F_ro = eps k_max span sqrt(n)`` is the
    amplitude-independent round-off of the residual
    (:func:`~iwan_element.models.solver.roundoff_force`). Below about 10 um on the
    Brake-Reuss beam ``1e-7 F`` fell under the round-off (residual stalling at 1e-6 to
    2.5e-6 N), Newton never converged and the step was cut without end; with the bound the
    2 um run takes seconds and agrees with QSMA (``tests/test_qsma.py``). No discontinuous
    iteration is involved (one per step, Exudyn's default): the compiled law is an explicit
    function of the slip given the committed state, which changes only in the post-step of
    an accepted step.
    """
    n_periods, cycles, duration = _check_args(specimen, steps_per_period, n_periods, cycles,
                                              duration)
    amp, rel = _start(specimen, mode, amplitude, impact, modes)
    positions = np.atleast_1d(np.asarray(
        specimen.sensor_position if sensors is None else sensors, float))
    rows = axis_rows(specimen, positions)
    L, w0 = rel["system"], rel["omega0"]
    floor = floor_damping(specimen)
    effs = [ModalEffects(specimen, r, L, phi, w) for r, phi, w in zip(amp, rel["phi"], w0)
            if any(e.mode == r for e in specimen.effects)]
    rec = _Recorder(L, effs, FloorWork(floor.C if floor.active else None), record_energy)
    model = build_specimen_model(specimen, tangential="iwan", post_step=rec,
                                 joint_elements=joint_elements)
    rec.model = model
    mbs = model.mbs
    for eff in effs:
        eff.attach(mbs, model.nodes, L.n_coordinates)
    if floor.active:
        attach_floor_damping(mbs, model.nodes, floor, L.free, L.n_coordinates)
    if impact is not None:
        _add_impact(model, impact, rec)
    if effs or floor.active or impact is not None:
        mbs.Assemble()
    x0 = np.zeros(L.n_coordinates)
    x0[L.free] = rel["x"]
    mbs.systemData.SetODE2Coordinates(x0, configuration=exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates(x0, configuration=exu.ConfigurationType.Current)
    kin0, e0 = _initial_energy(model, rel, effs)
    h = 2 * math.pi / (w0.max() * steps_per_period)
    if impact is not None:
        h = min(h, impact.contact_time / 16)
    n = int(round(duration / h)) if duration is not None else \
        int(round(cycles * steps_per_period * w0.max() / w0.min())) if impact is None else \
        int(round(cycles * 2 * math.pi / (w0.min() * h)))
    sim = solver_settings(force_scale=max(float(np.max(np.abs(L.K0 @ rel["x"]))),
                                          0.0 if impact is None else abs(impact.peak_force)))
    newton = sim.timeIntegration.newton
    newton.absoluteTolerance = max(newton.absoluteTolerance, roundoff_force(L, specimen))
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    t0 = time.perf_counter()
    rec.bar = progress_bar(progress, total=n + 1, desc="ringdown", unit="step")
    try:
        mbs.SolveDynamic(sim)
        tick(rec.bar, len(rec.times) % 50)            # the steps since the last tick
    finally:
        finish(rec.bar)
    wall = time.perf_counter() - t0
    quad = _joint_records(model.interface, rec.energy, e0 + rec.work_in) if record_energy \
        else None
    return with_energy_warning(_result(specimen, amp, rec, rel, rows, positions, h, n, {
        "n_periods": n_periods, "steps_per_period": steps_per_period, "wall": wall, "e0": e0,
        "kin0": kin0, "quad": quad, "n_points": len(model.points),
        "overflow": len(getattr(model.interface, "overflow_times", ())),
        "effects": tuple(nm for eff in effs for nm in eff.names), "impact": impact}))


def _result(specimen, amp, rec, rel, rows, positions, h, n, run) -> RingdownResult:
    """The ring-down's result from its records: every signal on the nominal step grid, one
    decay curve per mode from its modal filter."""
    L, w0, modes = rel["system"], rel["omega0"], tuple(amp)
    X = np.array(rec.coords)[:, L.free]
    k = len(modes)
    s_phi = np.array([float(L.S @ phi) for phi in rel["phi"]])
    sig = np.vstack([X @ L.S, (X @ (L.M @ np.array(rel["phi"]).T) * s_phi).T, rows @ X.T])
    t, sig, cut = _on_step_grid(np.array(rec.times), sig, h, n)
    sig = np.array(sig)
    modal, disp = sig[1:1 + k], sig[1 + k:]
    curves, warns = [], []
    for i, r in enumerate(modes):
        # several modes: each modally filtered record (the other modes filtered out, so
        # nothing to alias) is read every q-th step, about 32 samples per period of its mode;
        # the curve's filter costs grow steeply with the samples per period (measured: 6.7 s
        # at 64, 0.5 s at 32, whatever the record's length). An anti-aliasing decimation
        # (scipy.signal.decimate) left end effects that cut the short records' curves.
        q = 1 if k == 1 else max(1, int(run["steps_per_period"] * w0.max() / w0[i] / 32))
        ti, yi = t[::q], modal[i][::q]
        c = decay_curve(ti, yi, h, w0[i] / (2 * math.pi), run["n_periods"], notes=(
            f"{specimen.name}: Exudyn transient, mode {r}"
            + (f" of modes {', '.join(map(str, modes))}" if k > 1 else "")
            + f", {run['steps_per_period']} steps per period of the highest mode, "
            + (f"released from {amp[r]:.3g} m at the sensor" if amp[r] is not None else
               f"struck by {run['impact'].peak_force:.4g} N over {run['impact'].contact_time:.3g} s"
               f" at {run['impact'].position:.4g} m")
            + "; modal filtering"
            + (f"; with {' + '.join(run['effects'])}" if run["effects"] else "")))
        curves.append(c)
        warns += [w if k == 1 else f"mode {r}: {w}" for w in c.warnings]
    return RingdownResult(
        t=t, sensor=sig[0], modal=modal[0], curve=curves[0],
        energy={key: np.array(v) for key, v in rec.energy.items()}, initial_energy=run["e0"],
        wall_time=run["wall"],
        metadata={"h": h, "steps": n, "extra_steps": cut, "modes": modes, "amplitude": amp,
                  "floor": {r: specimen.floor(r) for r in modes}, "n_points": run["n_points"],
                  "effects": run["effects"], "kinetic_at_release": run["kin0"],
                  "joint_quadrature_error": run["quad"], "overflow_steps": run["overflow"],
                  "impact": run["impact"]},
        modes=modes, curves=tuple(curves), modal_responses=modal, sensor_positions=positions,
        sensor_displacement=disp, sensor_acceleration=_second_derivative(disp, h),
        warnings=tuple(warns) + _cut_warning(cut, n, w0.max() * h) + ((
            f"{run['overflow']} step(s) closed more slip loops than the compiled interface law "
            "holds (8 reversal points, 24 with several modes): their joint forces were not "
            "exact (the interface's "
            "overflow_times; the Python route, joint_elements=True, is exact)",)
            if run["overflow"] else ()))


def _second_derivative(y, h):
    """``d2y/dt2`` of records on the step grid (last axis) by central second differences
    (relative error ``(w h)^2 / 12`` at ``w`` [rad/s]), the ends extrapolated linearly. The
    integrator's own acceleration variable is not used: at spectral radius 1 the
    generalized-alpha acceleration alternates about the physical one by the start's
    mismatch (measured on the example beam: a sawtooth of the acceleration's size)."""
    a = np.empty_like(y)
    a[..., 1:-1] = (y[..., 2:] - 2 * y[..., 1:-1] + y[..., :-2]) / (h * h)
    a[..., 0] = 2 * a[..., 1] - a[..., 2]
    a[..., -1] = 2 * a[..., -2] - a[..., -3]
    return a


def _on_step_grid(times, signals, h, n):
    """Signals recorded once per accepted step (at ``times`` [s]) on the nominal grid
    ``k h``, ``k = 0..n``: ``(t, signals, cut)``. Where the interface slips hard,
    Exudyn cuts the step (measured: 1,689 accepted steps instead of 512 on the two-bolt
    aluminium beam released from 500 um); the records are then interpolated linearly onto the
    grid (``cut``: how many steps more than ``n`` were taken). Read as if every record were one
    nominal step apart, they had stretched the time scale: the decay came out at half its
    frequency."""
    t = np.arange(n + 1) * h
    if times.size == n + 1 and np.allclose(times, t, rtol=0.0, atol=1e-9 * h):
        return t, list(signals), 0
    return t, [np.interp(t, times, y) for y in signals], int(times.size - 1 - n)


def _cut_warning(cut: int, n: int, wh: float) -> tuple:
    """The warning of a ring-down whose solver took ``cut`` steps more than its ``n``
    nominal ones (``wh``: the nominal step times the linear frequency [rad])."""
    if not cut:
        return ()
    return (f"the solver took {cut} steps more than the {n} nominal ones (the interface "
            "slipping hard); the records were interpolated onto the nominal step, whose "
            f"trapezoidal period correction (up to {wh * wh / 12:.1e} of the frequency) is "
            "applied as if no step had been cut: give more steps_per_period for a frequency "
            "closer than that",)


def _joint_records(itf, energy: dict, e0: float) -> float:
    """Fill the joints' stored and dissipated energy into ``energy`` from the interface's
    records, and return their exact work minus the trapezoidal work ``sum (F_n + F_n+1) du / 2``
    of the same slips and forces, over the release energy ``e0`` [-]: the time integrator's
    quadrature error of the hysteretic forces, which is what the energy balance measures
    when the bookkeeping is right."""
    # the interface commits after the user post-step of the same step: its records (one per
    # accepted step, and one at t = 0) line up with ours
    m = len(energy["t"])
    energy["joint_stored"] = list(itf.stored_energy_history[-m:])
    energy["joint_dissipated"] = list(itf.dissipated_energy_history[-m:])
    u, F, W = itf.slip_history[-m:], itf.force_history[-m:], itf.work_history[-m:]
    trap = float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u, axis=0)))
    return (float(W[-1] - W[0]) - trap) / e0
