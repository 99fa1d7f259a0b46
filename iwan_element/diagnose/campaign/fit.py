"""One device model over a whole test campaign: parameter laws in the test conditions.

:func:`fit_campaign` takes the records of one device tested at several conditions (band
tension, drive frequency, stroke, ...) and fits **one** model of the device whose parameters
are stated smooth functions of the conditions, so that the device can be predicted at a
condition that was not tested (:meth:`CampaignFit.predict`). The procedure
(equations in ``docs/campaign.md``):

1. every record is diagnosed on its own (:func:`~iwan_element.diagnose`, in parallel through
   :func:`~iwan_element.ensemble.run_ensemble`): the effects it names, its own fit (the
   yardstick of the campaign model), its noise and the record as fitted (offsets, low-pass);
2. the campaign's effect stack is the most probable explanation over all records together
   (the product of the records' evidences, :mod:`.probability`; the effects named
   on at least half of the records when they were diagnosed without probabilities), or
   ``effects=``; every other explanation probable enough to be averaged gets its own
   campaign model (``CampaignFit.alternatives``, for :meth:`CampaignFit.averaged_band`);
   each quantity ``q`` of the stack (``Fs``, ``ln phi_max``, ``chi``, ``ln(1 + beta)``, every effect
   parameter per ``Fs**fs_power``, as ``ln(value - lower)``
   when it is bounded on one side only, e.g. a gap or a drag) follows a law linear in
   the conditions, ``q = a + sum_c b_c x_c`` (by default in every condition that varies;
   ``laws=`` states others, e.g. ``{"chi": ()}`` for a constant);
3. one weighted least-squares fit over all records (scipy ``least_squares``, sparse Jacobian
   structure), warm-started by regressing the per-record estimates on the conditions; the
   per-record nuisances are the force offset (eliminated in closed form) and the joint's
   starting state where the record's diagnosis fitted one; each record is weighted by
   ``1 / (s_r sqrt(tau_r))`` with ``s_r`` the larger of its noise and its own fit's RMS
   misfit and ``tau_r`` that misfit's correlation time, so a record with 10x larger forces
   does not swamp the others;
4. the law coefficients' covariance by the delta method on the whole, each record's
   residual variance estimated from the campaign residual on that record and inflated by
   its correlation time;
5. agreement: per record, the effects it named against the campaign stack and its own
   estimates against the law (z-scores); disagreements are stated in ``warnings``;
6. the record-to-record scatter about the laws (``scatter=True``): every record refitted
   alone with the campaign's stack, the covariance of its deviations from the laws (a
   random effect the conditions do not predict), carried in the prediction band and in
   the coefficients' ``stderr_scatter``.
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import replace

import numpy as np

from ...base.progress import complete, finish, progress_bar
from ...base.serialize import json_safe
from ...base.validation import check_int
from ...effects import EFFECTS
from ...effects.engine.evaluate import order_stack, stack_ok
from ...ensemble import run_ensemble
from ..loops.batch import check_options, check_records, executor_for
from ..loops.diagnosis import diagnose
from . import model as CM
from .assemble import assemble
from .model import build_model, solve
from .probability import campaign_explanations, probable_alternatives
from .result import CampaignFit
from .scatter import in_range

__all__ = ["fit_campaign", "CampaignFit"]

log = logging.getLogger(__name__)
_ARRAYS = ("t", "u", "F", "keep")


def _record_task(params, rng):
    """Diagnose one record and keep what the campaign fit needs (module level: picklable)."""
    del rng
    d = diagnose(params["t"], params["u"], params["F"], **params["options"])
    return _pack(CM.record_from_diagnosis(d, params["max_samples"]))


def _pack(prep: dict) -> dict:
    out: dict[str, np.ndarray | str] = {f"prep_{k}": np.asarray(prep[k], float) for k in _ARRAYS}
    out["meta"] = json.dumps(json_safe({k: v for k, v in prep.items() if k not in _ARRAYS}))
    return out


def _unpack(row: dict) -> dict:
    prep = {k: np.asarray(row[f"prep_{k}"], float) for k in _ARRAYS}
    prep["keep"] = prep["keep"].astype(np.intp)
    meta = json.loads(row["meta"])
    meta["effects"] = tuple(meta["effects"])
    meta["base_shape"] = tuple(meta["base_shape"])
    for key in ("estimates", "stderr"):
        meta[key] = {k: (math.nan if v is None else float(v)) for k, v in meta[key].items()}
    prep.update(meta)
    return prep


def _diagnose_records(recs, labels, opts, diagnoses, jobs, client, progress):
    """Per-record preparations (None where a record could not be diagnosed) and warnings."""
    max_samples = int(opts.get("max_samples", diagnose.__kwdefaults__["max_samples"]))
    if diagnoses is not None:
        diags = list(diagnoses)
        if len(diags) != len(recs):
            raise ValueError(
                f"diagnoses must hold one Diagnosis per record ({len(recs)}), got {len(diags)}"
            )
        for i, (d, r) in enumerate(zip(diags, recs)):
            if getattr(d, "F", None) is None or np.asarray(d.F).size != r[2].size:
                raise ValueError(
                    f"diagnoses[{i}] is not a Diagnosis of records[{i}] (its "
                    "force has another length)"
                )
        return [CM.record_from_diagnosis(d, max_samples) for d in diags], []
    sets = [
        {"t": t, "u": u, "F": F, "options": opts, "max_samples": max_samples} for t, u, F in recs
    ]
    ex = executor_for(jobs, client)
    try:
        res = run_ensemble(_record_task, sets, executor=ex, seed=0, progress=progress)
    finally:
        if ex is not client and not isinstance(ex, str):
            ex.shutdown()
    bad = {e.index: e.message for e in res.errors}
    preps, warns = [], []
    for i, row in enumerate(res.rows):
        if i in bad:
            preps.append(None)
            warns.append(f"{labels[i]} was not diagnosed and is left out: {bad[i]}")
        else:
            preps.append(_unpack(row))
    return preps, warns


def _common_stack(preps, effects, explanations=()):
    """The campaign's effect stack: ``effects``, or the most probable explanation over all
    records (:mod:`.probability`), or (records diagnosed without probabilities)
    the effects named on >= half the records.
    """
    if effects is not None:
        names = (effects,) if isinstance(effects, str) else tuple(effects)
        unknown = [n for n in names if n not in EFFECTS]
        if unknown:
            raise ValueError(f"effects names {unknown}; known effects are {sorted(EFFECTS)}")
        names = order_stack(dict.fromkeys(names))
        if not stack_ok(names):
            raise ValueError(
                f"effects {list(names)} cannot share one joint (at most one "
                "slider-level effect unless all are composable)"
            )
        return names, "given"
    if explanations and stack_ok(order_stack(explanations[0].effects)):
        top = explanations[0]
        return order_stack(top.effects), (
            f"the most probable explanation over the records, probability {top.probability:.3g}"
        )
    count = {}
    for p in preps:
        for nm in p["effects"]:
            count[nm] = count.get(nm, 0) + 1
    names = [nm for nm, c in sorted(count.items(), key=lambda kv: -kv[1]) if 2 * c >= len(preps)]
    kept = []
    for nm in names:  # most named first, as long as they can share
        if stack_ok(tuple(kept) + (nm,)):
            kept.append(nm)
    return order_stack(kept), "named on at least half of the records"


def _start_values(model, preps):
    """Law start: each quantity's per-record estimates regressed on its conditions (records
    without an estimate, e.g. an effect they did not name, left out of that regression).
    """
    theta = np.zeros(model.n_theta)
    for q in model.qnames:
        A = CM.design(model.X, model.cnames, model.laws[q], model.centre, model.cscale)
        y = np.array([p["estimates"].get(q, math.nan) for p in preps]) / model.qscale[q]
        ok = np.isfinite(y)
        if ok.sum() >= A.shape[1]:
            c, *_ = np.linalg.lstsq(A[ok], y[ok], rcond=None)
        else:
            c = np.zeros(A.shape[1])
            c[0] = float(np.median(y[ok])) if ok.any() else _no_effect(model, q)
        theta[model.slices[q]] = c
    for r, k in model.start_pos.items():
        theta[k] = preps[r]["start"] / model.records[r].x_max
    return theta


def _no_effect(model, q) -> float:
    """An effect parameter's first non-zero fitting start, in internal units (the law's
    internal scale is the physical value of fitting variable 1, :func:`build_model`).
    """
    nm, sp = CM.quantities(model.names)[2][q]
    z = float(sp.fit_starts[min(1, len(sp.fit_starts) - 1)])
    if not CM.log_form(sp):
        return z
    unit = float(np.median([rm.scales[sp.ref] ** -sp.ref_power for rm in model.records]))
    return CM.to_law(sp, max(sp.lower + z * unit, sp.lower + 1e-3 * unit))


def record_values(model, theta, preps, *, max_nfev: int = 60):
    """Each record's own values with the campaign's stack (its quantities fitted to it alone,
    every law a constant; warm-started at its own estimates, else at the laws), in the form
    :func:`.scatter.in_range` gives; None where that fit fails. The record-to-record
    scatter about the laws is read from them (:func:`.model.deviations`).
    """
    out: list[dict | None] = []
    for r, p in enumerate(preps):
        sub = build_model(
            [p], model.names, dict.fromkeys(model.qnames, ()), model.cnames, model.X[[r]]
        )
        law = model.law_values(theta, model.X[r])
        th0 = np.zeros(sub.n_theta)
        for q in sub.qnames:
            e = p["estimates"].get(q, math.nan)
            th0[sub.slices[q]] = (e if math.isfinite(e) else law[q]) / sub.qscale[q]
        if sub.start_pos:
            th0[-1] = p["start"] / sub.records[0].x_max
        try:
            res = solve(sub, th0, max_nfev=max_nfev)
        except (ValueError, FloatingPointError) as exc:
            log.info("record %d: its own fit with the campaign stack failed (%s)", r, exc)
            out.append(None)
            continue
        vals = sub.law_values(res.x, sub.X[0])
        out.append(in_range(model, vals, model.records[r]) if vals["Fs"] > 0 else None)
    return out


def _check_input(records, conditions, names, laws, effects, jobs, max_nfev, options, scatter):
    """Everything that can be checked before the records are diagnosed."""
    if not isinstance(scatter, bool):
        raise ValueError(f"scatter must be True or False, got {scatter!r}")
    recs, labels = check_records(records, names)
    cnames, X = CM.check_conditions(conditions, len(recs))
    opts = check_options(options)
    check_int("jobs", jobs, 1)
    check_int("max_nfev", max_nfev, 1)
    CM.precheck_laws(laws, cnames, X)
    if effects is not None:
        _common_stack([], effects)
    return recs, labels, cnames, X, opts


def fit_campaign(
    records,
    conditions,
    *,
    effects=None,
    laws=None,
    names=None,
    diagnoses=None,
    jobs: int = 1,
    client=None,
    progress: bool = False,
    max_nfev: int = 100,
    scatter: bool = True,
    **options,
) -> CampaignFit:
    """Fit one device model over a test campaign, its parameters laws of the conditions.

    See the module docstring for the procedure and ``docs/campaign.md`` for the equations.

    Parameters
    ----------
    records : sequence of (t, u, F)
        Time [s], displacement [m] and force [N] of each test, as :func:`~iwan_element.diagnose`
        takes them. Not modified.
    conditions : sequence of dict
        Per record the named test conditions, the same names for every record, finite numbers
        (e.g. ``{"tension": 30.0, "frequency": 0.5}``: band tension [lb], drive frequency [Hz]).
    effects : sequence of str, optional, keyword-only
        The campaign's effect stack (default: the most probable explanation over all the
        records; with records diagnosed without probabilities, the effects named on at
        least half of them).
    laws : dict, optional, keyword-only
        ``{quantity: conditions}`` for quantities whose law is not linear in every condition
        that varies (the default), e.g. ``{"Fs": ("tension",), "chi": ()}``. Quantities:
        ``Fs`` [N], ``log_phi_max`` [ln m], ``chi``, ``log1p_beta`` and per effect parameter
        ``"<effect>.<param>"`` (``"/Fs"`` appended for a force-scaled one; in ``ln(...)`` for
        one bounded on one side, e.g. ``"ln(backlash.gap)"``, ``"ln(backlash.drag/Fs)"``,
        ``"ln(breakaway.ratio - 1)"``, ``"asymmetric_slip.asymmetry"``).
    names : sequence of str, optional, keyword-only
        A label per record (default ``"record i"``).
    diagnoses : sequence of Diagnosis, optional, keyword-only
        The records' diagnoses, already made with ``options``; they are then not repeated.
    jobs : int, keyword-only
        Local processes for the per-record diagnoses (1: in this process).
    client : dask.distributed.Client, optional, keyword-only
        Run the per-record diagnoses on this Dask cluster instead.
    progress : bool, keyword-only
        tqdm progress bars: records diagnosed, then model evaluations of the joint fit.
    max_nfev : int, keyword-only
        Most evaluations of the joint fit's objective (``>= 1``, scipy's count: those of its
        finite-difference Jacobians, one per law coefficient plus one per iteration, are not
        counted; default 100).
    scatter : bool, keyword-only
        Estimate the record-to-record scatter about the laws (each record refitted alone
        with the campaign's stack, a few seconds per record) and carry it in the prediction
        band (default True). Without it the band holds the coefficients' uncertainty only,
        which is honest only when the conditions determine the device.
    **options
        Options of :func:`~iwan_element.diagnose` for every record (e.g. ``lowpass=20``).

    Returns
    -------
    CampaignFit

    Raises
    ------
    ValueError
        Records that are not triples of finite arrays, conditions that differ in their names
        or are not finite numbers, a law in an unknown quantity or condition, in a condition
        that does not vary, or with more coefficients than records, an unknown option.
    """
    t0 = time.perf_counter()
    recs, labels, cnames, X, opts = _check_input(
        records, conditions, names, laws, effects, jobs, max_nfev, options, scatter
    )
    preps, warns = _diagnose_records(recs, labels, opts, diagnoses, jobs, client, progress)
    ok = [i for i, p in enumerate(preps) if p is not None]
    preps, labels, X = [preps[i] for i in ok], [labels[i] for i in ok], X[ok]
    if not preps:
        raise ValueError("no record could be diagnosed: nothing to fit")
    t_diag = time.perf_counter() - t0
    expl = campaign_explanations(preps, opts.get("effect_prior"))
    names_, stack_from = _common_stack(preps, effects, expl)
    args = dict(
        preps=preps,
        labels=labels,
        X=X,
        laws=laws,
        cnames=cnames,
        max_nfev=max_nfev,
        scatter=scatter,
        progress=progress,
        opts=opts,
        t0=t0,
        t_diag=t_diag,
    )
    fit = _fit_stack(names_, stack_from, warns, **args)
    alts = {}
    for alt in probable_alternatives(expl, names_):
        if stack_ok(order_stack(alt)):
            alts[alt] = _fit_stack(order_stack(alt), "an alternative explanation", [], **args)
    return replace(fit, explanations=expl, alternatives=alts)


def _fit_stack(
    names_,
    stack_from,
    warns,
    *,
    preps,
    labels,
    X,
    laws,
    cnames,
    max_nfev,
    scatter,
    progress,
    opts,
    t0,
    t_diag,
):
    """The campaign model with the stack ``names_`` fitted to the prepared records: laws,
    joint fit, record scatter, result (steps 2-6 of the module docstring).
    """
    qnames, units, _ = CM.quantities(names_)
    laws_, lwarn = CM.resolve_laws(laws, qnames, cnames, X)
    model = build_model(preps, names_, laws_, cnames, X)
    theta0 = _start_values(model, preps)
    # the budget: max_nfev iterations, each one evaluation and at most one per coefficient for
    # the finite-difference Jacobian (the ETA is an upper bound; a converged fit completes it)
    budget = max_nfev * (1 + np.size(theta0))
    bar = progress_bar(progress, total=budget, desc="campaign fit", unit="eval")
    try:
        t1 = time.perf_counter()
        res = solve(model, theta0, max_nfev=max_nfev, bar=bar)
        t_fit = time.perf_counter() - t1
        complete(bar, "converged" if res.status > 0 else "stopped")
    finally:
        finish(bar)
    t2 = time.perf_counter()
    free = record_values(model, res.x, preps) if scatter else None
    times = {"diagnoses": t_diag, "joint_fit": t_fit, "scatter": time.perf_counter() - t2}
    return assemble(
        model=model,
        preps=preps,
        labels=labels,
        res=res,
        units=units,
        stack_from=stack_from,
        warnings=warns + lwarn,
        options=opts,
        times=times,
        t0=t0,
        free=free,
    )
