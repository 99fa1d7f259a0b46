"""The units guard of :meth:`VibrationDiagnosis.augment` on a specimen (docs/guards.md)."""
from __future__ import annotations

__all__ = ["check_amplitude_units"]

#: How far [factor] the diagnosed amplitudes may lie outside a specimen's documented and
#: calibrated amplitudes before augment refuses them as given in other units.
_UNIT_FACTOR = 30.0


def check_amplitude_units(diagnosed, specimen) -> None:
    """ValueError when the diagnosed amplitude range [m] lies wholly more than
    :data:`_UNIT_FACTOR` outside the specimen's ``amplitude_range`` and ``calibrated_range``
    (amplitudes in mm or um given as metres: the effects' amplitude constants and the
    calibrated range would be wrong by the factor and QSMA would stop warning)."""
    ranges = [r for r in (getattr(specimen, "amplitude_range", None),
                          getattr(specimen, "calibrated_range", None)) if r is not None]
    if not ranges:
        return
    lo, hi = min(r[0] for r in ranges), max(r[1] for r in ranges)
    if diagnosed[0] > _UNIT_FACTOR * hi or diagnosed[1] < lo / _UNIT_FACTOR:
        far = diagnosed[0] / hi if diagnosed[0] > hi else lo / diagnosed[1]
        raise ValueError(
            f"the diagnosed amplitudes ({diagnosed[0]:.3g} to {diagnosed[1]:.3g} m) lie "
            f"{far:.3g} times {'above' if diagnosed[0] > hi else 'below'} the target "
            f"specimen's amplitudes ({lo:.3g} to {hi:.3g} m): were they given in mm or um? "
            "diagnose_vibration takes amplitudes in metres; diagnose again in metres (or "
            "widen the specimen's amplitude_range if the test truly went there)")

