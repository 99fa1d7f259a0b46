"""Prediction of a campaign model at conditions, and its leave-one-out check (private module
of :mod:`iwan_element.diagnose.campaign`; equations in ``docs/campaign.md``)."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..core.result_shape import ResultShape
from ..core.serialize import json_safe
from ..core.validation import check_int, check_scalar, check_time, finite_array
from ..ensemble import run_ensemble
from ..plotting import axes_or_new
from . import _campaign_model as CM
from . import _model as M
from ._campaign_result import full_force
from .batch import band_misfit

__all__ = ["CampaignPrediction", "LeaveOneOut", "condition_vector", "predict", "leave_one_out"]

LOO_TARGET = 1.5                      # prediction band misfit / own fit's: the target


def condition_vector(cnames, conditions) -> np.ndarray:
    """``conditions`` (a dict with exactly the campaign's names) as a vector."""
    if not isinstance(conditions, dict) or set(map(str, conditions)) != set(cnames):
        got = sorted(map(str, conditions)) if isinstance(conditions, dict) else conditions
        raise ValueError(f"conditions must be a dict of the campaign's conditions "
                         f"{sorted(cnames)}, got {got!r}")
    x = np.array([float(conditions[c]) for c in cnames])
    return finite_array("conditions", x, ndim=1)


@dataclass(frozen=True, eq=False)
class CampaignPrediction(ResultShape):
    """Predicted force history at a condition: ``force`` [N] and its band ``lower``,
    ``upper`` [N] (probability ``level``, from the law coefficients' uncertainty), with the
    law values used and ``warnings`` (extrapolation)."""

    t: np.ndarray
    u: np.ndarray
    force: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    conditions: dict
    values: dict
    level: float
    warnings: tuple = field(default_factory=tuple)

    @property
    def success(self) -> bool:
        """True when the force and its band are finite at every sample."""
        return bool(np.all(np.isfinite(self.force)) and np.all(np.isfinite(self.lower))
                    and np.all(np.isfinite(self.upper)))

    def to_dict(self) -> dict:
        return json_safe({k: getattr(self, k) for k in (
            "t", "u", "force", "lower", "upper", "conditions", "values", "level", "warnings")}
            | {"success": self.success})

    def report(self) -> str:
        """Conditions, the law values used, the band's mean width, warnings."""
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        lines = [f"Prediction at {self.conditions} over {self.force.size} samples: {vals}",
                 f"  {100 * self.level:g} % band: mean width "
                 f"{float(np.mean(self.upper - self.lower)):.4g} N, largest "
                 f"{float(np.max(self.upper - self.lower)):.4g} N"]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def plot(self, ax=None, *, measured=None):
        """Force against displacement: the prediction, its band (as a shaded envelope in
        time order) and ``measured`` (a force array of the same length) if given. Returns
        the artists."""
        ax = axes_or_new(ax)
        arts = []
        if measured is not None:
            arts += ax.plot(self.u, np.asarray(measured, float), "-", lw=0.6, color="0.5",
                            label="measured")
        arts += ax.plot(self.u, self.force, "-", lw=0.8, label="predicted")
        arts += ax.plot(self.u, self.lower, ":", lw=0.5, color="C1",
                        label=f"{100 * self.level:g} % band")
        arts += ax.plot(self.u, self.upper, ":", lw=0.5, color="C1")
        ax.set_xlabel("u [m]")
        ax.set_ylabel("F [N]")
        ax.legend(fontsize=7)
        return arts


def _drive_record(model, theta, x, t, u):
    """A record dict for :class:`RecordModel` on a new drive (no measured force)."""
    vals = model.law_values(theta, x)
    shape = (math.exp(vals["log_phi_max"]), min(max(vals["chi"], M.CHI_BOUNDS[0]),
                                                M.CHI_BOUNDS[1]),
             math.expm1(min(max(vals["log1p_beta"], 0.0), math.log1p(M.BETA_MAX))))
    return {"t": t, "u": u, "F": np.zeros(u.size), "keep": np.arange(u.size),
            "sigma": 1.0, "rms_own": 1.0, "tau_own": 1.0, "base_shape": shape}


def _force(model, rm, theta, x, start):
    Fs, shape, effs = model.physical(model.law_values(theta, x), rm)
    rm.ev.set_start(start)
    return Fs * rm.ev.unit_force(shape, model.names, effs)


def predict(fit, conditions, t, u, *, F0=0.0, start=0.0, level=0.95, draws=64, rng=None):
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
    rng = np.random.default_rng(0 if rng is None else rng)
    Fs = model.law_values(theta, x)["Fs"]
    if not Fs > 0:
        raise ValueError(f"the Fs law gives Fs = {Fs:.4g} N <= 0 at conditions {conditions}: "
                         "the campaign model does not reach there")
    rm = CM.RecordModel(_drive_record(model, theta, x, tt, uu), full=True)
    force = _force(model, rm, theta, x, start) + F0
    ng = model.n_glob
    L = _chol(cov)
    samples, warns = [], []
    for _ in range(draws):
        th = theta.copy()
        th[:ng] = theta[:ng] + L @ rng.standard_normal(ng)
        if model.law_values(th, x)["Fs"] > 0:
            samples.append(_force(model, rm, th, x, start) + F0)
    if len(samples) < draws:
        warns.append(f"{draws - len(samples)} of {draws} coefficient draws give Fs <= 0 here "
                     "and are left out of the band")
    if not samples:
        samples = [force]
    q = 0.5 * (1.0 - level)
    lo, hi = np.quantile(np.array(samples), [q, 1.0 - q], axis=0)
    for j, c in enumerate(fit.condition_names):
        a, b = float(model.X[:, j].min()), float(model.X[:, j].max())
        if not a <= x[j] <= b:
            warns.append(f"{c} = {x[j]:g} is outside the tested {a:g} .. {b:g}: the laws "
                         "are extrapolated")
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    return CampaignPrediction(t=ro(tt.copy()), u=ro(uu.copy()), force=ro(force),
                              lower=ro(np.minimum(lo, force)), upper=ro(np.maximum(hi, force)),
                              conditions=dict(zip(fit.condition_names, x.tolist())),
                              values=model.law_values(theta, x), level=level,
                              warnings=tuple(warns))


def _chol(cov):
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    return V * np.sqrt(np.clip(w, 0.0, None))


def _predict_record(model, theta, r, prep):
    """Band misfit [N] of the device predicted from ``theta`` on record ``r``; the record's
    nuisances (force offset, starting state) are fitted to it with the device held."""
    best = (math.inf, 0.0)
    vals = model.law_values(theta, model.X[r])
    for g in M.START_GRID:
        s = g * model.records[r].x_max
        m = model.record_force(theta, r, vals=vals, start=s)
        if m is not None:
            e = model.records[r].y - m
            best = min(best, (float(np.var(e)), s))
    F, _ = full_force(model, theta, r, prep, vals=vals, start=best[1])
    return band_misfit(prep["F"], F, CM.BAND) if F is not None else math.nan


def _loo_step(model, theta, J, i):
    """One Gauss-Newton step from the full fit to the fit without record ``i`` (the weighted
    normal equations with its rows and its start column removed)."""
    rows = np.r_[0:model.rows[i], model.rows[i + 1]:model.rows[-1]]
    cols = [k for k in range(model.n_theta) if k != model.start_pos.get(i, -1)]
    w = np.concatenate([np.full(rm.y.size, rm.weight) for rm in model.records])
    r = model.residual(theta)[rows]
    Jw = J[rows][:, cols] * w[rows, None]
    delta, *_ = np.linalg.lstsq(Jw, -r, rcond=1e-10)
    th = theta.copy()
    th[cols] += delta
    return th


def _loo_task(params, rng):
    """Refit without record ``i`` (warm start), predict it (module level: picklable)."""
    del rng
    from .campaign import build_model, solve
    i, preps = params["i"], params["preps"]
    X = params["X"]
    others = [k for k in range(len(preps)) if k != i]
    sub = build_model([preps[k] for k in others], params["names"], params["laws"],
                      params["cnames"], X[others])
    sub.centre, sub.cscale, sub.qscale = params["centre"], params["cscale"], params["qscale"]
    full = build_model(preps, params["names"], params["laws"], params["cnames"], X)
    full.centre, full.cscale, full.qscale = sub.centre, sub.cscale, sub.qscale
    theta = params["theta"]
    th0 = np.concatenate([theta[:full.n_glob],
                          [theta[full.start_pos[k]] for k in others if k in full.start_pos]])
    res = solve(sub, th0, max_nfev=params["max_nfev"])
    th = theta.copy()
    th[:full.n_glob] = res.x[:full.n_glob]
    return {"band_pred": _predict_record(full, th, i, preps[i]), "nfev": int(res.nfev),
            "status": int(res.status)}


@dataclass(frozen=True, eq=False)
class LeaveOneOut(ResultShape):
    """Per record: the band misfit [N] of its prediction from the other records, of its own
    fit, their ratio, and the share of records within :data:`LOO_TARGET` (1.5)."""

    rows: tuple
    refit: str
    share_within: float
    wall_time: float
    warnings: tuple = field(default_factory=tuple)

    @property
    def success(self) -> bool:
        """True when at least 80 % of the records are predicted within 1.5x their own fit."""
        return self.share_within >= 0.8

    def report(self) -> str:
        lines = [f"Leave-one-out ({self.refit}): {100 * self.share_within:.0f} % of "
                 f"{len(self.rows)} records predicted within {LOO_TARGET:g}x their own fit's "
                 f"band misfit ({self.wall_time:.1f} s)",
                 f"  {'record':<26} {'own [N]':>9} {'predicted [N]':>13} {'ratio':>6}"]
        for r in self.rows:
            lines.append(f"  {r['record']:<26} {r['band_own']:9.4g} {r['band_pred']:13.4g} "
                         f"{r['ratio']:6.2f}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def plot(self, ax=None):
        """Ratio of the prediction's band misfit to the own fit's per record (bars), with the
        1.5 target. Returns the artists."""
        ax = axes_or_new(ax)
        x = np.arange(len(self.rows))
        arts = list(ax.bar(x, [r["ratio"] for r in self.rows], 0.6))
        arts.append(ax.axhline(LOO_TARGET, color="k", ls="--", lw=0.8))
        ax.set_xticks(x, [r["record"] for r in self.rows], rotation=60, ha="right", fontsize=7)
        ax.set_ylabel("band misfit: leave-one-out prediction / own fit")
        return arts

    def to_dict(self) -> dict:
        return json_safe({"rows": list(self.rows), "refit": self.refit,
                          "share_within": self.share_within, "success": self.success,
                          "wall_time": self.wall_time, "warnings": list(self.warnings)})


def leave_one_out(fit, *, refit="step", jobs=1, client=None, progress=False, max_nfev=20):
    """Predict each record from the campaign fitted without it.

    ``refit="step"``: one Gauss-Newton step from the full fit on the normal equations without
    the record (no new model evaluations but the prediction's); ``"full"``: a warm-started
    least-squares refit per record, on ``jobs`` local processes or a Dask ``client``. The
    prediction holds the device at the laws; the record's nuisances (force offset, starting
    state on :data:`_model.START_GRID`) are fitted to it. Returns :class:`LeaveOneOut`.
    """
    from .campaign import _executor
    if refit not in ("step", "full"):
        raise ValueError(f"refit must be 'step' or 'full', got {refit!r}")
    jobs = check_int("jobs", jobs, 1)
    max_nfev = check_int("max_nfev", max_nfev, 1)
    t0 = time.perf_counter()
    st = fit._state
    model, theta, preps = st["model"], st["theta"], st["preps"]
    n = len(preps)
    if n < 3:
        raise ValueError(f"leave_one_out needs at least 3 records, the campaign has {n}")
    warns = []
    if refit == "step":
        bands = [_predict_record(model, _loo_step(model, theta, st["J"], i), i, preps[i])
                 for i in range(n)]
    else:
        common = {"preps": preps, "X": model.X, "names": model.names, "laws": model.laws,
                  "cnames": model.cnames, "centre": model.centre, "cscale": model.cscale,
                  "qscale": model.qscale, "theta": theta, "max_nfev": max_nfev}
        ex = _executor(jobs, client)
        try:
            res = run_ensemble(_loo_task, [dict(common, i=i) for i in range(n)], executor=ex,
                               seed=0, progress=progress)
        finally:
            if ex is not client and not isinstance(ex, str):
                ex.shutdown()
        bands = [float(r.get("band_pred", math.nan)) for r in res.rows]
        warns += [f"{fit.records[e.index]}: {e.message}" for e in res.errors]
        warns += [f"{fit.records[i]}: the refit without it did not converge"
                  for i, r in enumerate(res.rows) if r.get("status", 1) == 0]
    rows = tuple({"record": fit.records[i], "conditions": fit.rows[i]["conditions"],
                  "band_own": preps[i]["band_own"], "band_pred": b,
                  "ratio": b / preps[i]["band_own"] if preps[i]["band_own"] > 0 else math.nan}
                 for i, b in enumerate(bands))
    warns += [f"{r['record']}: the laws from the other records give no model there (Fs <= 0 "
              "or an evaluation failure): not predicted, counted as a miss"
              for r in rows if not math.isfinite(r["band_pred"])]
    within = float(np.mean([r["ratio"] <= LOO_TARGET for r in rows]))
    return LeaveOneOut(rows=rows, refit=refit, share_within=within,
                       wall_time=time.perf_counter() - t0, warnings=tuple(warns))
