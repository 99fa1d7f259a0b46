"""The report stage of a loop diagnosis: the :class:`~.result.Diagnosis` of a record.

It reads what the earlier stages returned (the prepared record, its noise level, the
selection and the fitted stacks) and states it: where the plain joint misfits
(:func:`.locate._locate`), what the selection leaves unexplained, the starting state, the
details. It fits nothing.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ...base.serialize import json_safe
from ..selection.rule import criterion_text
from .locate import _locate
from .result import Diagnosis

__all__ = ["assemble"]


def assemble(rec, sel, fits, opts, t_start) -> Diagnosis:
    """The diagnosis of the prepared record ``rec`` from the selection ``sel``
    (:class:`~.loops.LoopSelection`) and the fitted stacks ``fits``
    (:class:`~.fit.FinalFits`); ``opts``: the rule's options, ``t_start``: when it began.
    """
    FF, uj, alpha, nl = rec.F, rec.uj, opts["alpha"], sel.noise
    warns = [f"noise estimate: {w}" for w in nl.warnings]
    if sel.noise_only:
        warns.append(
            "the force is indistinguishable from noise (the Iwan model explains no "
            "more than a constant): nothing is identified"
        )
    final, F_base, F_after, fit = fits.final, fits.F_base, fits.F_after, fits.fit
    misfit = sel.p_before < alpha and not sel.noise_only
    r0 = FF - F_base
    where, loc = (
        _locate(rec.t, uj, FF, F_base, r0, sel.cycles, nl.sigma, nl.tau) if sel.cycles else ("", {})
    )
    if not misfit:
        where = (
            f"The residual is consistent with the noise (RMS {np.sqrt(np.mean(r0**2)):.3g} "
            f"N vs {nl.sigma:.3g} N); there is no misfit to explain."
        )
    unexplained = _verdict_warnings(sel, misfit, alpha)
    warns += unexplained
    details = _details(rec, nl, sel, opts, loc, final, fit, t_start)
    if final.get("start", 0.0) != 0.0:
        warns.append(
            f"the record does not start from the joint's rest: a path to "
            f"{final['start']:.4g} +- {details['start_displacement_stderr']:.2g} m "
            "before the first sample (the joint's unknown "
            "starting state, fitted as a nuisance) fits better"
        )
    span = float(np.ptp(FF)) or 1.0
    steps = [
        {
            "on": st["on"],
            "candidates": [
                {
                    k: r.get(k)
                    for k in ("name", "nrmse", "ratio", "dIC", "explained", "verdict", "message")
                }
                for r in st["rows"]
            ],
        }
        for st in sel.steps
    ]
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    return Diagnosis(
        effect=sel.named[0] if sel.named else "none",
        effects=tuple(sel.named),
        ambiguous_with=sel.ambiguous,
        where=where,
        success=bool(not sel.noise_only and fit.success and not unexplained),
        failures=_failures(sel, fit, unexplained),
        offsets={"force": fit.details["force_offset"], "displacement": rec.u_offset},
        error_before=float(np.sqrt(np.mean(r0**2)) / span),
        error_after=float(np.sqrt(np.mean((FF - F_after) ** 2)) / span),
        noise_level=nl.sigma / span,
        noise_sigma=float(nl.sigma),
        misfit=bool(misfit),
        base_fit=fits.base_fit,
        fit=fit,
        model=fits.model,
        steps=tuple(json_safe(s) for s in steps),
        untestable=sel.untestable,
        warnings=tuple(warns),
        force_before=ro(F_base),
        force_after=ro(np.array(F_after)),
        t=ro(np.arange(rec.n, dtype=float) if rec.t is None else rec.t),
        u=ro(rec.u),
        F=ro(FF),
        details=json_safe(details),
        explanations=sel.explanations,
    )


def _failures(sel, fit, unexplained) -> tuple:
    """Why the diagnosis is not usable (docs/guards.md), in a tester's words."""
    if sel.noise_only:
        return ("the force is indistinguishable from noise: nothing is identified",)
    return tuple(unexplained) + tuple(fit.failure_reasons())


def _verdict_warnings(sel, misfit, alpha) -> list:
    """What the selection leaves unexplained."""
    if misfit and sel.named and sel.p_after < alpha:
        return [f"misfit well beyond the noise remains after {' + '.join(sel.named)}"]
    if misfit and not sel.named:
        return [
            "misfit well beyond the noise remains: no tested effect explains it"
            + (f"; this record cannot reveal {', '.join(sel.untestable)}" if sel.untestable else "")
        ]
    return []


def _details(rec, nl, sel, opts, loc, final, fit, t_start) -> dict:
    """The diagnosis' ``details``: sizes, noise, tests, location and the starting state."""
    return {
        "samples": rec.n,
        "fitted_samples": int(rec.keep.size),
        "tau": nl.tau,
        "n_eff": nl.n_eff,
        "noise_from": nl.text,
        "misfit_p": sel.p_before,
        "misfit_p_after": sel.p_after,
        "alpha": opts["alpha"],
        "ambiguity": opts["ambiguity"],
        "criterion": criterion_text(),
        "location": loc,
        "lowpass": rec.lowpass,
        "lowpass_reason": "rig dynamics removed before fitting" if rec.lowpass else None,
        "start_displacement": float(final.get("start", 0.0)),
        "rule_named": list(sel.rule_named),
        "time_given": rec.t is not None,
        "candidates": list(sel.candidates),
        "x_max": float(rec.ev.x_max),
        "scales": dict(final["model"].scales),
        "start_displacement_stderr": float(
            math.nan if (se_s := fit.details.get("start_displacement_stderr")) is None else se_s
        ),  # None: not determined
        "wall_time": time.perf_counter() - t_start,
    }
