"""Prediction of a campaign model at conditions, and its leave-one-out check; the methods
:meth:`~.result.CampaignFit.predict` and :meth:`~.result.CampaignFit.leave_one_out` call
these (equations in ``docs/campaign.md``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...base.result_shape import ResultShape, axes_or_new, table_lines
from ...base.serialize import json_safe
from ...base.validation import check_int, check_scalar, check_time, finite_array
from ...ensemble import run_ensemble
from ..loops import model as M
from ..loops.batch import band_misfit, executor_for
from . import model as CM
from .model import build_model, full_force, solve

__all__ = [
    "CampaignPrediction",
    "LeaveOneOut",
    "condition_vector",
    "predict",
    "leave_one_out",
    "predict_record",
    "draw_values",
]

LOO_TARGET = 1.5  # prediction band misfit / own fit's: the target


def condition_vector(cnames, conditions) -> np.ndarray:
    """``conditions`` (a dict with exactly the campaign's names) as a vector."""
    if not isinstance(conditions, dict) or set(map(str, conditions)) != set(cnames):
        got = sorted(map(str, conditions)) if isinstance(conditions, dict) else conditions
        raise ValueError(
            f"conditions must be a dict of the campaign's conditions {sorted(cnames)}, got {got!r}"
        )
    x = np.array([float(conditions[c]) for c in cnames])
    return finite_array("conditions", x, ndim=1)


@dataclass(frozen=True, eq=False)
class CampaignPrediction(ResultShape):
    """Predicted force history at a condition: ``force`` [N] and its band ``lower``,
    ``upper`` [N] (probability ``level``, from the law coefficients' uncertainty), with the
    law values used and ``warnings`` (extrapolation).
    """

    t: np.ndarray
    u: np.ndarray
    force: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    conditions: dict
    values: dict
    level: float

    @property
    def success(self) -> bool:
        """True when the force and its band are finite at every sample."""
        return bool(
            np.all(np.isfinite(self.force))
            and np.all(np.isfinite(self.lower))
            and np.all(np.isfinite(self.upper))
        )

    def to_dict(self) -> dict:
        """The prediction as a JSON-safe dict (times [s], displacements [m], forces [N])."""
        return json_safe(
            {
                k: getattr(self, k)
                for k in (
                    "t",
                    "u",
                    "force",
                    "lower",
                    "upper",
                    "conditions",
                    "values",
                    "level",
                    "warnings",
                )
            }
            | {"success": self.success}
        )

    def report(self) -> str:
        """Conditions, the law values used, the band's mean width, warnings."""
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        lines = [
            f"Prediction at {self.conditions} over {self.force.size} samples: {vals}",
            f"  {100 * self.level:g} % band: mean width "
            f"{float(np.mean(self.upper - self.lower)):.4g} N, largest "
            f"{float(np.max(self.upper - self.lower)):.4g} N",
        ]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def plot(self, ax=None, *, measured=None):
        """Force against displacement: the prediction, its band (as a shaded envelope in
        time order) and ``measured`` (a force array of the same length) if given. Returns
        the artists.
        """
        ax = axes_or_new(ax)
        arts = []
        if measured is not None:
            arts += ax.plot(
                self.u, np.asarray(measured, float), "-", lw=0.6, color="0.5", label="measured"
            )
        arts += ax.plot(self.u, self.force, "-", lw=0.8, label="predicted")
        arts += ax.plot(
            self.u, self.lower, ":", lw=0.5, color="C1", label=f"{100 * self.level:g} % band"
        )
        arts += ax.plot(self.u, self.upper, ":", lw=0.5, color="C1")
        ax.set_xlabel("u [m]")
        ax.set_ylabel("F [N]")
        ax.legend(fontsize=7)
        return arts


def _drive_record(model, theta, x, t, u):
    """A record dict for :class:`RecordModel` on a new drive (no measured force)."""
    vals = model.law_values(theta, x)
    shape = (
        math.exp(vals["log_phi_max"]),
        min(max(vals["chi"], M.CHI_BOUNDS[0]), M.CHI_BOUNDS[1]),
        math.expm1(min(max(vals["log1p_beta"], 0.0), math.log1p(M.BETA_MAX))),
    )
    return {
        "t": t,
        "u": u,
        "F": np.zeros(u.size),
        "keep": np.arange(u.size),
        "sigma": 1.0,
        "rms_own": 1.0,
        "tau_own": 1.0,
        "base_shape": shape,
    }


def _force(model, rm, vals, start):
    Fs, shape, effs = model.physical(vals, rm)
    rm.ev.set_start(start)
    return Fs * rm.ev.unit_force(shape, model.names, effs)


def draw_values(model, theta, cov, S, x, rng, draws):
    """``draws`` law-value dicts at conditions ``x``: coefficients from ``N(theta, cov)`` and,
    when ``S`` (the scatter covariance) is given, a record-to-record deviation from
    ``N(0, S)`` (:func:`.model.perturb`). Draws with ``Fs <= 0`` are left out.
    """
    ng = model.n_glob
    L = _chol(cov)
    Ls = None if S is None else _chol(S)
    out = []
    for _ in range(draws):
        th = theta.copy()
        th[:ng] = theta[:ng] + L @ rng.standard_normal(ng)
        vals = model.law_values(th, x)
        if Ls is not None:
            vals = CM.perturb(model, vals, Ls @ rng.standard_normal(Ls.shape[0]))
        if vals["Fs"] > 0:
            out.append(vals)
    return out


def predict(
    fit, conditions, t, u, *, F0=0.0, start=0.0, level=0.95, draws=64, rng=None, scatter=True
):
    """See :meth:`CampaignFit.predict`."""
    st = fit._state
    model, theta, cov = st["model"], st["theta"], st["cov_int"]
    x = condition_vector(fit.condition_names, conditions)
    uu = finite_array("u", u, ndim=1, min_size=3)
    tt = check_time(t, uu.size)
    F0 = check_scalar("F0", F0)
    start = check_scalar("start", start)
    level = check_scalar("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
    draws = check_int("draws", draws, 8)
    if not isinstance(scatter, bool):
        raise ValueError(f"scatter must be True or False, got {scatter!r}")
    rng = np.random.default_rng(0 if rng is None else rng)
    Fs = model.law_values(theta, x)["Fs"]
    if not Fs > 0:
        raise ValueError(
            f"the Fs law gives Fs = {Fs:.4g} N <= 0 at conditions {conditions}: "
            "the campaign model does not reach there"
        )
    rm = CM.RecordModel(_drive_record(model, theta, x, tt, uu), full=True)
    force = _force(model, rm, model.law_values(theta, x), start) + F0
    S = st.get("scatter_cov") if scatter else None
    if S is not None:
        cov = cov + st["cov_re"]
    samples = [
        _force(model, rm, v, start) + F0 for v in draw_values(model, theta, cov, S, x, rng, draws)
    ]
    warns = []
    if scatter and S is None:
        warns.append(
            "the fit holds no record-to-record scatter (fit_campaign(scatter=False)):"
            " the band is the coefficients' uncertainty only"
        )
    if len(samples) < draws:
        warns.append(
            f"{draws - len(samples)} of {draws} draws give Fs <= 0 here "
            "and are left out of the band"
        )
    if not samples:
        samples = [force]
    q = 0.5 * (1.0 - level)
    lo, hi = np.quantile(np.array(samples), [q, 1.0 - q], axis=0)
    for j, c in enumerate(fit.condition_names):
        a, b = float(model.X[:, j].min()), float(model.X[:, j].max())
        if not a <= x[j] <= b:
            warns.append(
                f"{c} = {x[j]:g} is outside the tested {a:g} .. {b:g}: the laws are extrapolated"
            )
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    return CampaignPrediction(
        t=ro(tt.copy()),
        u=ro(uu.copy()),
        force=ro(force),
        lower=ro(np.minimum(lo, force)),
        upper=ro(np.maximum(hi, force)),
        conditions=dict(zip(fit.condition_names, x.tolist())),
        values=model.law_values(theta, x),
        level=level,
        warnings=tuple(warns),
    )


def _chol(cov):
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    return V * np.sqrt(np.clip(w, 0.0, None))


def predict_record(model, theta, r, prep, bands=(), vals=None):
    """``(band misfit [N], coverages)`` of the device predicted from ``theta`` on record
    ``r``; the record's nuisances (force offset, starting state) are fitted to it once, with
    the device held. Each of ``bands``, ``(cov, S, draws, level, rng)``, gives one coverage:
    the share of the record's fitted samples in the misfit band (``|F| < 0.25 max|F|``)
    whose measured force lies in the prediction's band (coefficients from ``cov``, scatter
    from ``S``; nuisances held at the central prediction's), NaN where none can be drawn.
    ``vals``: law values to use instead of ``theta``'s (e.g. some of the record's own, to
    attribute the misfit).
    """
    best = (math.inf, 0.0)
    vals = model.law_values(theta, model.X[r]) if vals is None else vals
    for g in M.START_GRID:
        s = g * model.records[r].x_max
        m = model.record_force(theta, r, vals=vals, start=s)
        if m is not None:
            e = model.records[r].y - m
            best = min(best, (float(np.var(e)), s))
    F, F0 = full_force(model, theta, r, prep, vals=vals, start=best[1])
    if F is None:
        return math.nan, [math.nan] * len(bands)
    y = model.records[r].y
    mask = np.abs(y) < CM.BAND * np.abs(prep["F"]).max()
    coverages = []
    for cov, S, draws, level, rng in bands:
        forces = [
            model.record_force(theta, r, vals=v, start=best[1])
            for v in draw_values(model, theta, cov, S, model.X[r], rng, draws)
        ]
        forces = [f + F0 for f in forces if f is not None]
        if not forces or not mask.any():
            coverages.append(math.nan)
            continue
        q = 0.5 * (1.0 - level)
        lo, hi = np.quantile(np.array(forces), [q, 1.0 - q], axis=0)
        coverages.append(float(((y >= lo) & (y <= hi))[mask].mean()))
    return band_misfit(prep["F"], F, CM.BAND), coverages


def _loo_step(model, theta, J, i):
    """One Gauss-Newton step from the full fit to the fit without record ``i`` (the weighted
    normal equations with its rows and its start column removed).
    """
    rows = np.r_[0 : model.rows[i], model.rows[i + 1] : model.rows[-1]]
    cols = [k for k in range(model.n_theta) if k != model.start_pos.get(i, -1)]
    w = np.concatenate([np.full(rm.y.size, rm.weight) for rm in model.records])
    r = model.residual(theta)[rows]
    Jw = J[rows][:, cols] * w[rows, None]
    delta, *_ = np.linalg.lstsq(Jw, -r, rcond=1e-10)
    th = theta.copy()
    th[cols] += delta
    return th


def _loo_predict(model, th, i, prep, free, cov, cover) -> dict:
    """Band misfit of record ``i`` predicted from ``th`` and, when ``cover = (draws, level,
    seed)``, the coverage of its band samples by the prediction band with the scatter read
    from the other records (``coverage``) and by the coefficients' band alone
    (``coverage_coef``).
    """
    if cover is None:
        return {
            "band_pred": predict_record(model, th, i, prep)[0],
            "coverage": math.nan,
            "coverage_coef": math.nan,
        }
    draws, level, seed = cover
    S, cov_s = None, cov
    if free is not None:
        D, dof = CM.deviations(model, th, free, skip=i)
        if D.shape[0] >= 2:
            S = CM.scatter_cov(D, dof)
            cov_s = cov + CM.scatter_coef_cov(model, th, S, skip=i)
    rng = np.random.default_rng([seed, i])
    band, (cov_re, cov_coef) = predict_record(
        model, th, i, prep, ((cov_s, S, draws, level, rng), (cov, None, draws, level, rng))
    )
    return {
        "band_pred": band,
        "coverage": cov_re if S is not None else math.nan,
        "coverage_coef": cov_coef,
    }


def _loo_task(params, rng):
    """Refit without record ``i`` (warm start), predict it (module level: picklable)."""
    del rng
    i, preps = params["i"], params["preps"]
    X = params["X"]
    others = [k for k in range(len(preps)) if k != i]
    sub = build_model(
        [preps[k] for k in others], params["names"], params["laws"], params["cnames"], X[others]
    )
    sub.centre, sub.cscale, sub.qscale = params["centre"], params["cscale"], params["qscale"]
    full = build_model(preps, params["names"], params["laws"], params["cnames"], X)
    full.centre, full.cscale, full.qscale = sub.centre, sub.cscale, sub.qscale
    theta = params["theta"]
    th0 = np.concatenate(
        [theta[: full.n_glob], [theta[full.start_pos[k]] for k in others if k in full.start_pos]]
    )
    res = solve(sub, th0, max_nfev=params["max_nfev"])
    th = theta.copy()
    th[: full.n_glob] = res.x[: full.n_glob]
    out = _loo_predict(full, th, i, preps[i], params["free"], params["cov"], params["cover"])
    return dict(out, nfev=int(res.nfev), status=int(res.status))


@dataclass(frozen=True, eq=False)
class LeaveOneOut(ResultShape):
    """Per record: the band misfit [N] of its prediction from the other records, of its own
    fit, their ratio, and the share of records within :data:`LOO_TARGET` (1.5); with
    ``coverage=True`` also the share of its band samples inside the prediction band, with
    the record-to-record scatter (``coverage``) and without it (``coverage_coef``), and
    their medians over the records (``coverage``, ``coverage_coef``, NaN if not asked).
    """

    rows: tuple
    refit: str
    share_within: float
    wall_time: float
    coverage: float = math.nan
    coverage_coef: float = math.nan
    level: float = 0.95

    @property
    def success(self) -> bool:
        """True when at least 80 % of the records are predicted within 1.5x their own fit."""
        return self.share_within >= 0.8

    def report(self) -> str:
        """Plain-text table: each record's leave-one-out band misfit [N] against its own fit's."""
        lines = [
            f"Leave-one-out ({self.refit}): {100 * self.share_within:.0f} % of "
            f"{len(self.rows)} records predicted within {LOO_TARGET:g}x their own fit's "
            f"band misfit ({self.wall_time:.1f} s)"
        ]
        lines += table_lines(
            [
                ("record", "<26"),
                ("own [N]", "9.4g"),
                ("predicted [N]", "13.4g"),
                ("ratio", "6.2f"),
                ("in band", "8.2f"),
                ("coef only", "9.2f"),
            ],
            [
                [
                    r[k]
                    for k in (
                        "record",
                        "band_own",
                        "band_pred",
                        "ratio",
                        "coverage",
                        "coverage_coef",
                    )
                ]
                for r in self.rows
            ],
        )
        if math.isfinite(self.coverage_coef):
            lines.append(
                f"  band samples inside the {100 * self.level:g} % prediction band "
                f"(median over records): {100 * self.coverage:.0f} % with the "
                f"record-to-record scatter, {100 * self.coverage_coef:.0f} % with the "
                "coefficients' uncertainty only"
            )
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def plot(self, ax=None):
        """Ratio of the prediction's band misfit to the own fit's per record (bars), with the
        1.5 target. Returns the artists.
        """
        ax = axes_or_new(ax)
        x = np.arange(len(self.rows))
        arts = list(ax.bar(x, [r["ratio"] for r in self.rows], 0.6))
        arts.append(ax.axhline(LOO_TARGET, color="k", ls="--", lw=0.8))
        ax.set_xticks(x, [r["record"] for r in self.rows], rotation=60, ha="right", fontsize=7)
        ax.set_ylabel("band misfit: leave-one-out prediction / own fit")
        return arts

    def to_dict(self) -> dict:
        """The leave-one-out result as a JSON-safe dict (misfits [N], shares in 0..1)."""
        return json_safe(
            {
                "rows": list(self.rows),
                "refit": self.refit,
                "share_within": self.share_within,
                "success": self.success,
                "coverage": self.coverage,
                "coverage_coef": self.coverage_coef,
                "level": self.level,
                "wall_time": self.wall_time,
                "warnings": list(self.warnings),
            }
        )


def leave_one_out(
    fit,
    *,
    refit="step",
    jobs=1,
    client=None,
    progress=False,
    max_nfev=20,
    coverage=False,
    draws=32,
    level=0.95,
    seed=0,
):
    """Predict each record from the campaign fitted without it.

    ``refit="step"``: one Gauss-Newton step from the full fit on the normal equations without
    the record (no new model evaluations but the prediction's); ``"full"``: a warm-started
    least-squares refit per record, on ``jobs`` local processes or a Dask ``client``. The
    prediction holds the device at the laws; the record's nuisances (force offset, starting
    state on :data:`..loops.model.START_GRID`) are fitted to it. ``coverage=True`` also draws
    ``draws`` devices per record (coefficients from the full fit's covariance, scatter read
    from the other records) and states how much of the record's band the ``level`` band
    holds. Returns :class:`LeaveOneOut`.
    """
    if refit not in ("step", "full"):
        raise ValueError(f"refit must be 'step' or 'full', got {refit!r}")
    jobs = check_int("jobs", jobs, 1)
    max_nfev = check_int("max_nfev", max_nfev, 1)
    if not isinstance(coverage, bool):
        raise ValueError(f"coverage must be True or False, got {coverage!r}")
    draws = check_int("draws", draws, 8)
    level = check_scalar("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
    seed = check_int("seed", seed, 0)
    cover = (draws, level, seed) if coverage else None
    t0 = time.perf_counter()
    st = fit._state
    model, theta, preps = st["model"], st["theta"], st["preps"]
    n = len(preps)
    if n < 3:
        raise ValueError(f"leave_one_out needs at least 3 records, the campaign has {n}")
    warns = []
    if refit == "step":
        outs = [
            _loo_predict(
                model,
                _loo_step(model, theta, st["J"], i),
                i,
                preps[i],
                st.get("free"),
                st["cov_int"],
                cover,
            )
            for i in range(n)
        ]
    else:
        common = {
            "preps": preps,
            "X": model.X,
            "names": model.names,
            "laws": model.laws,
            "cnames": model.cnames,
            "centre": model.centre,
            "cscale": model.cscale,
            "qscale": model.qscale,
            "theta": theta,
            "max_nfev": max_nfev,
            "free": st.get("free"),
            "cov": st["cov_int"],
            "cover": cover,
        }
        ex = executor_for(jobs, client)
        try:
            res = run_ensemble(
                _loo_task,
                [dict(common, i=i) for i in range(n)],
                executor=ex,
                seed=0,
                progress=progress,
            )
        finally:
            if ex is not client and not isinstance(ex, str):
                ex.shutdown()
        nan = {"band_pred": math.nan, "coverage": math.nan, "coverage_coef": math.nan}
        outs = [{k: float(r.get(k, math.nan)) for k in nan} if r else nan for r in res.rows]
        warns += [f"{fit.records[e.index]}: {e.message}" for e in res.errors]
        warns += [
            f"{fit.records[i]}: the refit without it did not converge"
            for i, r in enumerate(res.rows)
            if r.get("status", 1) == 0
        ]
    rows = tuple(
        {
            "record": fit.records[i],
            "conditions": fit.rows[i]["conditions"],
            "band_own": preps[i]["band_own"],
            "band_pred": o["band_pred"],
            "ratio": (
                o["band_pred"] / preps[i]["band_own"] if preps[i]["band_own"] > 0 else math.nan
            ),
            "coverage": o["coverage"],
            "coverage_coef": o["coverage_coef"],
        }
        for i, o in enumerate(outs)
    )
    warns += [
        f"{r['record']}: the laws from the other records give no model there (Fs <= 0 "
        "or an evaluation failure): not predicted, counted as a miss"
        for r in rows
        if not math.isfinite(r["band_pred"])
    ]
    within = float(np.mean([r["ratio"] <= LOO_TARGET for r in rows]))
    med = {
        k: float(np.nanmedian([r[k] for r in rows])) if coverage else math.nan
        for k in ("coverage", "coverage_coef")
    }
    return LeaveOneOut(
        rows=rows,
        refit=refit,
        share_within=within,
        wall_time=time.perf_counter() - t0,
        warnings=tuple(warns),
        level=level,
        **med,
    )
