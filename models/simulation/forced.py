"""Stepped-sine forced response of a specimen through a resonance, at several force levels.

A transverse force ``F sin(2 pi f t)`` acts at the specimen's excitation point (a shaker);
at each frequency of the step the run continues from the state the previous frequency left
(the force's phase kept continuous) for ``settle_cycles`` periods; over the next
``measure_cycles`` the sensor's fundamental is read as a lock-in amplifier reads it: a least-
squares fit of ``a + b t + X sin(theta + phi)`` (``theta`` the force's phase), whose amplitude
``X`` and phase ``phi`` (receptance-like: 0 below the resonance, -pi above) are reported. The
linear term takes out the drift of a free-free specimen: a sine force switched on at rest
gives the rigid body a net momentum ``F / (W m)``, and its drift, read as half the
peak-to-peak displacement (as before), put up to six times the steady amplitude into the
Brake-Reuss beam's results. The
beams carry the specimen's damping floor, one ratio per mode, as the modal damping matrix
of the stuck system (the ring-down's,
:func:`~iwan_element.models.reduced.damping.floor_damping`); the joint damps through the
contact points' Iwan elements. Time integration: generalized-alpha at spectral radius 0.98
(a little numerical damping of the kHz axial and contact modes the force's switch-on
excites). The trapezoidal rule answers a force at ``W_d`` as the continuous system answers one at
``W = (2/h) tan(W_d h / 2)`` (the bilinear map; for the ring-down, the period correction of
``docs/beam_tests.md``): each frequency ``W`` is driven at ``W_d`` with
``steps_per_period`` steps a period of ``W_d`` (:func:`prewarp`), so the amplitudes are read
at ``W`` itself. Uncorrected, the response curve sat ``(W h)^2 / 12`` high in frequency
(8e-4 at 64 steps a period, a fifth of the bandwidth at 2 % damping: 2.2 % in amplitude
against 4x the steps; docs/transient_cost.md).

Check (``docs/beam_tests.md``): with the contact points stuck (a friction so high that
nothing slips) the response is the linear one, whose peak amplitude per force is
``|S phi| |E phi| / (2 zeta w^2)`` at ``w`` for the mode's floor ``zeta``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import exudyn as exu
import numpy as np

from iwan_element.base.progress import finish, progress_bar, tick
from iwan_element.base.result_shape import ResultShape, column, panels
from iwan_element.base.serialize import json_safe
from iwan_element.base.validation import check_int, check_scalar, finite_array

from ..modal.qsma import linear_modes
from ..reduced.dispatch import linear_system
from ..specimens.specimen import Specimen
from .host import build_host
from .newton import check_newton, choose_newton, solve_dynamic
from .solver import MAX_STEPS, check_steps, solver_settings

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["ForcedResponseResult", "forced_response", "prewarp"]


@dataclass(frozen=True)
class ForcedResponseResult(ResultShape):
    """Stepped-sine response, with the package's result shape.

    Attributes
    ----------
    force_levels : ndarray, shape (n_levels,)
        Force amplitudes [N].
    frequencies : ndarray, shape (n_freq,)
        Excitation frequencies [Hz] in the order stepped.
    amplitude : ndarray, shape (n_levels, n_freq)
        Fundamental displacement amplitude at the sensor [m] (module docstring).
    specimen : Specimen
    phase : ndarray, shape (n_levels, n_freq)
        Its phase relative to the force [rad], receptance-like.
    metadata : dict
        ``mode``, ``linear_frequency_Hz``, ``floor`` (the mode's damping floor [-]),
        ``settle_cycles``,
        ``measure_cycles``, ``steps_per_period``; the solver's ``newton_iterations``,
        ``jacobians`` and ``step_cuts`` (accepted steps beyond the nominal ones), each an
        int array of shape (n_levels, n_freq).
    warnings : tuple of str
        A peak at the first or last frequency (the resonance is not inside the sweep).
    """

    force_levels: np.ndarray
    frequencies: np.ndarray
    amplitude: np.ndarray
    specimen: Specimen
    phase: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    def _tables(self) -> list:
        """The response, one row per force level and frequency (the main table), then the
        peak of each level.
        """
        phase = self.phase if self.phase is not None else np.full(self.amplitude.shape, np.nan)
        rows = [
            (float(F), float(f), float(a), float(a / F), float(ph))
            for F, amp, phs in zip(self.force_levels, self.amplitude, phase)
            for f, a, ph in zip(self.frequencies, amp, phs)
        ]
        cols = (
            column("force level", "N"),
            column("frequency", "Hz"),
            column("amplitude", "m"),
            column("amplitude / force", "m/N"),
            column("phase", "rad"),
        )
        fp, ap = self.peaks()
        peaks = [(float(F), float(f), float(a)) for F, f, a in zip(self.force_levels, fp, ap)]
        head = (
            column("force level", "N"),
            column("peak frequency", "Hz"),
            column("peak amplitude", "m"),
        )
        return [("response", cols, rows), ("peaks", head, peaks)]

    def peaks(self) -> tuple[np.ndarray, np.ndarray]:
        """(peak frequency [Hz], peak amplitude [m]) per force level."""
        j = np.argmax(self.amplitude, axis=1)
        return self.frequencies[j], self.amplitude[np.arange(len(j)), j]

    @property
    def success(self) -> bool:
        """True when every level's peak lies inside the swept frequencies."""
        j = np.argmax(self.amplitude, axis=1)
        return bool(np.all((j > 0) & (j < self.frequencies.size - 1)))

    def summary(self) -> dict:
        """Peaks per level (JSON-safe)."""
        fp, ap = self.peaks()
        return json_safe(
            {
                "force_levels_N": self.force_levels,
                "peak_frequency_Hz": fp,
                "peak_amplitude_m": ap,
                "frequencies_Hz": self.frequencies,
            }
        )

    def report(self) -> str:
        """Human-readable account: the peak of each force level."""
        fp, ap = self.peaks()
        m = self.metadata
        lines = [
            self.verdict(),
            f"stepped sine of {self.specimen.name}, mode {m['mode']} (stuck "
            f"{m['linear_frequency_Hz']:.4f} Hz), {self.frequencies.size} frequencies "
            f"{self.frequencies.min():.4f}-{self.frequencies.max():.4f} Hz",
        ]
        lines += [
            f"  F = {F:g} N: peak {a:.4g} m at {f:.4f} Hz ({a / F:.4g} m/N)"
            for F, f, a in zip(self.force_levels, fp, ap)
        ]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def to_dict(self) -> dict:
        """JSON-safe: the amplitudes, peaks, metadata, success and warnings."""
        return json_safe(
            {
                **self.summary(),
                "amplitude_m": self.amplitude,
                "phase_rad": self.phase,
                "metadata": self.metadata,
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Amplitude per force [m/N] against frequency, one line per level; returns the
        artists.
        """
        (a,) = panels(ax, 1)
        arts = []
        for F, amp in zip(self.force_levels, self.amplitude):
            arts += a.plot(self.frequencies, amp / F, "o-", ms=3, label=f"F = {F:g} N")
        a.set(xlabel="frequency [Hz]", ylabel="amplitude / force [m/N]")
        a.legend(fontsize=8)
        return arts


def prewarp(w: float, steps_per_period: int) -> tuple[float, float]:
    """``(h, w_d)``: the time step [s] and the drive frequency [rad/s] at which the
    trapezoidal rule responds as the continuous system does at ``w`` [rad/s]:
    ``(2/h) tan(w_d h / 2) = w`` with ``w_d h = 2 pi / steps_per_period``, i.e.
    ``h = 2 tan(pi / steps_per_period) / w`` (module docstring).
    """
    h = 2.0 * math.tan(math.pi / steps_per_period) / w
    return h, 2.0 * math.pi / (steps_per_period * h)


def _lock_in(t, y, theta):
    """``(X, phi)`` of ``y(t) = a + b t + X sin(theta + phi)``, least squares (``theta`` the
    force's phase at each sample [rad]).
    """
    A = np.column_stack([np.ones_like(t), t - t.mean(), np.sin(theta), np.cos(theta)])
    c = np.linalg.lstsq(A, y, rcond=None)[0]
    return math.hypot(c[2], c[3]), math.atan2(c[3], c[2])


def _force_scale(model, F0, freqs) -> float:
    """Newton's force scale [N] of a sweep at force amplitude ``F0`` [N] over ``freqs``
    [Hz]: the largest elastic force of the host (bodies and springs, as the ring-down's)
    in the stuck interface's linear steady response at any of the frequencies, or ``F0``
    if larger.

    ``F0`` alone was far too small near a resonance: the residual of the host's dense
    stiffness has a round-off floor of about ``eps sum_j |K'_ij z_j|``, and with the
    Brake-Reuss beam at 0.02 N (elastic forces 0.2-0.5 N, terms of 1e5 N; the free-free
    beam's drift adds to ``z`` as the run goes on) Newton's ``1e-7 F0`` = 2e-9 N met that
    floor: modified Newton stalled at a contraction of 0.8-0.96 and took a new Jacobian,
    560 times over one frequency (docs/transient_cost.md).
    """
    n_eta, m = model.n_eta, len(model.points)
    K = model.Kb + model.Ks
    Kt = K.copy()
    if model.interface is not None:  # the Iwan elements' stuck stiffness
        i = np.arange(n_eta, n_eta + m)
        Kt[i, i] += model.points.KT
    C = np.zeros_like(K) if model.floor_C is None else model.floor_C
    f = np.zeros(K.shape[0])
    f[model.ports["excitation"]] = F0
    scale = F0
    for w in 2 * math.pi * np.asarray(freqs, float):
        z = np.linalg.solve(Kt - w * w * model.Mz + 1j * w * C, f)
        scale = max(scale, float(np.max(np.abs(K @ z))))
    return scale


def _sweep_level(s, F0, freqs, cycles, steps_per_period, rho, bar=None, newton="auto"):
    """Steady fundamental amplitude [m] and phase [rad] at the sensor at each frequency of
    ``freqs`` for one force level ``F0`` [N], each frequency continuing from the state the
    previous one left, and the solver's counts per frequency (Newton iterations, Jacobians,
    step cuts).
    """
    settle, measure = cycles
    # the switch-on transient beats with the forced response and nests the joints' loops:
    # the host's default depth (24) holds them (8 overflowed 54 times on the Brake-Reuss
    # beam at 2 N)
    L = linear_system(s)
    rec = {"t": [], "y": []}

    def record(mbs_, t):  # the sensor, once per accepted step (a
        rec["t"].append(t)  # stored sensor of every coordinate grew
        rec["y"].append(float(read @ mbs_.systemData.GetODE2Coordinates()))  # as n^2)
        return True

    model = build_host(s, ports={"excitation": L.E}, post_step=record, assemble=False)
    mbs = model.mbs
    read = model.T.T @ L.S  # the sensor's row in the host's coordinates
    state = {"w": 2 * math.pi * freqs[0], "t0": 0.0, "phase": 0.0}
    model.add_port_force(
        "excitation", lambda t: F0 * math.sin(state["phase"] + state["w"] * (t - state["t0"]))
    )
    mbs.Assemble()
    sim = solver_settings(force_scale=_force_scale(model, F0, freqs))
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    sim.timeIntegration.generalizedAlpha.spectralRadius = rho
    ti = sim.timeIntegration
    step = choose_newton(model, sim, newton)
    amp, phase = np.zeros(len(freqs)), np.zeros(len(freqs))
    counts = np.zeros((len(freqs), 3), int)  # Newton iterations, Jacobians, step cuts
    t_now = 0.0
    for j, f in enumerate(freqs):
        h, w_d = prewarp(2 * math.pi * f, steps_per_period)
        state["phase"] += state["w"] * (t_now - state["t0"])
        state["w"], state["t0"] = w_d, t_now
        n = (settle + measure) * steps_per_period
        ti.startTime, ti.endTime, ti.numberOfSteps = t_now, t_now + n * h, n
        if j > 0:
            ti.initialStepSize = h
        rec["t"].clear()
        rec["y"].clear()
        solve_dynamic(mbs, sim, newton=step, update_initial_values=True)
        tt, yy = np.array(rec["t"]), np.array(rec["y"])
        keep = tt >= t_now + settle * steps_per_period * h * (1 - 1e-12)
        tk = tt[keep]
        amp[j], phase[j] = _lock_in(tk, yy[keep], state["phase"] + state["w"] * (tk - t_now))
        it = mbs.sys["dynamicSolver"].it
        counts[j] = (it.newtonStepsCount, it.newtonJacobiCount, it.currentStepIndex - 1 - n)
        tick(bar, text=f"{F0:.3g} N, {f:.5g} Hz")
        t_now = ti.endTime
    return amp, phase, counts


def _sweep_frequencies(specimen, frequencies, mode) -> tuple[float, np.ndarray]:
    """``(f_lin, freqs)``: the stuck frequency of ``mode`` [Hz] and the checked frequencies
    of the sweep (default: 15 from 0.97 to 1.01 times it).
    """
    f_lin = linear_modes(specimen, mode=mode)[0] / (2 * math.pi)
    freqs = (
        np.linspace(0.97, 1.01, 15) * f_lin
        if frequencies is None
        else finite_array("frequencies", frequencies, ndim=1)
    )
    if np.any(freqs <= 0):
        raise ValueError(f"frequencies must be > 0 [Hz], got {frequencies!r}")
    steps = np.diff(freqs)
    if freqs.size < 3 or not (np.all(steps > 0) or np.all(steps < 0)):
        raise ValueError(
            "frequencies must be at least 3 values stepped up or down (strictly "
            f"monotonic) [Hz], got {frequencies!r}"
        )
    return f_lin, freqs


def forced_response(
    specimen: Specimen,
    *,
    force_levels=(0.5, 2.0),
    frequencies=None,
    mode: int = 1,
    settle_cycles: int = 60,
    measure_cycles: int = 10,
    steps_per_period: int = 60,
    spectral_radius: float = 0.98,
    progress: bool = False,
    newton: str = "auto",
    max_steps: int = MAX_STEPS,
) -> ForcedResponseResult:
    """Transverse force ``F sin(2 pi f t)`` at the excitation point, stepped through a
    resonance at each force level (module docstring).

    Parameters
    ----------
    specimen : Specimen
        Its ``excitation.position`` is where the force acts, its ``sensor_position`` where
        the amplitude is read; its damping floor damps the beams.
    force_levels : sequence of float, keyword-only
        Force amplitudes [N], finite and > 0.
    frequencies : array_like, optional, keyword-only
        Frequencies to step through [Hz], finite and > 0, in order; default 15 from 0.97 to
        1.01 times the stuck frequency of ``mode``.
    mode : int, keyword-only
        Elastic mode whose resonance the default frequencies cover (1: lowest).
    settle_cycles, measure_cycles : int, keyword-only
        Periods run before measuring, and measured, at each frequency (>= 1). Light damping
        settles slowly: raise ``settle_cycles`` for a sharper peak.
    steps_per_period : int, keyword-only
        Time steps per excitation period (>= 8).
    spectral_radius : float, keyword-only
        Generalized-alpha's spectral radius at infinite frequency, in [0.5, 1]: 0.98
        (default) damps a little the kHz axial and contact modes the force's switch-on
        excites; 1.0 is the trapezoidal rule. Either way the force is applied at the
        pre-warped frequency (:func:`prewarp`), so the integrator responds as the
        continuous system at the frequency asked for: measured on one mode (80 Hz, 2 %
        damping, 64 steps a period) within 2e-11 of its receptance at 1.0 and 1e-5 at 0.98,
        against 1.9 % off one bandwidth from the peak without the pre-warp.
    progress : bool, keyword-only
        Show a tqdm bar over the (level, frequency) points with its ETA; needs tqdm.
    newton : {"auto", "condensed", "exudyn"}, keyword-only
        How each time step is solved, as in :func:`~iwan_element.models.ringdown`: on the
        joints' slips, by Exudyn's modified Newton on the whole model, or (default) the
        first where it can serve and pays
        (:func:`~iwan_element.models.simulation.newton.choose_newton`).
    max_steps : int, keyword-only
        Most time steps over all levels and frequencies, ``levels x frequencies x
        (settle_cycles + measure_cycles) x steps_per_period`` (default
        :data:`~iwan_element.models.simulation.solver.MAX_STEPS`; the defaults take
        126,000); a longer sweep is refused before it starts with its estimated wall time.

    Returns
    -------
    ForcedResponseResult
    """
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    levels = finite_array("force_levels", force_levels, ndim=1)
    if np.any(levels <= 0):
        raise ValueError(f"force_levels must be > 0 [N], got {force_levels!r}")
    cycles = (
        check_int("settle_cycles", settle_cycles, 1),
        check_int("measure_cycles", measure_cycles, 1),
    )
    spp = check_int("steps_per_period", steps_per_period, 8)
    rho = check_scalar("spectral_radius", spectral_radius, low=0.5, high=1.0)
    check_newton(newton)
    f_lin, freqs = _sweep_frequencies(specimen, frequencies, mode)
    check_steps(
        levels.size * freqs.size * sum(cycles) * spp,
        n_coordinates=None,  # it records the sensor alone
        max_steps=max_steps,
        what="forced_response",
        shorten="fewer force_levels or frequencies, fewer settle_cycles or measure_cycles",
    )
    bar = progress_bar(
        progress, total=levels.size * freqs.size, desc="forced_response", unit="point"
    )
    try:
        runs = [
            _sweep_level(specimen, float(F0), freqs, cycles, spp, rho, bar, newton) for F0 in levels
        ]
    finally:
        finish(bar)
    out = ForcedResponseResult(
        force_levels=levels,
        frequencies=freqs,
        amplitude=np.array([r[0] for r in runs]),
        phase=np.array([r[1] for r in runs]),
        specimen=specimen,
        metadata={
            "mode": mode,
            "linear_frequency_Hz": f_lin,
            "floor": specimen.floor(mode),
            "settle_cycles": cycles[0],
            "measure_cycles": cycles[1],
            "steps_per_period": spp,
            "newton_iterations": np.array([r[2][:, 0] for r in runs]),
            "jacobians": np.array([r[2][:, 1] for r in runs]),
            "step_cuts": np.array([r[2][:, 2] for r in runs]),
        },
    )
    if not out.success:
        out = replace(
            out,
            warnings=out.warnings
            + (
                "a force level's largest amplitude is at the first or last frequency: the "
                "resonance peak is not inside the sweep; widen frequencies",
            ),
        )
    return out
