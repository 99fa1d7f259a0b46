"""What a specimen's analyses can stand: its size against an amplitude, its lap in macroslip.

* **Size.** The beam models (1-D and solid) are linear in geometry: small deflections and
  rotations, no bending-stretching coupling, a lap that never opens. A bolted-lap test
  stays far inside that (the Brake-Reuss beam's measured range ends at 60 um, 1/200 of its
  12.7 mm height), so a sensor amplitude above the beam's thickness (fraction 1, or above
  1/20 of the assembly's length when that is smaller: a slope of about 0.15 rad at a
  cantilever's tip) is no test of a jointed beam: most often a length in millimetres (or
  micrometres) given as metres. :func:`size_warnings` says so and names the likely slip.
* **Macroslip.** Past full slip the model holds the lap by the contact points' slip forces
  ``mu N`` alone: nothing like a bolt bearing on its hole (unless the specimen carries the
  ``pinning_stiffness`` effect) limits the slip, so the response there is the model's, not
  the joint's (a forced response then grows to the floor damping's limit: 48.2 m at 2 kN on
  the two-bolt beam). :func:`macroslip_report` says where each bolt's contact is fully
  slipped and makes a whole lap fully slipped a reason the result is not usable.
"""

from __future__ import annotations

import numpy as np

from iwan_element.harmonic import macroslip_lines

from ..reduced.dispatch import bolt_groups

__all__ = ["size_limit", "size_warnings", "macroslip_report", "SIZE_LENGTH_FRACTION"]

#: Fraction of the assembly's length above which an amplitude is no test of a beam [-].
SIZE_LENGTH_FRACTION = 0.05


def size_limit(specimen) -> float:
    """The largest plausible sensor amplitude [m]: the beam's ``thickness`` or
    :data:`SIZE_LENGTH_FRACTION` of its ``total_length``, whichever is smaller (module
    docstring).
    """
    return float(min(specimen.thickness, SIZE_LENGTH_FRACTION * specimen.total_length))


def size_warnings(specimen, amplitude, *, what: str = "amplitude", given: bool = True) -> list:
    """A warning when sensor amplitudes [m] exceed :func:`size_limit`: for amplitudes the
    caller ``given``, naming the unit slip that brings them into the specimen's
    ``amplitude_range`` (mm or um given as m), if any; for a computed response, that the
    load drives the model beyond the specimen.
    """
    X = np.atleast_1d(np.asarray(amplitude, float))
    lim = size_limit(specimen)
    bad = X > lim
    if not bad.any():
        return []
    top = float(X[bad].max())
    lo, hi = specimen.amplitude_range
    slip = next(
        (
            f"; likely {unit} given as metres ({top:.3g} {unit} = {top / k:.3g} m, inside the "
            f"specimen's documented range {lo:.3g} .. {hi:.3g} m)"
            for k, unit in ((1e3, "mm"), (1e6, "um"))
            if lo * 0.1 <= top / k <= hi * 10
        ),
        "; check the unit (metres)",
    )
    if not given:
        slip = "; the load drives the model far beyond any test of this specimen"
    return [
        f"{int(bad.sum())} of {X.size} {what}s ({X[bad].min():.3g} .. {top:.3g} m) exceed "
        f"{lim * 1e3:.3g} mm, the beam's thickness {specimen.thickness * 1e3:.3g} mm or "
        f"{SIZE_LENGTH_FRACTION:g} of its length {specimen.total_length:.3g} m: no bolted "
        "lap test vibrates that much and the beam models (small deflections) do not hold "
        f"there{slip}"
    ]


def macroslip_report(specimen, ratio, at, *, unit: str, what: str) -> tuple[list, list]:
    """``(warnings, failures)`` of the contact points' slip ratios ``ratio`` (n, n_points:
    slip amplitude over ``phi_max``; NaN not solved) at ``at`` (amplitudes [m] or
    frequencies [Hz], ``unit``): where each bolt's contact is fully slipped
    (:func:`iwan_element.harmonic.macroslip_lines` on
    :func:`~iwan_element.models.reduced.dispatch.bolt_groups`), and, when every bolt's is at
    once somewhere, that reason the result is not usable (module docstring).
    """
    groups = bolt_groups(specimen)
    r = np.nan_to_num(np.atleast_2d(np.asarray(ratio, float)), nan=0.0)
    at = np.asarray(at, float)
    warns = list(macroslip_lines(r, at, unit=unit, what=what, groups=groups))
    full = np.all([(r[:, list(idx)] >= 1.0).all(axis=1) for _, idx in groups], axis=0)
    if not full.any():
        return warns, []
    v = at[full]
    span = (
        f"{v.min():.4g} {unit}" if v.min() == v.max() else f"{v.min():.4g} .. {v.max():.4g} {unit}"
    )
    return warns, [
        f"the whole lap is fully slipped (macroslip at every bolt) at {int(full.sum())} of "
        f"{full.size} {what} ({span}): past macroslip the model holds the lap by its slip "
        "forces mu N alone, with no bolt bearing on its hole (carry the pinning_stiffness "
        "effect for one), so the result there is the model's, not the joint's"
    ]
