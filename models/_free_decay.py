"""Free decay of the jointed beam and its cycle-by-cycle analysis (see :mod:`.scenarios`)."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.itemInterface import LoadCoordinate, MarkerNodeCoordinate, SensorNode

from ._linear_modes import ModalResult, modal_analysis
from ._scenario_settings import _bending_force_scale, _settings
from .jointed_beam import JointedBeamConfig, build_jointed_beam

__all__ = ["decay_analysis", "DecayRun", "FreeDecayResult", "free_decay"]

_OVT = exu.OutputVariableType

def decay_analysis(t, x, *, window: int = 6):
    """Amplitude-dependent frequency and damping from a free-decay record, cycle by cycle.

    Extremes of ``x`` are located with parabolic interpolation; the half peak-to-peak
    amplitude of consecutive extremes ``A_k`` decays as ``exp(-zeta w t)``. Over a sliding
    window of ``window`` half-cycles, a straight-line fit of ``ln A`` against time gives
    ``zeta w``, and the spacing of the extremes gives ``w``.

    Parameters
    ----------
    t, x : array_like, shape (n,)
        Time [s] and response (any unit); at least ``window + 2`` extremes.
    window : int, keyword-only
        Half-cycles per estimate, ``>= 2``.

    Returns
    -------
    amplitude, frequency, damping : ndarray, shape (m,)
        Amplitude (unit of ``x``), frequency [Hz] and damping ratio [-] per window.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.shape != x.shape or t.ndim != 1:
        raise ValueError("t and x must be 1-D arrays of the same length")
    if int(window) < 2:
        raise ValueError(f"window must be >= 2 half-cycles, got {window}")
    i = np.flatnonzero((np.sign(np.diff(x[:-1])) != np.sign(np.diff(x[1:]))) & (np.diff(x[:-1]) != 0)) + 1
    if len(i) < window + 2:
        raise ValueError(f"too few extremes in the record ({len(i)}) for window={window}")
    y0, y1, y2 = x[i - 1], x[i], x[i + 1]
    den = y0 - 2 * y1 + y2
    d = np.where(den != 0, 0.5 * (y0 - y2) / np.where(den != 0, den, 1.0), 0.0)
    h = np.diff(t).mean()
    te = t[i] + d * h
    xe = y1 - 0.25 * (y0 - y2) * d
    A = 0.5 * np.abs(np.diff(xe))
    tA = 0.5 * (te[1:] + te[:-1])
    amp, freq, damp = [], [], []
    for k in range(len(A) - window + 1):
        sl = slice(k, k + window)
        slope = np.polyfit(tA[sl] - tA[sl].mean(), np.log(A[sl]), 1)[0]
        half_period = np.mean(np.diff(te[k:k + window + 1]))
        w = math.pi / half_period
        amp.append(math.exp(np.mean(np.log(A[sl]))))
        freq.append(w / (2 * math.pi))
        damp.append(-slope / w)
    return np.array(amp), np.array(freq), np.array(damp)


@dataclass
class DecayRun:
    """One free-decay run.

    Attributes
    ----------
    level : float
        Initial tip displacement [m].
    t, tip : ndarray, shape (n,)
        Time [s] and transverse tip displacement [m].
    slips : ndarray, shape (n_points, n)
        Joint slips [m] (Iwan runs only; empty otherwise).
    energy : dict of ndarray
        ``t``, ``kinetic``, ``strain``, ``springs``, ``joint_stored``, ``joint_dissipated``
        [J] at the recorded steps (if requested).
    amplitude, frequency, damping : ndarray
        Cycle-by-cycle estimates from :func:`decay_analysis`.
    wall_time : float
        [s] spent in the solver.
    """

    level: float
    t: np.ndarray
    tip: np.ndarray
    slips: np.ndarray
    energy: dict
    amplitude: np.ndarray
    frequency: np.ndarray
    damping: np.ndarray
    wall_time: float


