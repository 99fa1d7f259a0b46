"""Unit checks shared by the vibration functions: damping ratios that look like percent.

A damping ratio is dimensionless; the single-mode relations this package uses for vibration
data (modal Iwan curves, single-nonlinear-mode inversion of sweeps, ring-down averaging)
assume a lightly damped mode, ``zeta << 1`` (``docs/sweeps.md``). A value of 0.1 or more
is therefore refused: it is either a percentage (0.5 % typed as 0.5) or outside the range
where these relations hold. Frequency in rad/s instead of Hz is caught only against a
second frequency (the prediction of :func:`~iwan_element.diagnose_vibration`): the ratio of
two frequencies near 2 pi. A single curve ``f(X)`` carries no absolute scale to tell them.
"""
from __future__ import annotations

import numpy as np

__all__ = ["MAX_DAMPING_RATIO", "check_damping_ratio", "check_frequency_ratio"]

#: Largest damping ratio accepted by the vibration functions (light damping).
MAX_DAMPING_RATIO = 0.1


def check_damping_ratio(name: str, value) -> None:
    """Raise ``ValueError`` if any damping ratio is >= 0.1 (percent, or not light damping)."""
    z = np.asarray(value, dtype=float)
    if z.size and np.nanmax(z) >= MAX_DAMPING_RATIO:
        raise ValueError(
            f"{name} has values up to {np.nanmax(z):.3g}: a damping ratio is dimensionless "
            f"and a lightly damped mode has zeta < {MAX_DAMPING_RATIO:g}; it looks like "
            "percent (divide by 100). The single-mode relations used here do not hold for "
            "heavier damping either")


def check_frequency_ratio(name: str, value, other_name: str, other) -> None:
    """Raise ``ValueError`` if ``value / other`` is near 2 pi or 1 / (2 pi) (rad/s vs Hz)."""
    ratio = float(np.median(np.asarray(value, dtype=float) / np.asarray(other, dtype=float)))
    for k, a, b in ((2 * np.pi, name, other_name), (1 / (2 * np.pi), other_name, name)):
        if abs(ratio / k - 1.0) < 0.15:
            r = ratio if k > 1 else 1 / ratio
            raise ValueError(f"{a} is {r:.3g} x {b}, close to 2 pi: {a} looks like rad/s; "
                             "give both in Hz")
