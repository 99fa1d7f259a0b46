"""The pieces every ring-down shares (:func:`~iwan_element.models.ringdown`, 1-D beams and
solid bodies): the post-step recorder, the time grid and the run's length checked against
what its reader needs and what it costs, the timed solve, the release energy of the joints,
and the result built from the records.
"""

from __future__ import annotations

import math
import time

import numpy as np

from iwan_element import backbone_work
from iwan_element.base.progress import finish, progress_bar, tick

from .newton import solve_dynamic
from .ringdown_result import RingdownResult, decay_curve
from .solver import check_steps

__all__ = [
    "Recorder",
    "step_grid",
    "min_record",
    "min_cycles",
    "check_run_length",
    "solve_timed",
    "virgin_joint_energy",
    "build_result",
    "joint_records",
]

E_KEYS = (
    "t",
    "kinetic",
    "strain",
    "springs",
    "joint_stored",
    "joint_dissipated",
    "floor_dissipated",
    "effect_stored",
    "effect_dissipated",
    "input_work",
)


class Recorder:
    """The post-step function of a ring-down: the host's coordinates and (with
    ``record_energy``) the energy terms of every accepted step, and the effects' commits
    (everything in the host's coordinates, :mod:`~iwan_element.models.simulation.host`).
    """

    def __init__(self, effs, floor_work, record_energy: bool):
        self.effs, self.floor_work, self.record = effs, floor_work, record_energy
        self.times: list[float] = []  # [s]
        self.coords: list[np.ndarray] = []  # the host's coordinates z
        self.energy: dict[str, list[float]] = {k: [] for k in E_KEYS}  # [J]
        self.model = None
        self.impact = None  # (Impact, row of its point in z) when one acts
        self.work_in, self.last = 0.0, None
        self.bar = None  # a progress bar over the steps, if asked

    def __call__(self, mbs_, t):
        """Record the step accepted at time ``t`` [s]; returns True (Exudyn goes on)."""
        sd = mbs_.systemData
        self.times.append(t)
        if self.bar is not None and len(self.times) % 50 == 0:
            tick(self.bar, 50)
        self.coords.append(sd.GetODE2Coordinates())
        v = np.asarray(sd.GetODE2Coordinates_t())
        e = self.energy
        for eff in self.effs:
            eff.commit(self.coords[-1], v)
        if self.record:
            if self.effs:
                es, ed = np.sum([eff.energy() for eff in self.effs], axis=0)
                e["effect_stored"].append(es)
                e["effect_dissipated"].append(ed)
            e["floor_dissipated"].append(self.floor_work.step(t, v))
            if self.impact is not None:
                imp, row = self.impact
                F, y = imp.force(t), float(row @ self.coords[-1])
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


def step_grid(
    w0, steps_per_period: int, *, duration=None, cycles=None, impact=None
) -> tuple[float, int]:
    """``(h, n)``: the time step [s] (``steps_per_period`` per period of the highest of the
    modes' stuck frequencies ``w0`` [rad/s]; at most a sixteenth of an impact's contact time)
    and the number of steps (``duration`` [s], or ``cycles`` periods of the lowest mode).
    """
    h = 2 * math.pi / (w0.max() * steps_per_period)
    if impact is not None:
        h = min(h, impact.contact_time / 16)
    if duration is not None:
        return h, int(round(duration / h))
    if impact is None:
        return h, int(round(cycles * steps_per_period * w0.max() / w0.min()))
    return h, int(round(cycles * 2 * math.pi / (w0.min() * h)))


#: The decay reader's (:func:`iwan_element.amplitude_curve`) trims of the band-pass's end
#: effects at the record's two ends, in units of ``1 / B`` for a band ``B`` [Hz] wide:
#: measured 1.16 (example beam, 66.5 Hz, 16-64 steps a period) and 1.2 (two-bolt beam) at
#: each end in the ring-down's band ``(0.5, 1.5) f0``; allowed 1.5 each.
TRIM_CELLS = 3.0
#: The record length, in units of ``1 / B``, at which the reader finds the mode in its band
#: (a Welch peak 10 times the band's median level): in the ring-down's band the example
#: beam's record gave a ratio of 4.05 at 4 periods and 9.92 at 5, a curve at 5.5; in the
#: two-bolt beam's hammer band (18.1, 23.1) Hz, a curve at 5.44 / B and none at 4.94 / B.
MODE_CELLS = 6.0