@dataclass
class FreeDecayResult:
    """Result of :func:`free_decay`: Iwan runs, linear-joint runs and the prediction."""

    runs: list
    linear_runs: list
    modal: ModalResult
    config: JointedBeamConfig
    metadata: dict = field(default_factory=dict)

    def curves(self, which: str = "iwan"):
        """Concatenated (amplitude, frequency, damping) of all runs of ``which`` (``"iwan"``
        or ``"linear"``), sorted by amplitude."""
        if which not in ("iwan", "linear"):
            raise ValueError(f"which must be 'iwan' or 'linear', got {which!r}")
        runs = self.runs if which == "iwan" else self.linear_runs
        a = np.concatenate([r.amplitude for r in runs])
        f = np.concatenate([r.frequency for r in runs])
        z = np.concatenate([r.damping for r in runs])
        o = np.argsort(a)
        return a[o], f[o], z[o]

    def prediction(self):
        """Closed-form (frequency, damping) at the measured amplitudes of the Iwan runs."""
        a, _, _ = self.curves()
        return self.modal.predict(a)

    def summary(self) -> dict:
        """JSON-safe summary: per level, the measured and predicted frequency and damping at
        the first and last estimate."""
        out = {"linear_frequency_Hz": float(self.modal.frequencies[0]), "levels": []}
        for r in self.runs:
            fp, zp = self.modal.predict(r.amplitude[[0, -1]])
            out["levels"].append({
                "initial_tip_m": r.level,
                "tip_amplitude_m": [float(r.amplitude[0]), float(r.amplitude[-1])],
                "frequency_Hz": [float(r.frequency[0]), float(r.frequency[-1])],
                "predicted_frequency_Hz": [float(x) for x in fp],
                "damping": [float(r.damping[0]), float(r.damping[-1])],
                "predicted_damping": [float(x) for x in zp],
                "wall_time_s": r.wall_time})
        return out


class _release_ramp:
    """Static load pattern ``w1^2 M phi1`` scaled to a tip deflection ``level`` (its linear
    static deflection is the first mode exactly), and its half-cosine removal after
    :meth:`release` through a pre-step function."""

    def __init__(self, model, modal: ModalResult, level: float):
        mbs = model.mbs
        pattern = (2 * math.pi * modal.frequencies[0]) ** 2 * (modal.mass_matrix @ modal.shapes[:, 0])
        pattern *= level / modal.tip[0]
        self.loads = []
        clamped = set(model.clamped_coordinates)
        for node in model.nodes_a + model.nodes_b:
            i0 = mbs.GetNodeODE2Index(node)
            for c in range(4):
                value = float(pattern[i0 + c])
                if value != 0.0 and i0 + c not in clamped:
                    mk = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
                    self.loads.append((mbs.AddLoad(LoadCoordinate(markerNumber=mk, load=value)), value))
        self.T, self.active, self.done = 0.0, False, False

    def release(self, duration: float) -> None:
        """Start removing the load at t = 0 over ``duration`` [s]."""
        self.T, self.active = max(duration, 1e-12), True

    def pre_step(self, mbs_, t):
        if not self.active or self.done:          # static pre-load, or load already gone
            return True
        f = 0.5 * (1.0 + math.cos(math.pi * t / self.T)) if t < self.T else 0.0
        for item, value in self.loads:
            mbs_.SetLoadParameter(item, "load", f * value)
        if f == 0.0:
            self.done = True
        return True


def _decay_run(cfg, level, modal, *, cycles, steps_per_period, joint_factory,
               record_energy, energy_every, release_time):
    """Static deflection of about ``level`` at the tip in the shape of the first mode (load
    pattern ``w1^2 M phi1``; the joints are loaded through the static load steps), then
    release and free vibration.

    The load is removed along a half-cosine over ``release_time``: short against the first
    period, so mode 1 is released, but long against the periods of the axial and contact
    modes (kHz), which therefore follow quasi-statically instead of ringing undamped.
    """
    energy = {k: [] for k in ("t", "kinetic", "strain", "springs", "joint_stored", "joint_dissipated")}
    coords = []
    counter = [0]
    handle = {}

    def post_step(mbs_, t):
        coords.append(mbs_.systemData.GetODE2Coordinates())
        if record_energy and counter[0] % energy_every == 0:
            m = handle["model"]
            kin, pot = m.beam_energy()
            st, ds = m.joint_energy()
            for k, v in zip(energy, (t, kin, pot, m.spring_energy(), st, ds)):
                energy[k].append(v)
        counter[0] += 1
        return True

    # the post-step goes in before the joint connectors, which chain it
    model = build_jointed_beam(cfg.replace(boundary="clamped-free"), joint_factory=joint_factory,
                               post_step=post_step)
    handle["model"] = model
    mbs = model.mbs
    ramp = _release_ramp(model, modal, level)
    mbs.SetPreStepUserFunction(ramp.pre_step)
    s_tip = mbs.AddSensor(SensorNode(nodeNumber=model.tip_node, outputVariableType=_OVT.Displacement,
                                     storeInternal=True))
    mbs.Assemble()
    scale = _bending_force_scale(cfg, level)
    static = _settings(force_scale=scale, static=True)
    static.staticSolver.numberOfLoadSteps = 10
    mbs.SolveStatic(static, updateInitialValues=True)
    for v in energy.values():
        v.clear()
    coords.clear()
    ramp.release(release_time)
    f_lin = modal.frequencies[0]
    h = 1.0 / (f_lin * steps_per_period)
    n = int(round(cycles * steps_per_period))
    sim = _settings(force_scale=scale)
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    sim.solution.sensors.writePeriod = h
    t0 = time.perf_counter()
    mbs.SolveDynamic(sim)
    wall = time.perf_counter() - t0
    d = mbs.GetSensorStoredData(s_tip)
    free = d[:, 0] >= release_time - 1e-12 * h
    t, tip = d[free, 0], d[free, 2]
    # mode 1 by modal filtering, expressed as the tip displacement it carries
    q1 = modal.modal_coordinates(np.array(coords)[-len(d):][free]) * abs(modal.tip[0])
    amp, freq, damp = decay_analysis(t, q1)
    slips = np.array([c.slip_history for c in model.connectors]) if model.connectors else np.empty((0, len(t)))
    if model.connectors:
        slips = slips[:, -len(t):]        # the free-vibration part of the records
    return DecayRun(level=float(d[0, 2]), t=t, tip=tip, slips=slips,
                    energy={k: np.array(v) for k, v in energy.items()},
                    amplitude=amp, frequency=freq, damping=damp,
                    wall_time=wall), model


