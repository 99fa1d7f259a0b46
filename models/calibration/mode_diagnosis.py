"""The discrepancy workflow across modes: where one interface misses a mode, name the effect
in the joint that closes that mode's gap without opening another's.

A specimen calibrated on one mode predicts the others (:func:`predict_hammer_test`); where a
mode's measured curve leaves the prediction, the vibration diagnosis
(:func:`~iwan_element.diagnose_vibration`) names the effects whose modal form closes that
mode's gap. A modal form acts on its mode alone; the joint model needs the mechanism, and the
mechanism sits somewhere in the interface. Each named effect is therefore tried in the joint
at every placement (:data:`~iwan_element.models.specimens.effects.WHERE`: every contact
point, every bolt's shank, one bolt's shank, ``"bolt<k>"``, or the contact under one bolt,
``"under<k>"``), its joint values mapped from the
modal fit and fitted so that the joint's QSMA reproduces it on the mode it was found on
(:func:`~iwan_element.models.modal.resolve_interface_effects`), and every mode is then read
again through the augmented joint. A mechanism sits where the modes' slips say: a law at a
bolt where one mode slips and another hardly moves changes the first alone; the same law on
every contact point changes both.

Selection. Each candidate (and the plain joint) is scored on every mode's curve at once,
``chi2 = sum_modes sum_points (ln f/f_m / s_f)^2 + (ln zeta/zeta_m / s_z)^2`` with each mode's
noise as its diagnosis states it, and an information criterion ``IC = chi2 + k ln N`` (``k``
the effect's modal values, ``N`` all points of all modes); the probabilities are
``exp(-IC/2)`` normalised over the plain joint and the candidates (Schwarz, Ann. Stat.
6:461-464, 1978); with ``offsets`` (default) each curve's constant relative offsets of
frequency and damping are taken out first (the mean log residuals: a floor read from the
mode's lowest amplitudes, another route's period error). A candidate that makes another
mode worse by more than :data:`SPOIL` of that mode's noise trades one mode for the other and
is not named; where the plain joint already misses that mode by ``r > 1`` noise units (RMS),
its noise is taken as ``r`` times the stated one (the Birge ratio: the model cannot be held
to less than it already misses), so the tolerance is ``SPOIL max(1, r)``. The named
effect's gap on the mode it was found on is a fit, not a prediction: the other modes, and
tests held out of the workflow, are its check (``docs/multi_mode.md`` section 6).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping

import numpy as np

from iwan_element import diagnose_vibration
from iwan_element.base.validation import check_int

from ..modal.interface import stiffness_cap
from ..modal.qsma import modal_amplitude_curve, resolve_interface_effects
from ..specimens.effects import check_range, placement
from .mode_diagnosis_result import Candidate, ModesDiagnosis

__all__ = ["diagnose_modes", "default_placements", "score_logs", "SPOIL"]

log = logging.getLogger(__name__)

#: How much worse a candidate may make a mode it was not found on, in that mode's noise
#: units (RMS of the normalised log residuals, inflated by the plain joint's RMS misfit when
#: above 1), before it is refused as trading that mode for its own.
SPOIL = 0.5


def default_placements(specimen) -> tuple:
    """Every placement of an effect in ``specimen``'s joint: ``"contact"``, ``"bolts"``, each
    bolt's shank alone (``"bolt1"`` ... along the lap) and the contact under each bolt
    (``"under1"`` ...).
    """
    n = len(specimen.bolt_positions)
    if not n:
        return ("contact",)
    one = range(1, n + 1)
    return ("contact", "bolts") + tuple(f"bolt{k}" for k in one) + tuple(f"under{k}" for k in one)


def _placements(specimen, placements) -> tuple:
    if placements is None:
        return default_placements(specimen)
    out = tuple(placements)
    if not out:
        raise ValueError("placements must name at least one placement")
    n = len(specimen.bolt_positions)
    for p in out:
        k = placement(p)[1]  # ValueError for an unknown name
        if k is not None and k > n:
            raise ValueError(f"placements: {p!r}, but the specimen has {n} bolt(s)")
    return tuple(dict.fromkeys(out))


def _curves(measured, ranges) -> dict:
    """``{mode: (X, f, zeta)}`` of the measured curves within ``ranges``, checked."""
    if not isinstance(measured, Mapping) or not measured:
        raise ValueError("measured must be a non-empty {mode: AmplitudeCurve} mapping")
    out = {}
    for m, c in measured.items():
        mode = check_int("measured mode", m, 1)
        try:
            X, f, z = (
                np.asarray(getattr(c, k), float)
                for k in ("amplitude", "frequency", "damping_ratio")
            )
        except AttributeError as e:
            raise ValueError(
                f"measured[{m!r}] must be an AmplitudeCurve (amplitude, frequency, "
                f"damping_ratio), got {type(c).__name__}"
            ) from e
        if m in ranges:
            lo, hi = check_range(f"amplitude_range[{m!r}]", ranges[m])
            keep = (X >= lo) & (X <= hi)
            X, f, z = X[keep], f[keep], z[keep]
        if X.size < 3:
            raise ValueError(
                f"measured[{m!r}] holds {X.size} amplitudes (within its amplitude_range); "
                "at least 3 are needed"
            )
        out[mode] = (X, f, z)
    return dict(sorted(out.items()))


def _read(specimen, curves) -> dict | str:
    """``{mode: (f, zeta)}``: the specimen's QSMA at each measured curve's amplitudes; the
    reason as a str when a static solve fails.
    """
    out = {}
    for m, (X, _, _) in curves.items():
        try:
            c = modal_amplitude_curve(specimen, mode=m, amplitude=X)
        except ValueError as e:
            return f"mode {m}: {e}"
        out[m] = (np.asarray(c.frequency, float), np.asarray(c.damping_ratio, float))
    return out


def _score(read, curves, noise, offsets: bool = False) -> dict:
    """Per mode: chi-square, RMS in noise units, largest relative frequency and damping
    errors [-] of ``read`` against the measured curves (:func:`score_logs`).
    """
    logs = {}
    for m, (_, fm, zm) in curves.items():
        f, z = read[m]
        logs[m] = (np.log(f / fm), np.log(z / zm))
    return score_logs(logs, noise, offsets)


def score_logs(logs: dict, noise: dict, offsets: bool = False) -> dict:
    """Per mode, from the log residuals ``{mode: (ln f/f_m, ln zeta/zeta_m)}`` and the
    relative noise ``{mode: (s_f, s_z)}``: ``chi2``, ``rms`` (noise units), the largest
    relative errors ``frequency_error`` and ``damping_error`` [-], and the offsets [-]; with
    ``offsets``, after each curve's constant relative offset (the mean log residual, its
    least-squares value) is taken out.
    """
    out = {}
    for m, (lf, lz) in logs.items():
        of, oz = (float(np.mean(lf)), float(np.mean(lz))) if offsets else (0.0, 0.0)
        lf, lz = lf - of, lz - oz
        chi2 = float(np.sum((lf / noise[m][0]) ** 2) + np.sum((lz / noise[m][1]) ** 2))
        out[m] = {
            "chi2": chi2,
            "rms": math.sqrt(chi2 / (2 * max(lf.size, 1))),
            "frequency_error": float(np.max(np.abs(np.expm1(lf)), initial=0.0)),
            "damping_error": float(np.max(np.abs(np.expm1(lz)), initial=0.0)),
            "frequency_offset": -of,
            "damping_offset": -oz,
        }
    return out


def _diagnoses(specimen, curves, base, options) -> dict:
    """Each mode's vibration diagnosis against the plain joint's QSMA."""
    out = {}
    for m, (X, fm, zm) in curves.items():
        out[m] = diagnose_vibration(
            X,
            fm,
            zm,
            predicted_frequency=base[m][0],
            predicted_damping_ratio=base[m][1],
            **options,
        )
        log.info("mode %d: %s", m, out[m].verdict())
    return out


def _candidate(specimen, curves, noise, diag, mode, where, offsets) -> Candidate:
    """The effects ``diag`` named on ``mode``, in the joint at ``where``, read on every mode."""
    X = curves[mode][0]
    names = tuple(diag.effects)
    try:
        spec = resolve_interface_effects(
            specimen.with_effects(
                {n: dict(diag.parameters[n]) for n in names},
                mode=mode,
                calibrated_range=(float(X.min()), float(X.max())),
                form="physical",
                where=where,
            )
        )
    except ValueError as e:
        return Candidate(names, mode, where, reason=f"not mapped into the joint: {e}")
    placed = tuple(e.where for e in spec.interface_effects if e.name in names)
    read = _read(spec, curves)
    if isinstance(read, str):
        return Candidate(names, mode, where, placed=placed, reason=read)
    k = sum(len(diag.parameters[n]) for n in names)
    capped = tuple(
        e.name
        for e in spec.interface_effects
        if e.name in names and e.parameters.get("k_2", 0.0) >= 0.999 * stiffness_cap(spec, e)
    )
    return Candidate(
        names,
        mode,
        where,
        placed=placed,
        scores=_score(read, curves, noise, offsets),
        n_values=k,
        specimen=spec,
        read=read,
        values={e.name: e.parameters for e in spec.interface_effects if e.name in names},
        capped=capped,
    )


def diagnose_modes(
    specimen,
    measured,
    *,
    placements=None,
    amplitude_range=None,
    max_effects: int = 1,
    alpha: float = 1e-3,
    frequency_noise: float | None = None,
    damping_ratio_noise: float | None = None,
    offsets: bool = True,
) -> ModesDiagnosis:
    """Name the effect in the joint that closes the gaps between a specimen's modes and
    their measured curves (module docstring; ``docs/multi_mode.md`` section 6).

    Parameters
    ----------
    specimen : Specimen
        The calibrated specimen (joint and floors; e.g. ``HammerPrediction.calibration.
        specimen``). Not changed.
    measured : mapping
        ``{mode: AmplitudeCurve}``: each mode's measured curve at the specimen's sensor
        (amplitudes [m], frequencies [Hz], damping ratios [-]; at least 3 amplitudes), over
        the amplitudes the record resolves.
    placements : sequence of str, optional, keyword-only
        Where each named effect is tried (``"contact"``, ``"bolts"``, ``"bolt<k>"``,
        ``"under<k>"``);
        default :func:`default_placements`.
    amplitude_range : mapping, optional, keyword-only
        ``{mode: (low, high)}`` [m]: the amplitudes of each mode's curve the workflow reads
        (default all): the record's resolved amplitudes, above its noise floor.
    max_effects, alpha : keyword-only
        As in :func:`~iwan_element.diagnose_vibration`, for each mode's diagnosis.
    frequency_noise, damping_ratio_noise : float, optional, keyword-only
        Relative noise of every mode's curves [-]; default each diagnosis's estimate.
    offsets : bool, keyword-only
        Fit a constant relative offset of each mode's frequency and damping as nuisances,
        in every diagnosis (``between_tests``) and every candidate's score: for a floor read
        from a mode's own lowest amplitudes, or curves from another route or test (a
        transient's period error). A constant floor (viscous damping) is then not named.
        Default True: the workflow names what depends on amplitude; the constant part is
        the linear structure's (its update and floors).

    Returns
    -------
    ModesDiagnosis

    Raises
    ------
    ValueError
        A measured curve that is not an AmplitudeCurve or has fewer than 3 amplitudes, an
        unknown placement or a bolt the specimen lacks, or a plain joint whose QSMA fails at
        a measured amplitude.
    """
    places = _placements(specimen, placements)
    if amplitude_range is not None and not isinstance(amplitude_range, Mapping):
        raise ValueError("amplitude_range must be a {mode: (low, high)} mapping [m]")
    curves = _curves(measured, dict(amplitude_range or {}))
    options = {
        "max_effects": check_int("max_effects", max_effects, 1),
        "alpha": alpha,
        "frequency_noise": frequency_noise,
        "damping_ratio_noise": damping_ratio_noise,
        "between_tests": offsets,
    }
    base = _read(specimen, curves)
    if isinstance(base, str):
        raise ValueError(f"specimen: the plain joint's QSMA fails at a measured amplitude: {base}")
    diags = _diagnoses(specimen, curves, base, options)
    noise = {m: (d.frequency_noise, d.damping_ratio_noise) for m, d in diags.items()}
    plain = Candidate(
        (), 0, "", scores=_score(base, curves, noise, offsets), specimen=specimen, read=base
    )
    cands = []
    for m, d in diags.items():
        if not d.effects:
            continue
        seen = set()
        for p in places:
            c = _candidate(specimen, curves, noise, d, m, p, offsets)
            if c.placed and c.placed in seen:  # the mapping moved it where another went
                continue
            seen.add(c.placed)
            cands.append(c)
            log.info("%s", c.line())
    return ModesDiagnosis.build(plain, tuple(cands), diags, curves, spoil=SPOIL)
