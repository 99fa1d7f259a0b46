"""The leave-one-out check of a campaign model: each record predicted from the campaign
fitted without it (one Gauss-Newton step or a full warm-started refit), and its result
:class:`LeaveOneOut`; :meth:`~.result.CampaignFit.leave_one_out` calls it (equations in
``docs/campaign.md``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, axes_or_new, table_lines
from ...base.serialize import json_safe
from ...base.validation import check_int, check_scalar
from ...ensemble import run_ensemble
from ..loops.batch import executor_for
from .model import build_model, solve
from .predict import predict_record
from .scatter import deviations, scatter_coef_cov, scatter_cov

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["LeaveOneOut", "leave_one_out"]

LOO_TARGET = 1.5  # prediction band misfit / own fit's: the target


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
        D, dof = deviations(model, th, free, skip=i)
        if D.shape[0] >= 2:
            S = scatter_cov(D, dof)
            cov_s = cov + scatter_coef_cov(model, th, S, skip=i)
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
            self.verdict(),
            f"Leave-one-out ({self.refit}): {100 * self.share_within:.0f} % of "
            f"{len(self.rows)} records predicted within {LOO_TARGET:g}x their own fit's "
            f"band misfit ({self.wall_time:.1f} s)",
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

    def plot(self, ax=None) -> list[Artist]:
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
) -> LeaveOneOut:
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
    if refit == "step":
        outs, warns = _step_outs(model, theta, preps, st, cover), []
    else:
        outs, warns = _full_outs(
            fit, model, theta, preps, st, max_nfev, cover, jobs, client, progress
        )
    rows = _rows(fit, preps, outs)
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


def _step_outs(model, theta, preps, st, cover):
    """Each record predicted after one Gauss-Newton step without it (``refit="step"``)."""
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
        for i in range(len(preps))
    ]
    return outs


def _full_outs(fit, model, theta, preps, st, max_nfev, cover, jobs, client, progress):
    """Each record predicted after a warm-started refit without it (``refit="full"``), on
    local processes or a Dask client: ``(outs, warnings)``.
    """
    n = len(preps)
    warns = []
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
    return outs, warns


def _rows(fit, preps, outs):
    """One row per record: its own and predicted band misfit [N], ratio, coverages."""
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
    return rows