def free_decay(config: JointedBeamConfig | None = None, *, levels=(2e-4, 1e-3, 5e-3),
               cycles: float = 20, steps_per_period: int = 100, joint_factory=None,
               linear_comparison: bool = True, record_energy: bool = False,
               energy_every: int = 1, release_fraction: float = 0.1,
               progress=None) -> FreeDecayResult:
    """Free decay of the clamped-free assembly released from a static tip deflection.

    Each run loads the tip statically (Exudyn's static solver, so the joints are loaded through
    their virgin curves and the beams carry the consistent geometrically nonlinear state),
    removes the load and integrates the free vibration. The tip response is band-passed
    around the first bending frequency before the cycle-by-cycle analysis, which removes the
    few per cent of higher modes a static deflection contains.

    Parameters
    ----------
    config : JointedBeamConfig, optional
    levels : sequence of float, keyword-only
        Initial tip displacements [m] (one run each; reached to within the joint's softening).
    cycles : float, keyword-only
        Duration in periods of the linearised first mode.
    steps_per_period : int, keyword-only
        Time steps per period (generalized-alpha, spectral radius 1).
    joint_factory : callable, optional, keyword-only
        Joint element per contact point (default exact Iwan).
    linear_comparison : bool, keyword-only
        Also run each level with a linear joint of stiffness ``KT``.
    record_energy : bool, keyword-only
        Record the energy terms every ``energy_every`` accepted steps (including the release).
    release_fraction : float, keyword-only
        Duration of the smooth load removal as a fraction of the first period (0: sudden).
    progress : callable, optional, keyword-only
        ``progress(message)`` is called before each run.
    """
    cfg = (config or JointedBeamConfig()).replace(boundary="clamped-free")
    if len(levels) < 1 or any(not (math.isfinite(x) and x > 0) for x in levels):
        raise ValueError(f"levels must be positive tip displacements [m], got {levels!r}")
    modal = modal_analysis(cfg, n_modes=3)
    runs, lin_runs = [], []
    variants = [(cfg, joint_factory, runs)]
    if linear_comparison and cfg.joint_model == "iwan":
        variants.append((cfg.replace(joint_model="linear"), None, lin_runs))
    for c, jf, out in variants:
        for lv in levels:
            if progress is not None:
                progress(f"free decay, {c.joint_model} joint, initial tip {lv * 1e3:.3g} mm")
            run, _ = _decay_run(c, float(lv), modal, cycles=cycles,
                                steps_per_period=steps_per_period, joint_factory=jf,
                                record_energy=record_energy, energy_every=energy_every,
                                release_time=release_fraction / modal.frequencies[0])
            out.append(run)
    return FreeDecayResult(runs=runs, linear_runs=lin_runs, modal=modal, config=cfg,
                           metadata={"cycles": cycles, "steps_per_period": steps_per_period,
                                     "levels": list(map(float, levels)),
                                     "integrator": "generalized-alpha, spectral radius 1"})
