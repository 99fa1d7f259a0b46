"""The discrepancy workflow across modes on a hammer test: QSMA proposes, the multi-mode
ring-down names.

:func:`~iwan_element.models.calibration.diagnose_modes` reads every mode on its own by QSMA:
one mode's curve, one load shape. In a hammer test the modes ring together, and a law in the
joint that one mode engages acts on the other too (a patch that mode 1's motion slides
while mode 2 rings through it). :func:`diagnose_hammer_test` therefore runs the QSMA
workflow on the test's curves at its calibration sensor (each mode over the amplitudes the
prediction covers), then rings the measured release down again through the plain joint and
the ``top`` candidates QSMA ranks best (:meth:`HammerPrediction.predict_with`; every other
mode's floor read again with the candidate's joint, as the calibration read it with the
plain one), reads each like the record, and names among those by the same score (noise,
offsets, information criterion and spoil rule, :mod:`.mode_diagnosis`). QSMA against the
transient is the independent route: where they disagree the report says what QSMA alone
would have named (``docs/multi_mode.md`` section 6).
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from iwan_element.base.validation import check_int

from ..simulation.coupling import compare_curves
from .hammer_result import HammerPrediction
from .mode_diagnosis import SPOIL, diagnose_modes, score_logs
from .mode_diagnosis_result import Candidate, ModesDiagnosis
from .vibration import _floors

__all__ = ["diagnose_hammer_test"]

log = logging.getLogger(__name__)


def _covered(prediction: HammerPrediction, mode: int) -> tuple | None:
    """The amplitudes [m] where the prediction and the record overlap at the calibration
    sensor (``None``: fewer than 3, or the calibration mode: its whole curve).
    """
    if mode == prediction.calibration_mode:
        return None
    a = prediction.errors[(mode, prediction.calibration_sensor)]["amplitude"]
    return (float(np.min(a)), float(np.max(a))) if len(a) >= 3 else None


def _transient(c: Candidate, predicted: dict, prediction, noise, offsets) -> Candidate:
    """``c`` scored by its ring-down's curves at the calibration sensor against the record."""
    logs = {}
    for m in noise:
        key = (m, prediction.calibration_sensor)
        e = compare_curves(predicted[key], prediction.measured[key])
        logs[m] = (np.log1p(e["frequency_shift"]), np.log(e["damping_ratio"]))
    return replace(c, scores=score_logs(logs, noise, offsets), predicted=predicted)


def _refloored(c: Candidate, prediction) -> Candidate:
    """``c`` with every other mode's floor read again from its lowest measured amplitudes
    with ``c``'s joint, by the calibration's own rule (:func:`~iwan_element.models.
    calibration.modal_floor`, clipped to the floor's range): a law that acts there changes
    the joint's share the floor is the rest of.
    """
    sensor = prediction.calibration_sensor
    floors = {
        r: prediction.measured[(r, sensor)]
        for r in prediction.bands
        if r != prediction.calibration_mode
    }
    spec, _ = _floors(c.specimen, prediction.calibration_mode, floors, [])
    return replace(c, specimen=spec)


def diagnose_hammer_test(
    prediction: HammerPrediction,
    *,
    top: int = 3,
    placements=None,
    offsets: bool = True,
    max_effects: int = 1,
    alpha: float = 1e-3,
    frequency_noise: float | None = None,
    damping_ratio_noise: float | None = None,
) -> ModesDiagnosis:
    """Name the effect in the joint that closes a hammer test's gaps in every mode (module
    docstring).

    Parameters
    ----------
    prediction : HammerPrediction
        The test predicted from one calibrated mode (:func:`predict_hammer_test`).
    top : int, keyword-only
        How many of the QSMA workflow's candidates (least information criterion, spoiling no
        mode) the ring-down reads again, ``>= 1``; each costs one multi-mode ring-down.
    placements, offsets, max_effects, alpha, frequency_noise, damping_ratio_noise
        As :func:`diagnose_modes`.

    Returns
    -------
    ModesDiagnosis
        With ``checked`` (the plain joint and the candidates read by the ring-down), which
        named; the QSMA stage's result as it is when it has no candidate to check.
    """
    if not isinstance(prediction, HammerPrediction):
        raise ValueError(f"prediction must be a HammerPrediction, got {type(prediction).__name__}")
    top = check_int("top", top, 1)
    sensor = prediction.calibration_sensor
    modes = sorted({m for m, n in prediction.measured if n == sensor})
    ranges = {m: r for m in modes if (r := _covered(prediction, m)) is not None}
    first = diagnose_modes(
        prediction.calibration.specimen,
        {m: prediction.measured[(m, sensor)] for m in modes},
        placements=placements,
        amplitude_range=ranges,
        max_effects=max_effects,
        alpha=alpha,
        frequency_noise=frequency_noise,
        damping_ratio_noise=damping_ratio_noise,
        offsets=offsets,
    )
    pool = sorted(
        (c for c in first.candidates if c.scores is not None and not c.spoils),
        key=lambda c: c.ic,
    )[:top]
    if not pool:
        return first
    noise = {m: (d.frequency_noise, d.damping_ratio_noise) for m, d in first.diagnoses.items()}
    checked = [_transient(first.plain, prediction.predicted, prediction, noise, offsets)]
    for c in pool:
        c = _refloored(c, prediction)
        log.info("ring-down through %s (floors %s)", c.label, c.specimen.modal_damping)
        checked.append(
            _transient(c, prediction.predict_with(c.specimen), prediction, noise, offsets)
        )
    n_points = sum(2 * len(prediction.errors[(m, sensor)]["amplitude"]) for m in noise)
    return ModesDiagnosis.build(
        first.plain,
        first.candidates,
        first.diagnoses,
        first.curves,
        spoil=SPOIL,
        checked=tuple(checked),
        checked_points=n_points,
    )
