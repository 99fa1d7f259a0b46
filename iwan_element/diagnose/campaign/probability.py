"""How sure a campaign's stack is (:mod:`.fit`): the probabilities of the explanations over
all records together, and the model-averaged prediction.

The records of one device share its explanation: the campaign's evidence of an explanation
is the product of the records' evidences (each record's noise independent of the others'),
``ln Z_M = sum_r ln Z_M,r``, over the explanations every record's diagnosis fitted (an
explanation some record did not fit is not compared); the prior is the diagnosis' default
or ``effect_prior`` over the candidates the records tested. The probabilities follow as for
one record (:mod:`..selection.probabilities`). Their model-averaged prediction at a
condition mixes the campaign models of every probable explanation
(:mod:`..selection.averaging`), each with its band from the law coefficients and the
record-to-record scatter.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import ndtri

from ...fitting.evidence import posterior_probabilities
from ..selection.averaging import MIN_WEIGHT, band, members
from ..selection.probabilities import Explanation, check_effect_prior, log_model_prior

if TYPE_CHECKING:
    from ..selection.averaging import AveragedBand

__all__ = ["record_explanations", "campaign_explanations", "campaign_band"]


def record_explanations(d) -> dict:
    """What the campaign keeps of a record's diagnosis ``d``: ``{"explanations": [[effects,
    ln Z, chi2, n_params]], "candidates": [...]}`` (JSON-safe).
    """
    cands = sorted(
        {n for e in d.explanations for n in e.effects} | set(d.details.get("candidates", ()))
    )
    return {
        "explanations": [
            [list(e.effects), float(e.log_evidence), float(e.chi2), int(e.n_params)]
            for e in d.explanations
        ],
        "candidates": cands,
    }


def campaign_explanations(preps, effect_prior=None) -> tuple:
    """The campaign's explanations with their probabilities (module docstring), most probable
    first; empty when a record has none (diagnosed without probabilities).
    """
    if not preps or any(not p.get("explanations") for p in preps):
        return ()
    common = None
    for p in preps:
        keys = {tuple(e[0]) for e in p["explanations"]}
        common = keys if common is None else common & keys
    if not common:
        return ()
    lz = dict.fromkeys(common, 0.0)
    chi2 = dict.fromkeys(common, 0.0)
    npar = dict.fromkeys(common, 0)
    for p in preps:
        for eff, z, c, q in p["explanations"]:
            k = tuple(eff)
            if k in lz:
                lz[k] += z
                chi2[k] += c
                npar[k] += q
    cands = sorted(
        {c for p in preps for c in p.get("candidates", ())} | {n for k in common for n in k}
    )
    prior = check_effect_prior(
        {k: v for k, v in effect_prior.items() if k in cands}
        if isinstance(effect_prior, dict)
        else effect_prior,
        tuple(cands),
    )
    lp = log_model_prior(list(common), prior)
    post = posterior_probabilities(lz, lp)
    out = [
        Explanation(
            effects=k,
            stack=k,
            chi2=chi2[k],
            n_params=npar[k],
            log_likelihood=math.nan,
            log_occam=math.nan,
            log_evidence=lz[k],
            log_prior=lp[k],
            probability=post[k],
            theta=np.zeros(0),
            covariance=np.zeros((0, 0)),
            log_evidence_laplace=lz[k],
        )
        for k in common
    ]
    return tuple(sorted(out, key=lambda e: -e.probability))


def campaign_band(fit, conditions, t, u, *, level: float = 0.95, **options) -> AveragedBand:
    """The model-averaged force at ``conditions`` under the drive ``(t, u)``: each probable
    explanation's campaign model (:attr:`CampaignFit.alternatives`, the fit itself for its
    own stack) predicts with its band (:meth:`CampaignFit.predict`, ``options`` passed on),
    read as a Gaussian of the band's half-width over the normal quantile; weights their
    probabilities.
    """
    parts, warns = [], []
    z = float(ndtri(0.5 * (1.0 + level)))
    mem = members(fit.explanations) if fit.explanations else []
    fits = dict(fit.alternatives)
    fits[tuple(sorted(fit.effects))] = fit
    for e, w in mem:
        f = fits.get(e.effects)
        if f is None:
            warns.append(
                f"{' + '.join(e.effects) or 'the plain joint'} (probability "
                f"{e.probability:.2g}) has no campaign model and is left out"
            )
            continue
        pr = f.predict(conditions, t, u, level=level, **options)
        parts.append((e.effects, w, {"force": (pr.force, (pr.upper - pr.lower) / (2 * z), "N")}))
        warns += list(pr.warnings)
    if not parts:
        pr = fit.predict(conditions, t, u, level=level, **options)
        parts = [
            (
                tuple(sorted(fit.effects)),
                1.0,
                {"force": (pr.force, (pr.upper - pr.lower) / (2 * z), "N")},
            )
        ]
    s = sum(p[1] for p in parts)
    parts = [(a, w / s, c) for a, w, c in parts]
    return band(
        np.asarray(t, float), "time [s]", parts, level, warnings=tuple(dict.fromkeys(warns))
    )


def probable_alternatives(explanations, stack) -> list:
    """Explanations other than ``stack`` probable enough to be averaged (their campaign
    models are fitted too).
    """
    return [
        e.effects
        for e in explanations
        if e.probability >= MIN_WEIGHT and set(e.effects) != set(stack)
    ]


__all__ += ["probable_alternatives"]