def min_record(band, window: float) -> float:
    """Shortest record [s] from which the decay reader gives one window of ``window`` [s] in
    ``band`` ``(low, high)`` [Hz]: ``max(6 / B, 3 / B + window)``, ``B = high - low``
    (:data:`MODE_CELLS`, :data:`TRIM_CELLS`).
    """
    width = float(band[1]) - float(band[0])
    return max(MODE_CELLS / width, TRIM_CELLS / width + window)


def min_cycles(n_periods: float) -> float:
    """Fewest periods of the lowest mode a ring-down's record must last for its decay curve
    (band ``(0.5, 1.5) f0``, ``B = f0``) to hold one window of ``n_periods``:
    ``max(6, n_periods + 3)`` (:func:`min_record`). Measured: 6, 9, 12 periods gave 1, 2, 3
    points at ``n_periods = 3``; 12 periods were refused ("record too short") and 13 gave one
    point at ``n_periods = 10``. ``k`` points take about ``3 + k n_periods`` periods.
    """
    return min_record((0.5, 1.5), n_periods)


def check_run_length(
    w0, steps_per_period: int, *, n_periods, duration, cycles, impact, **cost
) -> tuple[float, int]:
    """``(h, n)`` of :func:`step_grid` once the run is long enough for its decay curves
    (:func:`min_cycles` periods of the lowest of the stuck frequencies ``w0`` [rad/s]; a
    ValueError naming ``duration`` or ``cycles`` and the minimum otherwise) and within its
    step budget (``cost``: ``n_coordinates`` and ``max_steps`` of :func:`check_steps`).
    """
    w0 = np.atleast_1d(np.asarray(w0, float))
    need, f_low = min_cycles(n_periods), float(w0.min()) / (2 * math.pi)
    why = (
        f"{need:g} periods of the lowest mode ({f_low:.4g} Hz): its decay curve's reader "
        f"trims about {TRIM_CELLS / 2:g} periods of filter end effects at each end and needs "
        f"one window of n_periods = {n_periods:g} periods between them, and at least "
        f"{MODE_CELLS:g} periods to find the mode in its band"
    )
    if duration is not None and duration * f_low < need:
        raise ValueError(f"duration must be >= {need / f_low:.4g} s ({why}), got {duration!r}")
    if duration is None and cycles < need:
        raise ValueError(f"cycles must be >= {need:g} ({why}), got {cycles!r}")
    h, n = step_grid(w0, steps_per_period, duration=duration, cycles=cycles, impact=impact)
    check_steps(
        n,
        what="the ring-down",
        shorten="shorten duration (or cycles) or lower steps_per_period",
        **cost,
    )
    return h, n


def solve_timed(mbs, sim, rec, n: int, progress: bool, *, newton=None) -> dict:
    """The run over ``n`` steps (:func:`~.newton.solve_dynamic`, with the Newton step
    ``newton`` or Exudyn's) with the recorder's progress bar (if asked): ``{"wall": seconds
    in the solve, "newton_iterations": total, "jacobians": Newton Jacobians computed,
    "condensed_iterations": iterations on the joints' slips (0 on Exudyn's route)}``.
    """
    t0 = time.perf_counter()
    rec.bar = progress_bar(progress, total=n + 1, desc="ringdown", unit="step")
    try:
        solve_dynamic(mbs, sim, newton=newton)
        tick(rec.bar, len(rec.times) % 50)  # the steps since the last tick
    finally:
        finish(rec.bar)
    wall = time.perf_counter() - t0
    it = mbs.sys["dynamicSolver"].it
    return {
        "wall": wall,
        "newton_iterations": int(it.newtonStepsCount),
        "jacobians": int(it.newtonJacobiCount),
        "condensed_iterations": 0 if newton is None else newton.condensed_iterations,
    }


