"""The result of the specimen's transient ring-down (:func:`~iwan_element.models.ringdown`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from iwan_element import AmplitudeCurve, amplitude_curve
from iwan_element.base.result_shape import ResultShape, column, panels
from iwan_element.base.serialize import json_safe
from iwan_element.base.validation import plain_number

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["RingdownResult", "ENERGY_TOL", "with_energy_warning", "decay_curve"]

#: Largest relative energy-balance error a ring-down may show and still be a success.
ENERGY_TOL = 1e-3


@dataclass(frozen=True)
class RingdownResult(ResultShape):
    """Result of :func:`~iwan_element.models.ringdown`, with the package's result shape
    (``report``, ``to_dict``, ``warnings``, ``success``, ``plot(ax=None)`` on three panels:
    the modes' responses against time, then each decay's frequency and damping against
    amplitude).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] from the release.
    sensor : ndarray, shape (n,)
        Transverse displacement at the specimen's sensor point [m] (all modes; on a solid
        specimen the section's z displacement there, as its sensor is read).
    modal : ndarray, shape (n,)
        The first (lowest) mode's contribution at the sensor, ``(S phi) q(t)`` [m].
    curve : AmplitudeCurve
        The first mode's frequency and damping against amplitude (``method="ringdown"``).
    energy : dict of ndarray
        ``t``, ``kinetic``, ``strain``, ``springs``, ``joint_stored``, ``joint_dissipated``,
        ``floor_dissipated``, ``effect_stored``, ``effect_dissipated``, ``input_work`` [J]
        (filled when ``record_energy``; the effect terms stay empty without effects, the
        input work, the impact's trapezoidal work ``sum (F_n + F_n+1) dy / 2`` at its
        point, without an impact).
        ``floor_dissipated`` is the work of the floor's modal damping matrix ``C``,
        ``v^T C v`` integrated with the step's mean velocity (the trapezoidal rule's own
        damping work); zero without a floor.
    initial_energy : float
        Elastic energy at the release [J] (beams, springs, joints, effects).
    wall_time : float
        Seconds spent in ``SolveDynamic``.
    metadata : dict
        ``h`` [s], ``steps``, ``extra_steps`` (how many more steps the solver took, cutting
        them where the interface slips hard; the records are then interpolated onto the
        nominal step), ``modes``, ``amplitude`` ({mode: release amplitude at the sensor
        [m]}), ``floor`` ({mode: linear damping ratio}), ``n_points``, ``effects``,
        ``kinetic_at_release`` [J] and ``joint_quadrature_error`` [-]: with
        ``record_energy``, the joints' exact work minus the trapezoidal work of their
        recorded forces, over the release energy; the time integrator's share of the energy
        balance (it converges with ``steps_per_period``), else None; ``overflow_steps``:
        steps that closed more slip loops than the compiled interface law holds (their
        joint forces not exact; warned); ``newton_iterations`` and ``jacobians``: Exudyn's
        Newton iterations and Jacobians over the run; ``tangential`` (``"iwan"``, or
        ``"linear"``: springs at the stuck stiffness); a solid specimen's run also gives
        ``n_coordinates`` (the reduced coordinates integrated).
    modes : tuple of int
        The elastic modes released, ascending (``(mode,)`` for a single-mode call).
    curves : tuple of AmplitudeCurve
        One decay curve per mode of ``modes`` from its modal filter (``curves[0] is
        curve``).
    modal_responses : ndarray, shape (n_modes, n)
        Each mode's contribution at the specimen's sensor point [m] (``modal_responses[0]``
        is ``modal``).
    sensor_positions : ndarray, shape (n_sensors,)
        Positions [m] along the beams' axis where the response is read (default: the
        specimen's ``sensor_position``).
    sensor_displacement, sensor_acceleration : ndarray, shape (n_sensors, n)
        Transverse displacement [m] and acceleration [m/s^2] there (all modes); the
        acceleration by central second differences of the displacement (relative error
        ``(w h)^2 / 12``, 8e-4 at 64 steps per period).
    warnings : tuple of str
        The decay curves' warnings (prefixed by their mode in a multi-mode run), and an
        energy balance off by more than :data:`ENERGY_TOL` (when recorded).
    """

    plot_panels = 3

    t: np.ndarray
    sensor: np.ndarray
    modal: np.ndarray
    curve: AmplitudeCurve
    energy: dict
    initial_energy: float
    wall_time: float
    metadata: dict = field(default_factory=dict)
    modes: tuple = (1,)
    curves: tuple = ()
    modal_responses: np.ndarray | None = None
    sensor_positions: np.ndarray | None = None
    sensor_displacement: np.ndarray | None = None
    sensor_acceleration: np.ndarray | None = None

    def sensor_curve(
        self, sensor: int, band, *, quantity: str = "acceleration", n_periods: float | None = None
    ) -> AmplitudeCurve:
        """The decay curve of the mode in ``band`` [Hz] read from sensor ``sensor`` (an index
        of :attr:`sensor_positions`) the way a measured record is read
        (:func:`iwan_element.amplitude_curve` on its ``quantity``, "acceleration" or
        "displacement"; amplitudes are displacements [m]), the trapezoidal rule's period
        error removed, at the record's own step: a decimated record (scipy.signal.decimate,
        FIR, zero phase) put its filter's end effects into the last window (a 0.6 s
        Brake-Reuss ring-down read 1.30e-3 there for 1.81e-3), which the curve's own trimming
        does not see. ``n_periods``: fixed windows (default: windows that follow the
        decay).
        """
        if quantity not in ("acceleration", "displacement"):
            raise ValueError(f"quantity must be 'acceleration' or 'displacement', got {quantity!r}")
        positions = self.sensor_positions
        records = (
            self.sensor_acceleration if quantity == "acceleration" else self.sensor_displacement
        )
        if positions is None or records is None:
            raise ValueError(
                "sensor_curve needs the result's sensor records (sensor_positions, "
                f"sensor_{quantity}), which this result does not hold"
            )
        sensor = plain_number(sensor)
        if (
            isinstance(sensor, bool)
            or not isinstance(sensor, int)
            or not 0 <= sensor < len(positions)
        ):
            raise ValueError(f"sensor must be an index below {len(positions)}, got {sensor!r}")
        lo, hi = (float(b) for b in band)
        h = self.metadata["h"]
        y = records[sensor]
        return decay_curve(
            self.t,
            y,
            h,
            0.5 * (lo + hi),
            n_periods,
            band=(lo, hi),
            quantity=quantity,
            notes=f"sensor at {positions[sensor]:.4g} m",
        )

    def mode_curve(self, mode: int) -> AmplitudeCurve:
        """The decay curve of elastic mode ``mode`` (one of :attr:`modes`)."""
        if mode not in self.modes:
            raise ValueError(f"mode must be one of the released modes {self.modes}, got {mode!r}")
        return self.curves[self.modes.index(mode)]

    @property
    def max_energy_error(self) -> float | None:
        """Largest relative energy-balance error [-], or None when energy was not recorded."""
        return float(np.max(np.abs(self.energy_error()))) if len(self.energy["t"]) else None

    @property
    def success(self) -> bool:
        """True when every mode's decay gave at least three curve points and the energy
        balance (when recorded) closes to :data:`ENERGY_TOL`.
        """
        err = self.max_energy_error
        return bool(
            all(len(c) >= 3 for c in self.curves or (self.curve,))
            and (err is None or err <= ENERGY_TOL)
        )

    def report(self) -> str:
        """Human-readable account."""
        m = self.metadata
        lines = [
            self.verdict(),
            f"Exudyn ring-down: {m['steps']} steps of {m['h']:.4g} s "
            f"({self.t[-1]:.4g} s, {self.wall_time:.3g} s wall), {m['n_points']} contact "
            f"points, mode(s) {', '.join(map(str, self.modes))}"
            + (f", effects {' + '.join(m['effects'])}" if m["effects"] else ""),
        ]
        for mode, c in zip(self.modes, self.curves or (self.curve,)):
            if len(c):
                lines.append(
                    f"  mode {mode}: {len(c)} points, {c.amplitude.min():.3g}-"
                    f"{c.amplitude.max():.3g} m, f {c.frequency.min():.6g}-"
                    f"{c.frequency.max():.6g} Hz, zeta {100 * c.damping_ratio.min():.3g}-"
                    f"{100 * c.damping_ratio.max():.3g} %"
                )
        err = self.max_energy_error
        lines.append(
            "  energy balance: "
            + (
                "not recorded"
                if err is None
                else f"max relative error {err:.2e}; the joints' "
                "trapezoidal work is off their exact work by "
                f"{m['joint_quadrature_error']:.2e}"
            )
        )
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe summary: the curves, the energy balance and the run's metadata."""
        curves = self.curves or (self.curve,)
        return json_safe(
            {
                "curve": self.curve.to_dict(),
                "duration": float(self.t[-1]),
                "modes": list(self.modes),
                "curves": {str(k): c.to_dict() for k, c in zip(self.modes, curves)},
                "sensor_positions": self.sensor_positions,
                "initial_energy": self.initial_energy,
                "max_energy_error": self.max_energy_error,
                "wall_time": self.wall_time,
                "metadata": self.metadata,
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def _tables(self) -> list:
        """The modes' decay curves (the main table: one row per curve point, by mode), the
        time series at the sensor (all modes, then each mode's share), then the run.
        """
        curves = self.curves or (self.curve,)
        points = [
            (int(mode), float(a), float(f), float(z))
            for mode, c in zip(self.modes, curves)
            for a, f, z in zip(c.amplitude, c.frequency, c.damping_ratio)
        ]
        resp = self.modal_responses if self.modal_responses is not None else self.modal[None]
        series = (
            (column("t", "s"), column("sensor", "m"))
            + tuple(column(f"mode {m}", "m") for m in self.modes),
            [tuple(map(float, r)) for r in zip(self.t, self.sensor, *resp)],
        )
        err = self.max_energy_error
        where = () if self.sensor_positions is None else np.atleast_1d(self.sensor_positions)
        run = [
            (column("duration", "s"), float(self.t[-1])),
            (column("initial energy", "J"), float(self.initial_energy)),
            (column("largest energy error", "-"), err),
            (column("wall time", "s"), float(self.wall_time)),
            (
                column("sensor positions", "m"),
                ", ".join(f"{x:.4g}" for x in where),
            ),
        ]
        return [
            (
                "curves",
                (
                    "mode",
                    column("amplitude", "m"),
                    column("frequency", "Hz"),
                    column("damping_ratio", "-"),
                ),
                points,
            ),
            ("time series", *series),
            ("run", ("quantity", "value"), run),
        ]

    def plot(self, ax=None) -> list[Artist]:
        """Each mode's response at the sensor against time, then the decays' frequency and
        damping against amplitude, on ``ax = (ax_t, ax_f, ax_z)`` (a new figure if
        ``None``; :mod:`iwan_element.base.result_shape`); returns the artists.
        """
        ax_t, ax_f, ax_z = panels(ax, 3, figsize=(6, 8))
        resp = self.modal_responses if self.modal_responses is not None else self.modal[None]
        arts = []
        for mode, y, c in zip(self.modes, resp, self.curves or (self.curve,)):
            arts += ax_t.plot(self.t, y, lw=0.6, label=f"mode {mode} at the sensor")
            arts += c.plot((ax_f, ax_z), label=f"ring-down, mode {mode}")
        ax_t.set_xlabel("time [s]")
        ax_t.set_ylabel("displacement at the sensor [m]")
        ax_t.legend(fontsize=8, loc="upper right")
        f = np.concatenate([c.frequency for c in self.curves or (self.curve,)])
        if f.size and np.nanmax(f) > 3 * np.nanmin(f):  # modes far apart (21 and 133 Hz)
            ax_f.set_yscale("log")
        return arts

    def energy_error(self) -> np.ndarray:
        """Relative energy balance error over time (needs ``record_energy``):
        ``(kinetic + strain + springs + stored + dissipated) / E0 - 1``, the dissipated
        energy of the joints, the damping floor and the effects; with an impact,
        ``(... - E0 - W_in) / (E0 + W_in,end)`` (``W_in`` its input work).
        """
        e = self.energy
        total = (
            e["kinetic"] + e["strain"] + e["springs"] + e["joint_stored"] + e["joint_dissipated"]
        )
        total = total + e["floor_dissipated"]
        if e.get("effect_stored") is not None and len(e["effect_stored"]):
            total = total + e["effect_stored"] + e["effect_dissipated"]
        w_in = e.get("input_work")
        if w_in is None or not len(w_in):
            return total / self.initial_energy - 1.0
        return (total - self.initial_energy - w_in) / (self.initial_energy + w_in[-1])


def with_energy_warning(out: RingdownResult) -> RingdownResult:
    """The result with a warning when its recorded energy balance is off by more than
    :data:`ENERGY_TOL`.
    """
    err = out.max_energy_error
    if err is not None and err > ENERGY_TOL:
        out = replace(
            out,
            warnings=out.warnings
            + (
                f"the energy balance is off by {err:.2g} of the release energy (more than "
                f"{ENERGY_TOL:g}; the time integrator's quadrature of the joint forces "
                f"accounts for {out.metadata['joint_quadrature_error']:.2g}): "
                "refine steps_per_period",
            ),
        )
    return out


def decay_curve(
    t, y, h, f0, n_periods, *, notes, band=None, quantity: str = "displacement"
) -> AmplitudeCurve:
    """Frequency and damping of a computed decay by :func:`iwan_element.amplitude_curve`
    (``quantity`` of the record ``y`` at times ``t`` [s]; band ``(0.5, 1.5) f0`` around the
    stuck frequency ``f0`` [Hz] unless ``band`` is given; windows of ``n_periods``, or
    following the decay when None; no second extraction: the record is noise-free), the
    trapezoidal rule's period error of the step ``h`` [s] removed
    (``w_true = tan(w h / 2) 2 / h``).
    """
    band = (0.5 * f0, 1.5 * f0) if band is None else band
    c = amplitude_curve(t, y, quantity=quantity, band=band, n_periods=n_periods, compare=False)
    f_true = np.tan(math.pi * c.frequency * h) / (math.pi * h)
    return replace(
        c, frequency=f_true, method="ringdown", notes=f"{notes}; {c.notes}" if c.notes else notes
    )
