"""Stepped-sine forced response of the jointed beam (see :mod:`.scenarios`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.itemInterface import LoadForceVector, MarkerNodePosition, SensorNode

from ._linear_modes import modal_analysis
from ._scenario_settings import _bending_force_scale, _check_count, _check_positive, _settings
from .jointed_beam import JointedBeamConfig, build_jointed_beam

__all__ = ["ForcedResponseResult", "forced_response"]

_OVT = exu.OutputVariableType

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


def _sweep_level(cfg, F0, freqs, settle_cycles, measure_cycles, steps_per_period,
                 joint_factory, progress) -> np.ndarray:
    """Steady tip amplitude [m] at each frequency of ``freqs`` for one force level ``F0`` [N],
    each frequency continuing from the state the previous one left (force phase continuous)."""
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
    amp = np.zeros(len(freqs))
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
        amp[j] = 0.5 * np.ptp(d[keep, 2])
        t_now = ti.endTime
    return amp


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
    amp = np.array([_sweep_level(cfg, float(F0), freqs, settle_cycles, measure_cycles,
                                 steps_per_period, joint_factory, progress) for F0 in levels])
    return ForcedResponseResult(force_levels=levels, frequencies=freqs, amplitude=amp, config=cfg,
                                metadata={"settle_cycles": settle_cycles,
                                          "measure_cycles": measure_cycles,
                                          "steps_per_period": steps_per_period,
                                          "linear_frequency_Hz": float(f_lin)})
