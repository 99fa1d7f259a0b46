"""Scenarios for the jointed beam: the paper's quasi-static test, free decay, forced response.

Each scenario builds its own model from a :class:`~iwan_element.models.jointed_beam.JointedBeamConfig`
and returns a result object with numpy arrays, metadata and a JSON-safe ``summary()``.

* :func:`quasi_static_test`: beam A clamped, beam B's end gripped and driven axially with
  ``u(t) = u0 sin(2 pi f t)`` (0.02 Hz, 0.1 mm by default), solved with Exudyn's static solver
  one load step per sample (inertia is irrelevant at 0.02 Hz); machine force vs displacement
  and joint force vs slip.
* :func:`modal_analysis`: linearised modes with the joint at its stiffness ``KT`` and the
  closed-form prediction of the amplitude-dependent frequency and damping of a mode
  (single-mode equivalent linearisation with the joint's secant stiffness, paper eq. 24, and
  dissipation per cycle, paper eq. 17)::

      w(q)^2 = w_lin^2 - sum_i g_i^2 (KT_i - K_sec,i(|g_i| q))
      zeta(q) = sum_i D_i(|g_i| q) / (2 pi w(q)^2 q^2)

  where ``q`` is the mass-normalised modal amplitude and ``g_i`` the slip at contact point
  ``i`` per unit ``q``.
* :func:`free_decay`: released from rest in the first bending mode's shape at several
  levels, integrated with generalized-alpha at spectral radius 1 (no numerical damping);
  amplitude-dependent frequency and damping extracted cycle by cycle from the tip response,
  next to the prediction and to the same run with a linear joint of stiffness ``KT``.
* :func:`forced_response`: harmonic tip force at several levels, stepped through the first
  resonance with continuation; steady amplitude per frequency and the resonance peak.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (LoadCoordinate, LoadForceVector, MarkerNodeCoordinate,
                                  MarkerNodePosition, SensorNode, SensorObject)

from iwan_element import dissipation, secant_stiffness

from .jointed_beam import JointedBeamConfig, JointedBeamModel, build_jointed_beam

__all__ = ["QuasiStaticResult", "quasi_static_test", "ModalResult", "modal_analysis",
           "DecayRun", "FreeDecayResult", "free_decay", "decay_analysis",
           "ForcedResponseResult", "forced_response"]

log = logging.getLogger(__name__)
_OVT = exu.OutputVariableType


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


# ------------------------------------------------------------------ quasi-static test
@dataclass
class QuasiStaticResult:
    """Result of :func:`quasi_static_test` (SI units).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] of each load step.
    machine_displacement, machine_force : ndarray, shape (n,)
        Prescribed grip displacement [m] and the machine (reaction) force [N], tension > 0.
    joint_slip, joint_force : ndarray, shape (n_points, n)
        Tangential slip [m] and force [N] at each contact point.
    joint_dissipation : ndarray, shape (n_points, n)
        Energy dissipated by each point since the start [J].
    config : JointedBeamConfig
    metadata : dict
    """

    t: np.ndarray
    machine_displacement: np.ndarray
    machine_force: np.ndarray
    joint_slip: np.ndarray
    joint_force: np.ndarray
    joint_dissipation: np.ndarray
    config: JointedBeamConfig
    metadata: dict = field(default_factory=dict)

    @property
    def total_joint_force(self) -> np.ndarray:
        """Sum of the tangential forces of all contact points [N]."""
        return self.joint_force.sum(axis=0)

    @property
    def mean_slip(self) -> np.ndarray:
        """Mean slip of the contact points [m]."""
        return self.joint_slip.mean(axis=0)

    def last_cycle(self) -> np.ndarray:
        """Boolean mask of the samples of the last full cycle."""
        period = 1.0 / self.metadata["frequency"]
        return self.t >= self.t[-1] - period - 1e-9 * period

    def summary(self) -> dict:
        """JSON-safe summary of the last cycle."""
        m = self.last_cycle()
        s = self.joint_slip[:, m]
        return {
            "amplitude_m": self.metadata["amplitude"],
            "frequency_Hz": self.metadata["frequency"],
            "machine_force_amplitude_N": float(np.max(np.abs(self.machine_force[m]))),
            "joint_slip_amplitude_m": [float(x) for x in 0.5 * (s.max(axis=1) - s.min(axis=1))],
            "joint_dissipation_per_cycle_J": [
                float(d[m][-1] - d[m][0]) for d in self.joint_dissipation],
            "secant_stiffness_machine_N_per_m": float(
                np.ptp(self.machine_force[m]) / np.ptp(self.machine_displacement[m])),
        }


def quasi_static_test(config: JointedBeamConfig | None = None, *, amplitude: float = 1e-4,
                      frequency: float = 0.02, cycles: int = 3, steps_per_cycle: int = 200,
                      joint_factory=None) -> QuasiStaticResult:
    """The paper's quasi-static test on the jointed beam (machine drives beam B's end axially).

    Parameters
    ----------
    config : JointedBeamConfig, optional
        Its ``boundary`` is set to ``"clamped-driven"``.
    amplitude : float, keyword-only
        Grip displacement amplitude ``u0`` [m] (default 0.1 mm).
    frequency : float, keyword-only
        [Hz] (default 0.02 Hz, the paper's).
    cycles, steps_per_cycle : int, keyword-only
        Number of cycles and static load steps per cycle.
    joint_factory : callable, optional, keyword-only
        Passed to :func:`build_jointed_beam`.

    Returns
    -------
    QuasiStaticResult
    """
    cfg = (config or JointedBeamConfig()).replace(boundary="clamped-driven")
    if not (math.isfinite(amplitude) and amplitude > 0):
        raise ValueError(f"amplitude must be > 0 [m], got {amplitude!r}")
    if not (math.isfinite(frequency) and frequency > 0):
        raise ValueError(f"frequency must be > 0 [Hz], got {frequency!r}")
    cycles = _check_count("cycles", cycles, 1)
    steps_per_cycle = _check_count("steps_per_cycle", steps_per_cycle, 8)
    w = 2.0 * math.pi * frequency

    def drive(t):
        return amplitude * math.sin(w * t)

    model = build_jointed_beam(cfg, joint_factory=joint_factory, drive_function=drive)
    mbs = model.mbs
    s_force = mbs.AddSensor(SensorObject(objectNumber=model.drive, outputVariableType=_OVT.Force,
                                         storeInternal=True))
    mbs.Assemble()
    n = cycles * steps_per_cycle
    duration = cycles / frequency
    sim = _settings(force_scale=cfg.joint.Fs, static=True)
    sim.staticSolver.numberOfLoadSteps = n
    sim.staticSolver.loadStepDuration = duration
    sim.solution.sensors.writePeriod = duration / n
    mbs.SolveStatic(sim)
    data = mbs.GetSensorStoredData(s_force)
    t = np.array(model.connectors[0].time) if model.connectors else data[:, 0]
    # the static solver reports the constraint force on the beam: tension on the grip is +
    F_machine = np.interp(t, data[:, 0], data[:, 1])
    return QuasiStaticResult(
        t=t, machine_displacement=amplitude * np.sin(w * t), machine_force=F_machine,
        joint_slip=np.array([c.slip_history for c in model.connectors]),
        joint_force=np.array([c.force_history for c in model.connectors]),
        joint_dissipation=np.array([c.dissipated_energy_history for c in model.connectors]),
        config=cfg, metadata={"amplitude": amplitude, "frequency": frequency, "cycles": cycles,
                              "steps_per_cycle": steps_per_cycle, "solver": "SolveStatic"})


# ------------------------------------------------------------------ modes and prediction
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


# ------------------------------------------------------------------ free decay
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


def _bending_force_scale(cfg: JointedBeamConfig, tip: float) -> float:
    """Static tip force of a cantilever of the assembly's length deflected by ``tip`` [N]."""
    return 3.0 * cfg.EI * tip / cfg.total_length ** 3


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
    # static load pattern w1^2 M phi1: its linear static deflection is the first mode exactly
    pattern = (2 * math.pi * modal.frequencies[0]) ** 2 * (modal.mass_matrix @ modal.shapes[:, 0])
    pattern *= level / modal.tip[0]
    loads = []
    clamped = set(model.clamped_coordinates)
    for node in model.nodes_a + model.nodes_b:
        i0 = mbs.GetNodeODE2Index(node)
        for c in range(4):
            value = float(pattern[i0 + c])
            if value != 0.0 and i0 + c not in clamped:
                mk = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
                loads.append((mbs.AddLoad(LoadCoordinate(markerNumber=mk, load=value)), value))
    ramp = {"T": 0.0, "active": False, "done": False}

    def pre_step(mbs_, t):
        if not ramp["active"] or ramp["done"]:       # static pre-load, or load already gone
            return True
        f = 0.5 * (1.0 + math.cos(math.pi * t / ramp["T"])) if t < ramp["T"] else 0.0
        for item, value in loads:
            mbs_.SetLoadParameter(item, "load", f * value)
        if f == 0.0:
            ramp["done"] = True
        return True

    mbs.SetPreStepUserFunction(pre_step)
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
    ramp["T"] = max(release_time, 1e-12)
    ramp["active"] = True
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


# ------------------------------------------------------------------ forced response
@dataclass
class ForcedResponseResult:
    """Stepped-sine response: ``amplitude[i, j]`` is the steady tip amplitude [m] at force
    level ``force_levels[i]`` [N] and frequency ``frequencies[j]`` [Hz]."""

    force_levels: np.ndarray
    frequencies: np.ndarray
    amplitude: np.ndarray
    config: JointedBeamConfig
    metadata: dict = field(default_factory=dict)

    def peaks(self):
        """(peak frequency [Hz], peak amplitude [m]) per force level."""
        j = np.argmax(self.amplitude, axis=1)
        return self.frequencies[j], self.amplitude[np.arange(len(j)), j]

    def summary(self) -> dict:
        fp, ap = self.peaks()
        return {"force_levels_N": self.force_levels.tolist(), "peak_frequency_Hz": fp.tolist(),
                "peak_tip_amplitude_m": ap.tolist(), "frequencies_Hz": self.frequencies.tolist()}


def forced_response(config: JointedBeamConfig | None = None, *, force_levels=(0.5, 2.0, 8.0),
                    frequencies=None, settle_cycles: int = 60, measure_cycles: int = 10,
                    steps_per_period: int = 60, joint_factory=None, progress=None) -> ForcedResponseResult:
    """Harmonic transverse tip force ``F sin(2 pi f t)`` stepped through the first resonance.

    At each frequency the run continues from the previous state for ``settle_cycles`` and
    the tip amplitude is taken as half the peak-to-peak over the following
    ``measure_cycles``. Light joint damping means slow settling: raise ``settle_cycles`` for
    a sharper peak.

    Parameters
    ----------
    config : JointedBeamConfig, optional
        Its ``boundary`` is set to ``"clamped-free"``; for a response that settles give the
        beams some material damping (``rayleigh_beta``).
    force_levels : sequence of float, keyword-only
        Force amplitudes [N], ``> 0``.
    frequencies : array_like, optional, keyword-only
        [Hz], ``> 0``; default 15 frequencies from -3 % to +1 % of the linearised first mode.
    settle_cycles, measure_cycles : int, keyword-only
        Cycles run before measuring, and measured, at each frequency (``>= 1``).
    steps_per_period : int, keyword-only
        Time steps per excitation period (``>= 8``).
    joint_factory : callable, optional, keyword-only
        Joint element per contact point (default exact Iwan).
    progress : callable, optional, keyword-only
        ``progress(message)`` is called at each frequency.

    Returns
    -------
    ForcedResponseResult
    """
    cfg = (config or JointedBeamConfig()).replace(boundary="clamped-free")
    levels = _check_positive("force_levels", force_levels)
    if frequencies is not None:
        frequencies = _check_positive("frequencies", frequencies)
    settle_cycles = _check_count("settle_cycles", settle_cycles, 1)
    measure_cycles = _check_count("measure_cycles", measure_cycles, 1)
    steps_per_period = _check_count("steps_per_period", steps_per_period, 8)
    modal = modal_analysis(cfg, n_modes=1)
    f_lin = modal.frequencies[0]
    freqs = np.linspace(0.97, 1.01, 15) * f_lin if frequencies is None else frequencies
    amp = np.zeros((len(levels), len(freqs)))
    for i, F0 in enumerate(levels):
        model = build_jointed_beam(cfg, joint_factory=joint_factory)
        mbs = model.mbs
        state = {"w": 2 * math.pi * freqs[0], "t0": 0.0, "phase": 0.0}

        def load(mbs_, t, load_vector):
            return [0.0, F0 * math.sin(state["phase"] + state["w"] * (t - state["t0"])), 0.0]

        mk = mbs.AddMarker(MarkerNodePosition(nodeNumber=model.tip_node))
        mbs.AddLoad(LoadForceVector(markerNumber=mk, loadVector=[0, 0, 0], loadVectorUserFunction=load))
        s_tip = mbs.AddSensor(SensorNode(nodeNumber=model.tip_node, outputVariableType=_OVT.Displacement,
                                         storeInternal=True))
        mbs.Assemble()
        sim = _settings(force_scale=_bending_force_scale(cfg, 1e-3))
        sim.timeIntegration.generalizedAlpha.spectralRadius = 0.98
        t_now = 0.0
        for j, f in enumerate(freqs):
            if progress is not None:
                progress(f"forced response, F = {F0:g} N, f = {f:.2f} Hz")
            # keep the force continuous: new phase at the switch time
            state["phase"] = state["phase"] + state["w"] * (t_now - state["t0"])
            state["w"], state["t0"] = 2 * math.pi * f, t_now
            n = (settle_cycles + measure_cycles) * steps_per_period
            h = 1.0 / (f * steps_per_period)
            ti = sim.timeIntegration
            ti.startTime = t_now
            ti.endTime = t_now + n * h
            ti.numberOfSteps = n
            sim.solution.sensors.writePeriod = h
            if j > 0:
                ti.initialStepSize = h
            mbs.SolveDynamic(sim, updateInitialValues=True)
            d = mbs.GetSensorStoredData(s_tip)
            keep = d[:, 0] >= t_now + settle_cycles * steps_per_period * h - 1e-12
            amp[i, j] = 0.5 * np.ptp(d[keep, 2])
            t_now = ti.endTime
    return ForcedResponseResult(force_levels=levels, frequencies=freqs, amplitude=amp, config=cfg,
                                metadata={"settle_cycles": settle_cycles,
                                          "measure_cycles": measure_cycles,
                                          "steps_per_period": steps_per_period,
                                          "linear_frequency_Hz": float(f_lin)})
