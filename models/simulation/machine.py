"""The quasi-static test of a specimen's joint: beam A clamped, beam B's end in a machine grip.

The grip holds beam B's far end transversely and in rotation and drives it axially with
``u(t) = u0 sin(2 pi f t)`` (0.02 Hz and 0.1 mm by default, the test of Segalman's four-
parameter joint in the seed paper's machine); Exudyn's static solver takes one load step
per sample (inertia is irrelevant at 0.02 Hz), so every contact point's Iwan element is
loaded through its virgin curve and then its Masing branches. The machine force is the
grip's constraint force; the lap passes it on through the contact points' tangential forces,
so in axial equilibrium the machine force equals their sum (``docs/beam_tests.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import exudyn as exu
import numpy as np
from exudyn.itemInterface import SensorObject

from iwan_element import dissipation
from iwan_element.base.result_shape import ResultShape, column, panels
from iwan_element.base.serialize import json_safe
from iwan_element.base.validation import check_int, check_scalar

from ..reduced.dispatch import linear_system
from ..specimens.specimen import Specimen
from .host import build_host
from .solver import solver_settings

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["QuasiStaticResult", "quasi_static_test"]

#: Largest relative gap, on the last cycle, between each contact point's loop area and its
#: closed-form dissipation at the cycle's slip amplitude for a success.
LOOP_TOL = 1e-2


@dataclass(frozen=True)
class QuasiStaticResult(ResultShape):
    """Result of :func:`quasi_static_test` (SI units), with the package's result shape.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] of each load step.
    machine_displacement, machine_force : ndarray, shape (n,)
        Prescribed grip displacement [m] and the machine force [N] (tension > 0).
    slip, force : ndarray, shape (n, n_points)
        Tangential slip [m] and force [N] of each contact point.
    dissipated : ndarray, shape (n,)
        Energy dissipated by the interface since the start [J].
    specimen : Specimen
        The specimen as tested (``boundary="clamped-driven"``).
    metadata : dict
        ``amplitude`` [m], ``frequency`` [Hz], ``cycles``, ``steps_per_cycle``.
    warnings : tuple of str
    """

    COLUMNS = {
        "amplitude_m": ("grip amplitude", "m"),
        "frequency_Hz": ("frequency", "Hz"),
        "machine_force_amplitude_N": ("machine force amplitude", "N"),
        "mean_slip_amplitude_m": ("mean slip amplitude", "m"),
        "dissipation_per_cycle_J": ("dissipation per cycle", "J"),
        "machine_secant_stiffness_N_per_m": ("machine secant stiffness", "N/m"),
    }

    plot_panels = 2

    t: np.ndarray
    machine_displacement: np.ndarray
    machine_force: np.ndarray
    slip: np.ndarray
    force: np.ndarray
    dissipated: np.ndarray
    specimen: Specimen
    metadata: dict = field(default_factory=dict)

    @property
    def joint_force(self) -> np.ndarray:
        """Sum of the contact points' tangential forces [N], shape (n,)."""
        return self.force.sum(axis=1)

    @property
    def mean_slip(self) -> np.ndarray:
        """Mean slip of the contact points [m], shape (n,)."""
        return self.slip.mean(axis=1)

    def last_cycle(self) -> np.ndarray:
        """Boolean mask of the samples of the last full cycle."""
        period = 1.0 / self.metadata["frequency"]
        return self.t >= self.t[-1] - period * (1 + 1e-9)

    def loop_check(self) -> tuple[np.ndarray, np.ndarray]:
        """Per contact point, the last cycle's loop area (trapezoid of its force against its
        slip) and the closed-form dissipation per cycle at the cycle's slip amplitude [J].
        """
        m = self.last_cycle()
        s, F = self.slip[m], self.force[m]
        area = np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(s, axis=0), axis=0)
        amp = 0.5 * (s.max(axis=0) - s.min(axis=0))
        from ..reduced.dispatch import contact_points

        pts = contact_points(self.specimen)
        return area, np.array([dissipation(a, p) for a, p in zip(amp, pts.params)])

    @property
    def success(self) -> bool:
        """True when every point's loop area matches its closed-form dissipation to
        :data:`LOOP_TOL` of the interface's total.
        """
        area, closed = self.loop_check()
        return bool(np.max(np.abs(area - closed)) <= LOOP_TOL * max(closed.sum(), 1e-300))

    def _tables(self) -> list:
        """The test's time series (the main table: grip and machine force, the joint's
        mean slip and summed force, the dissipated energy), then the last cycle in numbers.
        """
        cols = (
            column("t", "s"),
            column("machine displacement", "m"),
            column("machine force", "N"),
            column("mean slip", "m"),
            column("joint force", "N"),
            column("dissipated", "J"),
        )
        arrays = (
            self.t,
            self.machine_displacement,
            self.machine_force,
            self.mean_slip,
            self.joint_force,
            self.dissipated,
        )
        rows = [tuple(map(float, r)) for r in zip(*arrays)]
        last = self._quantity_rows(self.summary().items())
        return [("time series", cols, rows), ("last cycle", ("quantity", "value"), last)]

    def summary(self) -> dict:
        """The last cycle in numbers (JSON-safe)."""
        m = self.last_cycle()
        d = self.dissipated[m]
        return json_safe(
            {
                "amplitude_m": self.metadata["amplitude"],
                "frequency_Hz": self.metadata["frequency"],
                "machine_force_amplitude_N": float(np.max(np.abs(self.machine_force[m]))),
                "mean_slip_amplitude_m": float(0.5 * np.ptp(self.mean_slip[m])),
                "dissipation_per_cycle_J": float(d[-1] - d[0]),
                "machine_secant_stiffness_N_per_m": float(
                    np.ptp(self.machine_force[m]) / np.ptp(self.machine_displacement[m])
                ),
            }
        )

    def report(self) -> str:
        """Human-readable account of the last cycle."""
        s = self.summary()
        area, closed = self.loop_check()
        lines = [
            self.verdict(),
            f"quasi-static test of {self.specimen.name}: grip {s['amplitude_m']:.4g} m at "
            f"{s['frequency_Hz']:g} Hz, {self.metadata['cycles']} cycle(s) of "
            f"{self.metadata['steps_per_cycle']} load steps",
            f"  machine force amplitude {s['machine_force_amplitude_N']:.4g} N, mean slip "
            f"amplitude {s['mean_slip_amplitude_m']:.4g} m, dissipation "
            f"{s['dissipation_per_cycle_J']:.4g} J per cycle",
            f"  loop areas vs closed forms: largest gap {np.max(np.abs(area - closed)):.3g} J",
        ]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def to_dict(self) -> dict:
        """JSON-safe summary, metadata, success and warnings."""
        return json_safe(
            {
                **self.summary(),
                "metadata": self.metadata,
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """The joint's loop (summed force against mean slip) and the machine's loop (force
        against grip displacement) on ``ax = (ax_joint, ax_machine)``; returns the artists.
        """
        a1, a2 = panels(ax, 2, figsize=(6, 7))
        arts = a1.plot(self.mean_slip, self.joint_force, lw=1.0)
        a1.set(xlabel="mean slip [m]", ylabel="joint force [N]")
        arts += a2.plot(self.machine_displacement, self.machine_force, lw=1.0)
        a2.set(xlabel="machine displacement [m]", ylabel="machine force [N]")
        return arts


def quasi_static_test(
    specimen: Specimen,
    *,
    amplitude: float = 1e-4,
    frequency: float = 0.02,
    cycles: int = 3,
    steps_per_cycle: int = 200,
) -> QuasiStaticResult:
    """Drive beam B's end axially in the machine grip, beam A clamped (module docstring).

    Parameters
    ----------
    specimen : Specimen
        Tested with ``boundary="clamped-driven"`` whatever its own boundary.
    amplitude : float, keyword-only
        Grip displacement amplitude ``u0`` [m], in (0, 0.1 beam_length].
    frequency : float, keyword-only
        [Hz], > 0 (only sets the time axis: the solution is static).
    cycles : int, keyword-only
        Number of cycles, >= 1.
    steps_per_cycle : int, keyword-only
        Static load steps per cycle, >= 8.

    Returns
    -------
    QuasiStaticResult
        ``success`` and ``warnings`` say whether each contact point's last loop matches its
        closed-form dissipation.
    """
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    s = specimen.replace(boundary="clamped-driven")
    u0 = check_scalar("amplitude", amplitude, low=0.0, high=0.1 * s.beam_length, low_open=True)
    f = check_scalar("frequency", frequency, low=0.0, low_open=True)
    cycles = check_int("cycles", cycles, 1)
    steps = check_int("steps_per_cycle", steps_per_cycle, 8)
    w = 2.0 * math.pi * f
    model = build_host(s, ports={"grip": linear_system(s).drive}, floor=False, assemble=False)
    mbs = model.mbs
    grip = model.prescribe_port("grip", lambda t: u0 * math.sin(w * t))
    sensor = mbs.AddSensor(
        SensorObject(
            objectNumber=grip, storeInternal=True, outputVariableType=exu.OutputVariableType.Force
        )
    )
    mbs.Assemble()
    n, duration = cycles * steps, cycles / f
    sim = solver_settings(force_scale=float(model.points.Fs.sum()), static=True)
    sim.staticSolver.numberOfLoadSteps = n
    sim.staticSolver.loadStepDuration = duration
    sim.solution.sensors.writePeriod = duration / n
    mbs.SolveStatic(sim)
    iface = model.interface
    assert iface is not None  # built with the Iwan elements (tangential="iwan")
    rec = iface.records()
    t = np.asarray(rec["time"])
    data = mbs.GetSensorStoredData(sensor)
    out = QuasiStaticResult(
        t=t,
        machine_displacement=u0 * np.sin(w * t),
        machine_force=np.interp(t, data[:, 0], data[:, 1]),
        slip=np.asarray(rec["slip"]),
        force=np.asarray(rec["force"]),
        dissipated=np.asarray(iface.dissipated_energy_history),
        specimen=s,
        metadata={"amplitude": u0, "frequency": f, "cycles": cycles, "steps_per_cycle": steps},
    )
    if not out.success:
        area, closed = out.loop_check()
        out = replace(
            out,
            warnings=out.warnings
            + (
                f"a contact point's last loop differs from its closed-form dissipation by "
                f"{np.max(np.abs(area - closed)):.3g} J (more than {LOOP_TOL:g} of the "
                f"interface's {closed.sum():.3g} J): give more steps_per_cycle",
            ),
        )
    return out
