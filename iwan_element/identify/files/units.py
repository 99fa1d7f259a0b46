"""Unit checks shared by the vibration functions: damping in percent, frequency in rad/s.

A damping ratio is dimensionless. Two signs of a percentage are refused:

* a value of 1 or more (critical damping: not a vibrating mode);
* every value 0.05 or more. The damping of a curve's smallest amplitudes is the structure's
  linear floor (material, air, supports), well below 5 % for the metallic jointed structures
  these functions are for (the Brake-Reuss beam: about 0.1 %); the joint adds to it only as
  the amplitude grows, so a curve that never goes below 0.05 is read as percent. A curve
  with a floor that is truly that high is outside the light-damping single-mode relations
  used here (``docs/sweeps.md``).

Frequency in rad/s instead of Hz is caught only against a second frequency (the prediction
of :func:`~iwan_element.diagnose_vibration`): a ratio of the two near 2 pi. A single curve
``f(X)`` has no absolute scale to tell them apart.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MAX_DAMPING_FLOOR", "check_damping_ratio", "check_frequency_ratio"]

#: Smallest damping ratio of a curve above which it is read as percent.
MAX_DAMPING_FLOOR = 0.05


def check_damping_ratio(name: str, value) -> None:
    """Raise ``ValueError`` if damping ratios look like percent (see the module docstring)."""
    z = np.asarray(value, dtype=float)
    if z.size == 0:
        return
    if np.nanmax(z) >= 1.0:
        raise ValueError(
            f"{name} has values up to {np.nanmax(z):.3g}: a damping ratio is "
            "dimensionless and below 1; it looks like percent (divide by 100)"
        )
    if np.nanmin(z) >= MAX_DAMPING_FLOOR:
        raise ValueError(
            f"{name} is never below {np.nanmin(z):.3g}: the damping floor of a jointed metal "
            f"structure is far below {MAX_DAMPING_FLOOR:g}; it looks like percent (divide by "
            "100). The light-damping single-mode relations used here would not hold either"
        )


def check_frequency_ratio(name: str, value, other_name: str, other) -> None:
    """Raise ``ValueError`` if ``value / other`` is near 2 pi or 1 / (2 pi) (rad/s vs Hz)."""
    ratio = float(np.median(np.asarray(value, dtype=float) / np.asarray(other, dtype=float)))
    for k, a, b in ((2 * np.pi, name, other_name), (1 / (2 * np.pi), other_name, name)):
        if abs(ratio / k - 1.0) < 0.15:
            r = ratio if k > 1 else 1 / ratio
            raise ValueError(
                f"{a} is {r:.3g} x {b}, close to 2 pi: {a} looks like rad/s; give both in Hz"
            )
