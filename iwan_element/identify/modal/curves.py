"""Amplitude-dependent modal properties: the one result type shared by every vibration route.

A vibration test of a jointed structure (hammer ring-down, stepped sine, a quasi-static modal
analysis of a model, a transient simulation) ends as three curves against response amplitude:
the natural frequency f(X) [Hz], the damping ratio zeta(X) [-] and, where known, their
uncertainty. :class:`AmplitudeCurve` holds them, validated, with the noise floor below which
the measurement stops and a statement of how it was made.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, column, panels, table_lines, wrap
from ...base.validation import check_magnitude, finite_array

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["AmplitudeCurve", "MIN_POINTS", "DECAY_METHODS"]

#: Fewest curve points a modal fit can use (:func:`~iwan_element.fit_modal_iwan` needs three
#: amplitudes: frequency and damping each carry up to three parameters of the microslip form).
MIN_POINTS = 3
#: The extractions of a free decay (:func:`~iwan_element.amplitude_curve`; their curves carry
#: the damping a decay shows, :attr:`AmplitudeCurve.method`).
DECAY_METHODS = ("hilbert", "pff")


def _optional_std(value, n: int, name: str) -> np.ndarray:
    """A per-point standard deviation: ``None`` means unknown (NaN), else finite and >= 0."""
    if value is None:
        return np.full(n, np.nan)
    arr = np.array(value, dtype=float, copy=True)
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        raise ValueError(f"{name} must have one value per amplitude ({n}), got shape {arr.shape}")
    known = arr[~np.isnan(arr)]
    if np.any(~np.isfinite(known)) or np.any(known < 0):
        raise ValueError(f"{name} must be >= 0 and finite (NaN for unknown)")
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True)
class AmplitudeCurve(ResultShape):
    """Natural frequency and damping ratio against response amplitude.

    Parameters
    ----------
    amplitude : array_like, shape (n,)
        Displacement amplitude at the sensor point [m] (> 0).
    frequency : array_like, shape (n,)
        Natural frequency [Hz] (> 0). :func:`~iwan_element.amplitude_curve` and
        :func:`~iwan_element.stepped_sine_curve` give the undamped one (``w_n / 2 pi``); at
        the damping of bolted joints the damped one differs by ``zeta**2 / 2``.
    damping_ratio : array_like, shape (n,)
        Equivalent viscous damping ratio [-] (finite; a value above 1 is refused as a likely
        percentage).
    amplitude_std, frequency_std, damping_ratio_std : array_like or float, optional
        Standard uncertainty of each point in the same units; ``None`` (the default) means
        unknown and is stored as NaN.
    noise_floor : float, optional
        Amplitude [m] below which the signal is noise and the curve stops (NaN if unknown).
    method : str
        How the curve was made (for example ``"hilbert"``, ``"stepped-sine"``, ``"qsma"``).
    notes : str
        Free text: trimming of filter end effects, sensor point, mode number.
    warnings : tuple of str
        What the maker of the curve could not vouch for.
    failures : tuple of str
        Why the curve is not usable as it stands (each also among ``warnings``): e.g. a
        response whose phase contradicts its declared quantity. Empty by default.

    Notes
    -----
    The arrays are copied and made read-only; nothing the caller passed is changed.
    """

    plot_panels = 2

    amplitude: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    amplitude_std: np.ndarray | None = None
    frequency_std: np.ndarray | None = None
    damping_ratio_std: np.ndarray | None = None
    noise_floor: float = float("nan")
    method: str = ""
    notes: str = ""
    failures: tuple = ()

    def __post_init__(self):
        amp = check_magnitude(
            "amplitude", finite_array("amplitude", self.amplitude).copy(), unit="m"
        )
        if amp.ndim != 1 or amp.size == 0:
            raise ValueError(f"amplitude must be a non-empty 1-D array, got shape {amp.shape}")
        n = amp.size
        arrays = {"amplitude": amp}
        for name in ("frequency", "damping_ratio"):
            arr = check_magnitude(name, finite_array(name, getattr(self, name)).copy())
            if arr.shape != (n,):
                raise ValueError(f"{name} must have the shape of amplitude ({n},), got {arr.shape}")
            arrays[name] = arr
        if np.any(amp <= 0):
            raise ValueError("amplitude must be > 0 [m]")
        if np.any(arrays["frequency"] <= 0):
            raise ValueError("frequency must be > 0 [Hz]")
        if np.any(arrays["damping_ratio"] > 1):
            raise ValueError(
                "damping_ratio must be a ratio (<= 1); values above 1 look like percent"
            )
        for name, arr in arrays.items():
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        for name in ("amplitude_std", "frequency_std", "damping_ratio_std"):
            object.__setattr__(self, name, _optional_std(getattr(self, name), n, name))
        floor = float(self.noise_floor)
        if not (np.isnan(floor) or (np.isfinite(floor) and floor >= 0)):
            raise ValueError(f"noise_floor must be >= 0 [m] or NaN, got {self.noise_floor!r}")
        object.__setattr__(self, "noise_floor", floor)
        self._fold_failures()

    def __len__(self) -> int:
        return int(self.amplitude.size)

    def _stds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The standard uncertainties of amplitude [m], frequency [Hz] and damping ratio [-]."""
        a_sd, f_sd, z_sd = self.amplitude_std, self.frequency_std, self.damping_ratio_std
        # __post_init__ stores an array for every one (NaN where the caller gave None)
        assert a_sd is not None and f_sd is not None and z_sd is not None
        return a_sd, f_sd, z_sd

    def sorted(self) -> AmplitudeCurve:
        """The same curve with the points in increasing amplitude."""
        order = np.argsort(self.amplitude, kind="stable")
        a_sd, f_sd, z_sd = self._stds()
        return AmplitudeCurve(
            self.amplitude[order],
            self.frequency[order],
            self.damping_ratio[order],
            amplitude_std=a_sd[order],
            frequency_std=f_sd[order],
            damping_ratio_std=z_sd[order],
            noise_floor=self.noise_floor,
            method=self.method,
            notes=self.notes,
            warnings=self.warnings,
            failures=self.failures,
        )

    @property
    def success(self) -> bool:
        """True when the curve has at least :data:`MIN_POINTS` points with finite frequency
        and damping (a modal fit needs them; fewer points are reported in ``warnings``) and
        no ``failures`` (docs/guards.md).
        """
        return not self.failure_reasons()

    def failure_reasons(self) -> tuple:
        """Why the curve is not usable: its ``failures``, and too few points."""
        ok = np.isfinite(self.frequency) & np.isfinite(self.damping_ratio)
        n = int(np.count_nonzero(ok))
        few = (
            ()
            if n >= MIN_POINTS
            else (
                f"only {n} point(s) with a finite frequency and damping ratio: a modal fit needs "
                f"{MIN_POINTS}",
            )
        )
        return tuple(self.failures) + few

    def to_dict(self) -> dict:
        """Plain JSON-ready dictionary (NaN written as ``None``)."""

        def clean(a):
            return [None if np.isnan(x) else float(x) for x in np.asarray(a, dtype=float)]

        return {
            "amplitude": clean(self.amplitude),
            "frequency": clean(self.frequency),
            "damping_ratio": clean(self.damping_ratio),
            "amplitude_std": clean(self.amplitude_std),
            "frequency_std": clean(self.frequency_std),
            "damping_ratio_std": clean(self.damping_ratio_std),
            "noise_floor": None if np.isnan(self.noise_floor) else self.noise_floor,
            "method": self.method,
            "notes": self.notes,
            "warnings": list(self.warnings),
            "failures": list(self.failures),
            "success": self.success,
        }

    def to_json(self) -> str:
        """The curve as a JSON string (:meth:`to_dict`, indented)."""
        return json.dumps(self.to_dict(), indent=2)

    def report(self) -> str:
        """A short table of the curve: amplitude, frequency and damping with uncertainties."""
        lines = [
            self.verdict(),
            f"Amplitude curve ({self.method or 'unspecified method'}), {len(self)} points",
        ]
        if self.notes:
            lines += wrap(f"  {self.notes}", indent="    ")
        if not np.isnan(self.noise_floor):
            lines.append(f"  noise floor: {self.noise_floor:.3e} m")
        lines += table_lines(
            [
                ("X [m]", "11.4e"),
                ("f [Hz]", "12.6g"),
                ("+-", "9.2e"),
                ("zeta [-]", "11.4e"),
                ("+-", "9.2e"),
            ],
            zip(
                self.amplitude,
                self.frequency,
                self._stds()[1],
                self.damping_ratio,
                self._stds()[2],
            ),
        )
        for w in self.warnings:
            lines += wrap(f"  warning: {w}", indent="    ")
        return "\n".join(lines)

    #: Column titles of the curve's points (:meth:`to_dataframe`).
    POINT_COLUMNS = (
        column("amplitude", "m"),
        column("amplitude_std", "m"),
        column("frequency", "Hz"),
        column("frequency_std", "Hz"),
        column("damping_ratio", "-"),
        column("damping_ratio_std", "-"),
    )

    def _tables(self) -> list:
        a_sd, f_sd, z_sd = self._stds()
        rows = list(
            zip(
                *(
                    map(float, a)
                    for a in (
                        self.amplitude,
                        a_sd,
                        self.frequency,
                        f_sd,
                        self.damping_ratio,
                        z_sd,
                    )
                )
            )
        )
        out = [("points", self.POINT_COLUMNS, rows)]
        info = [
            ("method", self.method or "unspecified"),
            ("points", len(self)),
            (
                column("noise floor", "m"),
                None if np.isnan(self.noise_floor) else float(self.noise_floor),
            ),
            ("notes", self.notes),
        ]
        return out + [("curve", ("quantity", "value"), info)]

    def plot(self, ax=None, *, label=None, **kwargs) -> list[Artist]:
        """Frequency and damping ratio against amplitude on log amplitude axes.

        Parameters
        ----------
        ax : sequence of two matplotlib Axes, optional
            ``(ax_frequency, ax_damping)``; a new figure with two panels if omitted (the
            package's axes contract, :mod:`iwan_element.base.result_shape`).
        label : str, optional
            Legend label.

        Returns
        -------
        list
            The matplotlib artists drawn.
        """
        ax_f, ax_z = panels(ax, 2, sharex=True, figsize=(6, 6))
        kw = {"marker": "o", "ms": 3, "ls": "-"}
        kw.update(kwargs)
        artists = []
        for a, y, s in (
            (ax_f, self.frequency, self.frequency_std),
            (ax_z, self.damping_ratio, self.damping_ratio_std),
        ):
            assert s is not None  # __post_init__ made every std an array (NaN: not given)
            if np.all(np.isnan(s)):
                artists += a.plot(self.amplitude, y, label=label, **kw)
            else:
                eb = a.errorbar(self.amplitude, y, yerr=np.nan_to_num(s), label=label, **kw)
                artists += [eb.lines[0], *eb.lines[2]]
            a.set_xscale("log")
            if a.get_yscale() == "linear":  # 79.05 .. 79.06 Hz, not "+7.9e1" and 0.01 steps
                a.ticklabel_format(axis="y", useOffset=False)
            if label is not None:
                a.legend(fontsize=8)
        ax_f.set_ylabel("frequency [Hz]")
        ax_z.set_ylabel("damping ratio [-]")
        ax_z.set_xlabel("amplitude [m]")
        return artists
