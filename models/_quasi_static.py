"""The paper's quasi-static test on the jointed beam (see :mod:`.scenarios`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import exudyn as exu
import numpy as np
from exudyn.itemInterface import SensorObject

from ._scenario_settings import _check_count, _settings
from .jointed_beam import JointedBeamConfig, build_jointed_beam

__all__ = ["QuasiStaticResult", "quasi_static_test"]

_OVT = exu.OutputVariableType

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
