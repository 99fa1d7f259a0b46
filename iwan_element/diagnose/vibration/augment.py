"""The body of :meth:`VibrationDiagnosis.augment` and its units guard (docs/guards.md)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...base.validation import check_scalar
from ...core.protocol import check_element
from ...effects import EFFECTS

__all__ = ["augmented", "check_amplitude_units"]


def augmented(diag, target, *, modal_mass, slip_per_amplitude, mode, form) -> Any:
    """:meth:`VibrationDiagnosis.augment` of the diagnosis ``diag`` (see there)."""
    if form not in ("physical", "modal"):
        raise ValueError(f"form must be 'physical' or 'modal', got {form!r}")
    if hasattr(target, "with_effects"):
        if not diag.effects:
            return target
        diagnosed = (float(diag.amplitude.min()), float(diag.amplitude.max()))
        check_amplitude_units(diagnosed, target)
        return target.with_effects(
            {n: dict(diag.parameters[n]) for n in diag.effects},
            mode=mode,
            calibrated_range=diagnosed,
            form=form,
        )
    check_element(target, name="target")
    if modal_mass is None:
        raise ValueError("modal_mass is required to augment a joint element")
    m = check_scalar("modal_mass", modal_mass, low=0.0, low_open=True)
    r = check_scalar("slip_per_amplitude", slip_per_amplitude, low=0.0, low_open=True)
    el = target
    w0 = 2 * np.pi * float(diag.frequency[np.argmin(diag.amplitude)])
    for name in diag.effects:
        cls = EFFECTS[name]
        el = cls(
            el,
            **cls.modal_to_joint(
                diag.parameters[name], modal_mass=m, slip_per_amplitude=r, omega0=w0
            ),
        )
    return el


#: How far [factor] the diagnosed amplitudes may lie outside a specimen's documented and
#: calibrated amplitudes before augment refuses them as given in other units.
_UNIT_FACTOR = 30.0


def check_amplitude_units(diagnosed, specimen) -> None:
    """ValueError when the diagnosed amplitude range [m] lies wholly more than
    :data:`_UNIT_FACTOR` outside the specimen's ``amplitude_range`` and ``calibrated_range``
    (amplitudes in mm or um given as metres: the effects' amplitude constants and the
    calibrated range would be wrong by the factor and QSMA would stop warning).
    """
    ranges = [
        r
        for r in (
            getattr(specimen, "amplitude_range", None),
            getattr(specimen, "calibrated_range", None),
        )
        if r is not None
    ]
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
            "widen the specimen's amplitude_range if the test truly went there)"
        )