def virgin_joint_energy(slip, params) -> float:
    """Energy [J] stored by virgin Iwan elements (``params``) loaded to the slips ``slip``
    [m] along their backbones: the joints' share of a release state's energy.
    """
    return float(sum(backbone_work(abs(u), p) for u, p in zip(slip, params)))


def build_result(specimen, amp, rec, X, rel, rows, positions, h, n, run) -> RingdownResult:
    """The ring-down's result from its records (``rec``: times and energy terms; ``X``:
    the free coordinates of the linear system at every recorded step, shape
    ``(n_records, n_free)``): every signal on the nominal step grid, one decay curve per
    mode from its modal filter.
    """
    L, w0, modes = rel["system"], rel["omega0"], tuple(amp)
    k = len(modes)
    s_phi = np.array([float(L.S @ phi) for phi in rel["phi"]])
    sig = np.vstack([X @ L.S, (X @ (L.M @ np.array(rel["phi"]).T) * s_phi).T, rows @ X.T])
    t, sig, cut = on_step_grid(np.array(rec.times), sig, h, n)
    sig = np.array(sig)
    modal, disp = sig[1 : 1 + k], sig[1 + k :]
    curves, warns = [], []
    for i, r in enumerate(modes):
        # several modes: each modally filtered record (the other modes filtered out, so
        # nothing to alias) is read every q-th step, about 32 samples per period of its mode;
        # the curve's filter costs grow steeply with the samples per period (measured: 6.7 s
        # at 64, 0.5 s at 32, whatever the record's length). An anti-aliasing decimation
        # (scipy.signal.decimate) left end effects that cut the short records' curves.
        q = 1 if k == 1 else max(1, int(run["steps_per_period"] * w0.max() / w0[i] / 32))
        ti, yi = t[::q], modal[i][::q]
        c = decay_curve(
            ti,
            yi,
            h,
            w0[i] / (2 * math.pi),
            run["n_periods"],
            notes=_curve_notes(specimen, amp, r, modes, run),
        )
        curves.append(c)
        warns += [w if k == 1 else f"mode {r}: {w}" for w in c.warnings]
    return RingdownResult(
        t=t,
        sensor=sig[0],
        modal=modal[0],
        curve=curves[0],
        energy={key: np.array(v) for key, v in rec.energy.items()},
        initial_energy=run["e0"],
        wall_time=run["solve"]["wall"],
        metadata={
            "h": h,
            "steps": n,
            "extra_steps": cut,
            "modes": modes,
            "amplitude": amp,
            "floor": {r: specimen.floor(r) for r in modes},
            "n_points": run["n_points"],
            "effects": run["effects"],
            "kinetic_at_release": run["kin0"],
            "joint_quadrature_error": run["quad"],
            "overflow_steps": run["overflow"],
            "impact": run["impact"],
            "newton_iterations": run["solve"]["newton_iterations"],
            "jacobians": run["solve"]["jacobians"],
            "condensed_iterations": run["solve"]["condensed_iterations"],
            **run.get("extra", {}),
        },
        modes=modes,
        curves=tuple(curves),
        modal_responses=modal,
        sensor_positions=positions,
        sensor_displacement=disp,
        sensor_acceleration=second_derivative(disp, h),
        warnings=tuple(warns)
        + cut_warning(cut, n, w0.max() * h)
        + (
            (
                f"{run['overflow']} step(s) closed more slip loops than the compiled interface law "
                "holds (24 reversal points): their joint forces were not "
                "exact (the interface's "
                "overflow_times; the Python route, joint_elements=True, is exact)",
            )
            if run["overflow"]
            else ()
        ),
    )


