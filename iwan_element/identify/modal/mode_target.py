"""One identified linear mode (:class:`ModeTarget`, an entry of
:class:`~iwan_element.identify.modal.targets.ModalTargets`) and the modal assurance
criterion (:func:`mac`) that pairs shapes (``docs/modal_targets.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["ModeTarget", "mac"]


def mac(a, b) -> float:
    """Modal assurance criterion ``|a^H b|^2 / ((a^H a)(b^H b))`` of two shapes [-].

    Parameters
    ----------
    a, b : array_like of complex or real, or mappings {position: amplitude}
        Two shapes at the same sensors (mappings are matched by position; a position missing
        from either is a ``ValueError``).
    """
    if isinstance(a, dict) or isinstance(b, dict):
        if not (isinstance(a, dict) and isinstance(b, dict)):
            raise ValueError(
                "a and b must both be arrays or both be {position: amplitude} mappings"
            )
        if set(a) != set(b):
            raise ValueError(
                f"a and b must hold the same positions, got {sorted(map(str, a))} "
                f"and {sorted(map(str, b))}"
            )
        keys = list(a)
        a, b = [a[k] for k in keys], [b[k] for k in keys]
    try:
        a = np.asarray(a, dtype=complex).ravel()
    except (TypeError, ValueError):
        raise ValueError(
            f"a must be an array of (complex) amplitudes, got {type(a).__name__}"
        ) from None
    try:
        b = np.asarray(b, dtype=complex).ravel()
    except (TypeError, ValueError):
        raise ValueError(
            f"b must be an array of (complex) amplitudes, got {type(b).__name__}"
        ) from None
    if a.shape != b.shape or a.size == 0:
        raise ValueError(
            f"a and b must be shapes at the same sensors, got sizes {a.size} and {b.size}"
        )
    den = float(np.vdot(a, a).real * np.vdot(b, b).real)
    if not (den > 0 and math.isfinite(den)):
        raise ValueError("a and b must be finite and not all zero")
    if a.size < 2:
        raise ValueError("a and b must be shapes at 2 or more sensors")
    return float(abs(np.vdot(a, b)) ** 2 / den)


def _nan(x):
    return float("nan") if x is None else float(x)


@dataclass(frozen=True, eq=False)
class ModeTarget:
    """One identified mode (see :class:`ModalTargets` for the units and conventions).

    Attributes
    ----------
    index : int
        1, 2, ... by ascending frequency among the test's identified modes.
    label : str
        The band or fit it came from.
    frequency, frequency_std : float
        Undamped natural frequency ``|s| / 2 pi`` [Hz] and its statistical standard error.
    damping_ratio, damping_ratio_std : float
        Viscous damping ratio ``-Re s / |s|`` [-] and its standard error.
    sensors, positions : tuple
        Sensor names and positions [m] (empty for a fit without shapes).
    amplitude : ndarray of complex, shape (m,)
        Complex displacement amplitude at each sensor [m] at ``t_ref`` (the motion is
        ``Re(amplitude exp(s (t - t_ref)))``), common phase reference: the same pole for all.
    amplitude_std : ndarray, shape (m, 2)
        Standard errors of its real and imaginary parts [m].
    shape : ndarray of complex, shape (m,)
        ``amplitude`` turned by one phase so that it is as nearly real as possible (the sum
        of its squares real and positive), the largest real part positive; for a real
        (proportionally damped) mode the imaginary parts are noise.
    shape_std : ndarray, shape (m, 2)
        Standard errors of the real and imaginary parts of ``shape`` [m].
    modal_constant, modal_constant_std : float
        ``phi_drive phi_response`` [1/kg] of the mass-normalised mode (NaN unless a force
        was measured).
    t_ref : float
        Reference time of ``amplitude`` [s] (the window's start; NaN for an FRF).
    window : tuple of float
        ``(t0, t1)`` [s] of a ring-down's window; ``(f0, f1)`` [Hz] of an FRF's lines.
    amplitude_range : tuple of float
        Largest displacement amplitude over the sensors at the start and at the end of the
        window [m] (for an FRF: the smallest and largest response amplitude of its points).
    frequency_drift, frequency_drift_std, damping_drift, damping_drift_std : float
        Second half of the window minus its first half, with the combined standard error
        (NaN where not measured).
    linear : bool or None
        Whether the drifts are within three combined standard errors (None: not checked).
    complexity : float
        ``|Im shape| / |shape|`` [-].
    method : str
        How the mode was identified.
    """

    index: int
    label: str
    frequency: float
    frequency_std: float
    damping_ratio: float
    damping_ratio_std: float
    sensors: tuple = ()
    positions: tuple = ()
    amplitude: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    amplitude_std: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    shape: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    shape_std: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    modal_constant: float = float("nan")
    modal_constant_std: float = float("nan")
    t_ref: float = float("nan")
    window: tuple = (float("nan"), float("nan"))
    amplitude_range: tuple = (float("nan"), float("nan"))
    frequency_drift: float = float("nan")
    frequency_drift_std: float = float("nan")
    damping_drift: float = float("nan")
    damping_drift_std: float = float("nan")
    linear: bool | None = None
    complexity: float = float("nan")
    method: str = ""

    def __post_init__(self):
        if not (self.frequency > 0 and math.isfinite(self.frequency)):
            raise ValueError(f"frequency must be > 0 and finite [Hz], got {self.frequency!r}")
        if not (math.isfinite(self.damping_ratio) and abs(self.damping_ratio) < 1):
            raise ValueError(
                f"damping_ratio must be a finite ratio below 1, got {self.damping_ratio!r}"
            )
        m = len(self.sensors)
        if len(self.positions) != m:
            raise ValueError("positions must hold one position per sensor")
        for name, dt, shp in (
            ("amplitude", complex, (m,)),
            ("shape", complex, (m,)),
            ("amplitude_std", float, (m, 2)),
            ("shape_std", float, (m, 2)),
        ):
            arr = np.array(getattr(self, name), dtype=dt, copy=True).reshape(shp)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)
        for name in (
            "frequency",
            "frequency_std",
            "damping_ratio",
            "damping_ratio_std",
            "modal_constant",
            "modal_constant_std",
            "t_ref",
            "frequency_drift",
            "frequency_drift_std",
            "damping_drift",
            "damping_drift_std",
            "complexity",
        ):
            object.__setattr__(self, name, _nan(getattr(self, name)))
        object.__setattr__(self, "window", tuple(map(float, self.window)))
        object.__setattr__(self, "amplitude_range", tuple(map(float, self.amplitude_range)))
        object.__setattr__(self, "sensors", tuple(map(str, self.sensors)))
        object.__setattr__(self, "positions", tuple(self.positions))

    def _widened(self, std, drift):
        """The statistical error, with the drift added in quadrature where it is significant."""
        if self.linear is False and math.isfinite(drift):
            return math.hypot(std, drift)
        return std

    @property
    def frequency_stderr(self) -> float:
        """Standard error of the frequency target [Hz]: the statistical one, combined in
        quadrature with the drift across the window when that drift is significant (the
        structure was not quite linear there).
        """
        return self._widened(self.frequency_std, self.frequency_drift)

    @property
    def damping_ratio_stderr(self) -> float:
        """Standard error of the damping target [-], widened like :attr:`frequency_stderr`."""
        return self._widened(self.damping_ratio_std, self.damping_drift)

    def to_dict(self) -> dict:
        """JSON-safe dictionary (complex numbers as ``[re, im]``, NaN as ``None``)."""

        def num(x):
            return float(x) if x is not None and math.isfinite(float(x)) else None

        def cplx(z):
            return [[num(v.real), num(v.imag)] for v in np.asarray(z).ravel()]

        return {
            "index": self.index,
            "label": self.label,
            "method": self.method,
            "frequency": num(self.frequency),
            "frequency_std": num(self.frequency_std),
            "frequency_stderr": num(self.frequency_stderr),
            "damping_ratio": num(self.damping_ratio),
            "damping_ratio_std": num(self.damping_ratio_std),
            "damping_ratio_stderr": num(self.damping_ratio_stderr),
            "sensors": list(self.sensors),
            "positions": [list(p) if isinstance(p, tuple) else num(p) for p in self.positions],
            "amplitude": cplx(self.amplitude),
            "amplitude_std": [[num(a), num(b)] for a, b in self.amplitude_std],
            "shape": cplx(self.shape),
            "shape_std": [[num(a), num(b)] for a, b in self.shape_std],
            "modal_constant": num(self.modal_constant),
            "modal_constant_std": num(self.modal_constant_std),
            "t_ref": num(self.t_ref),
            "window": [num(w) for w in self.window],
            "amplitude_range": [num(a) for a in self.amplitude_range],
            "frequency_drift": num(self.frequency_drift),
            "frequency_drift_std": num(self.frequency_drift_std),
            "damping_drift": num(self.damping_drift),
            "damping_drift_std": num(self.damping_drift_std),
            "linear": self.linear,
            "complexity": num(self.complexity),
        }
