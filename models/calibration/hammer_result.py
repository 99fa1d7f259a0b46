"""The result of a hammer test predicted from one mode (:class:`HammerPrediction`, returned
by :func:`~iwan_element.models.calibration.predict_hammer_test`): the calibration, the
release, the multi-mode ring-down and every predicted curve against the measured one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from iwan_element.base.result_shape import ResultShape, column, panels, table_lines
from iwan_element.base.serialize import json_safe

from ..simulation.coupling import plot_curve_pairs
from ..simulation.ringdown_result import RingdownResult
from ..simulation.solver import MAX_STEPS
from ..simulation.transient import ringdown
from ..updating.result import LinearUpdateResult
from .vibration import CalibrationResult

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["HammerPrediction"]


@dataclass(frozen=True)
class HammerPrediction(ResultShape):
    """Result of :func:`~iwan_element.models.calibration.predict_hammer_test`.

    Attributes
    ----------
    calibration : CalibrationResult
        The joint from the calibration mode, the other modes' floors.
    calibration_mode : int
    calibration_sensor : str
        The record at the specimen's sensor position.
    bands : dict
        ``{mode: (low, high)}`` [Hz].
    release : dict
        ``{mode: X}`` [m] at the calibration sensor, ``release_time`` after the impact.
    ringdown : RingdownResult
        The multi-mode ring-down of the calibrated specimen.
    measured, predicted : dict
        ``{(mode, sensor name): AmplitudeCurve}``.
    errors : dict
        ``{(mode, sensor name): compare_curves(predicted, measured)}``.
    ratios : dict
        ``{(mode, sensor name): (measured, predicted)}``: the mode's amplitude at that sensor
        over the calibration sensor's.
    success : bool
        The linear update (when made) and the calibration are usable and every predicted
        curve overlaps its measured one in at least 3 amplitudes.
    update : LinearUpdateResult or None
        The linear update on the modes' low-amplitude frequencies (``None``: not made).
    sensors : tuple of (str, float)
        Each record's name and position [m] along the beam, in the ring-down's order.
    calibration_periods : float
        Window of the calibration mode's curves in its periods.
    warnings : tuple of str
    """

    plot_panels = 2

    calibration: CalibrationResult
    calibration_mode: int
    calibration_sensor: str
    bands: dict
    release: dict
    ringdown: RingdownResult
    measured: dict
    predicted: dict
    errors: dict
    ratios: dict
    success: bool
    update: LinearUpdateResult | None = None
    sensors: tuple = ()
    calibration_periods: float = 20.0

    def predict_with(self, specimen, *, max_steps: int | None = None) -> dict:
        """``{(mode, sensor): AmplitudeCurve}``: the same release rung down on ``specimen``
        (another joint on the same beam: an augmented one, a candidate) for as long as the
        prediction, every record's position a sensor, read like the record (the
        calibration mode in windows of ``calibration_periods``).
        """
        t = self.ringdown.t
        rd = ringdown(
            specimen,
            amplitude=self.release,
            duration=float(t[-1] - t[0]),
            sensors=tuple(x for _, x in self.sensors),
            max_steps=MAX_STEPS if max_steps is None else max_steps,
        )
        return {
            (r, n): rd.sensor_curve(
                i,
                self.bands[r],
                n_periods=self.calibration_periods if r == self.calibration_mode else None,
            )
            for i, (n, _) in enumerate(self.sensors)
            for r in self.bands
            if (r, n) in self.measured
        }

    def summary(self) -> dict:
        """``{(mode, sensor): {points, max_frequency_error, max_damping_error, first_...}}``:
        the largest relative errors [-] over the common amplitudes and the first (largest
        amplitude) common window's.
        """
        out: dict[Any, dict[str, Any]] = {}  # {(mode, sensor name): {quantity: value}}
        for key, e in self.errors.items():
            n = len(e["amplitude"])
            if not n:
                out[key] = {"points": 0}
                continue
            first = int(np.argmax(e["amplitude"]))
            out[key] = {
                "points": n,
                "amplitude_range": (float(e["amplitude"].min()), float(e["amplitude"].max())),
                "max_frequency_error": float(np.max(np.abs(e["frequency_shift"]))),
                "max_damping_error": float(np.max(np.abs(e["damping_ratio"] - 1))),
                "first_frequency_error": float(e["frequency_shift"][first]),
                "first_damping_error": float(e["damping_ratio"][first] - 1),
            }
        return out

    def _prediction_rows(self) -> list:
        """Per mode and sensor: points, the largest and the first relative errors [%]."""
        rows = []
        for (r, name), s in self.summary().items():
            if not s["points"]:
                rows.append((r, name, 0, math.nan, math.nan, math.nan, math.nan))
                continue
            rows.append(
                (
                    r,
                    name,
                    s["points"],
                    100 * s["max_frequency_error"],
                    100 * s["max_damping_error"],
                    100 * s["first_frequency_error"],
                    100 * s["first_damping_error"],
                )
            )
        return rows

    def _tables(self) -> list:
        """The prediction against the measured curves per mode and sensor (the main
        table), then the calibration's mode and sensor.
        """
        cols = (
            "mode",
            "sensor",
            "points",
            column("max |df/f|", "%"),
            column("max |dzeta/zeta|", "%"),
            column("first df/f", "%"),
            column("first dzeta/zeta", "%"),
        )
        run = [
            ("calibration mode", self.calibration_mode),
            ("calibration sensor", self.calibration_sensor),
        ] + [(column(f"release, mode {r}", "m"), float(x)) for r, x in self.release.items()]
        return [("prediction", cols, self._prediction_rows()), ("run", ("quantity", "value"), run)]

    def report(self) -> str:
        """The verdict, the calibration, the release, and each predicted curve against the
        measured one; the mode-shape check.
        """
        lines = [self.verdict(), f"Hammer test predicted from mode {self.calibration_mode}"]
        if self.update is not None:
            fitted = ", ".join(n for n, p in self.update.params.items() if p.identified)
            lines += [
                f"linear structure ({fitted}) updated on the low-amplitude frequencies of "
                "modes "
                + ", ".join(
                    r["target"][1:] for r in self.update.residuals if r["target"].startswith("f")
                )
                + ":",
                self.update.report(),
            ]
        lines += [
            f"joint calibrated on the amplitude curve of mode {self.calibration_mode} at "
            f"{self.calibration_sensor} (the other modes' curves give only their floors "
            "from their lowest amplitudes):",
            self.calibration.report(),
            "release: " + ", ".join(f"mode {r} {1e6 * x:.4g} um" for r, x in self.release.items()),
            "prediction against the measured curve at the same amplitudes:",
        ]
        rows = self._prediction_rows()
        lines += table_lines(
            (
                ("mode", "5d"),
                ("sensor", ">8s"),
                ("points", "7d"),
                ("max|df/f| [%]", "15.3f"),
                ("max|dz/z| [%]", "14.1f"),
                ("first df/f [%]", "15.3f"),
                ("first dz/z [%]", "15.1f"),
            ),
            rows,
            indent=2,
        )
        for (r, name), (m, p) in self.ratios.items():
            lines.append(
                f"  mode {r} amplitude {name}/calibration sensor: measured {m:.3f}, "
                f"predicted {p:.3f} ({100 * (p / m - 1):+.1f} %)"
            )
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe: bands, release, the summary, ratios, the calibration, verdict."""
        key = lambda k: f"mode {k[0]} at {k[1]}"  # noqa: E731
        return json_safe(
            {
                "calibration_mode": self.calibration_mode,
                "calibration_sensor": self.calibration_sensor,
                "bands": {str(r): b for r, b in self.bands.items()},
                "release": {str(r): x for r, x in self.release.items()},
                "summary": {key(k): v for k, v in self.summary().items()},
                "ratios": {key(k): v for k, v in self.ratios.items()},
                "calibration": self.calibration.to_dict(),
                "update": None if self.update is None else self.update.to_dict(),
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Measured (points) and predicted (lines) damping ratio [%] and frequency [Hz]
        against amplitude for every curve, on ``ax = (ax_z, ax_f)``; returns the artists.
        """
        ax_z, ax_f = panels(ax, 2, figsize=(6, 6))
        pairs = [
            (
                f"mode {r} at {name}",
                self.measured[(r, name)],
                "measured",
                self.predicted[(r, name)],
                "predicted",
            )
            for r, name in self.predicted
        ]
        return plot_curve_pairs(ax_z, ax_f, pairs, ("o", "-"))