def _curve_notes(specimen, amp, r, modes, run) -> str:
    """The notes of mode ``r``'s decay curve: the run, the release or impact, the effects."""
    k = len(modes)
    return (
        f"{specimen.name}: Exudyn transient, mode {r}"
        + (f" of modes {', '.join(map(str, modes))}" if k > 1 else "")
        + f", {run['steps_per_period']} steps per period of the highest mode, "
        + (
            f"released from {amp[r]:.3g} m at the sensor"
            if amp[r] is not None
            else f"struck by {run['impact'].peak_force:.4g} N over "
            f"{run['impact'].contact_time:.3g} s at {run['impact'].position:.4g} m"
        )
        + "; modal filtering"
        + (f"; with {' + '.join(run['effects'])}" if run["effects"] else "")
    )


def second_derivative(y, h):
    """``d2y/dt2`` of records on the step grid (last axis) by central second differences
    (relative error ``(w h)^2 / 12`` at ``w`` [rad/s]), the ends extrapolated linearly. The
    integrator's own acceleration variable is not used: at spectral radius 1 the
    generalized-alpha acceleration alternates about the physical one by the start's
    mismatch (measured on the example beam: a sawtooth of the acceleration's size).
    """
    a = np.empty_like(y)
    a[..., 1:-1] = (y[..., 2:] - 2 * y[..., 1:-1] + y[..., :-2]) / (h * h)
    a[..., 0] = 2 * a[..., 1] - a[..., 2]
    a[..., -1] = 2 * a[..., -2] - a[..., -3]
    return a


def on_step_grid(times, signals, h, n):
    """Signals recorded once per accepted step (at ``times`` [s]) on the nominal grid
    ``k h``, ``k = 0..n``: ``(t, signals, cut)``. Where the interface slips hard,
    Exudyn cuts the step (measured: 1,689 accepted steps instead of 512 on the two-bolt
    aluminium beam released from 500 um); the records are then interpolated linearly onto the
    grid (``cut``: how many steps more than ``n`` were taken). Read as if every record were one
    nominal step apart, they had stretched the time scale: the decay came out at half its
    frequency.
    """
    t = np.arange(n + 1) * h
    if times.size == n + 1 and np.allclose(times, t, rtol=0.0, atol=1e-9 * h):
        return t, list(signals), 0
    return t, [np.interp(t, times, y) for y in signals], int(times.size - 1 - n)


def cut_warning(cut: int, n: int, wh: float) -> tuple:
    """The warning of a ring-down whose solver took ``cut`` steps more than its ``n``
    nominal ones (``wh``: the nominal step times the linear frequency [rad]).
    """
    if not cut:
        return ()
    return (
        f"the solver took {cut} steps more than the {n} nominal ones (the interface "
        "slipping hard); the records were interpolated onto the nominal step, whose "
        f"trapezoidal period correction (up to {wh * wh / 12:.1e} of the frequency) is "
        "applied as if no step had been cut: give more steps_per_period for a frequency "
        "closer than that",
    )


def joint_records(itf, energy: dict, e0: float) -> float:
    """Fill the joints' stored and dissipated energy into ``energy`` from the interface's
    records, and return their exact work minus the trapezoidal work ``sum (F_n + F_n+1) du / 2``
    of the same slips and forces, over the release energy ``e0`` [-]: the time integrator's
    quadrature error of the hysteretic forces, which is what the energy balance measures
    when the bookkeeping is right. Without an Iwan interface (``itf`` None: linear springs)
    the joints' terms are zeros and so is the error.
    """
    m = len(energy["t"])
    if itf is None:
        energy["joint_stored"] = energy["joint_dissipated"] = [0.0] * m
        return 0.0
    # the interface commits after the user post-step of the same step: its records (one per
    # accepted step, and one at t = 0) line up with ours
    energy["joint_stored"] = list(itf.stored_energy_history[-m:])
    energy["joint_dissipated"] = list(itf.dissipated_energy_history[-m:])
    u, F, W = itf.slip_history[-m:], itf.force_history[-m:], itf.work_history[-m:]
    trap = float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u, axis=0)))
    return (float(W[-1] - W[0]) - trap) / e0
