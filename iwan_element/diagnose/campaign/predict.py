"""Prediction of a campaign model at conditions; the method
:meth:`~.result.CampaignFit.predict` calls it, the leave-one-out check (:mod:`.holdout`)
predicts each record with it (equations in ``docs/campaign.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, axes_or_new
from ...base.serialize import json_safe
from ...base.validation import check_int, check_scalar, check_time, finite_array
from ..loops import model as M
from ..loops.batch import band_misfit
from . import model as CM
from .model import full_force
from .scatter import perturb

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = [
    "CampaignPrediction",
    "condition_vector",
    "predict",
    "predict_record",
    "draw_values",
]


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
    law values used and ``warnings`` (extrapolation). ``failures``: why the prediction is
    not usable (the campaign fit it comes from is not usable: its reasons), each also among
    the warnings.
    """

    COLUMNS = {"lower": ("lower", "N"), "upper": ("upper", "N")}

    t: np.ndarray
    u: np.ndarray
    force: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    conditions: dict
    values: dict
    level: float
    failures: tuple = ()

    def __post_init__(self):
        self._fold_failures()

    @property
    def success(self) -> bool:
        """True when the fit it comes from is usable and the force and its band are finite
        at every sample.
        """
        return bool(
            not self.failures
            and np.all(np.isfinite(self.force))
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
                    "failures",
                )
            }
            | {"success": self.success}
        )

    def report(self) -> str:
        """Conditions, the law values used, the band's mean width, warnings."""
        vals = ", ".join(f"{k} = {v:.4g}" for k, v in self.values.items())
        lines = [
            self.verdict(),
            f"Prediction at {self.conditions} over {self.force.size} samples: {vals}",
            f"  {100 * self.level:g} % band: mean width "
            f"{float(np.mean(self.upper - self.lower)):.4g} N, largest "
            f"{float(np.max(self.upper - self.lower)):.4g} N",
        ]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def plot(self, ax=None, *, measured=None) -> list[Artist]:
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


def draw_values(model, theta, cov, S, x, rng, draws) -> list[dict[str, float]]:
    """``draws`` law-value dicts at conditions ``x``: coefficients from ``N(theta, cov)`` and,
    when ``S`` (the scatter covariance) is given, a record-to-record deviation from
    ``N(0, S)`` (:func:`.scatter.perturb`). Draws with ``Fs <= 0`` are left out.
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
            vals = perturb(model, vals, Ls @ rng.standard_normal(Ls.shape[0]))
        if vals["Fs"] > 0:
            out.append(vals)
    return out


def predict(
    fit, conditions, t, u, *, F0=0.0, start=0.0, level=0.95, draws=64, rng=None, scatter=True
) -> CampaignPrediction:
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
        failures=tuple(
            f"the campaign fit it comes from is not usable ({r})" for r in fit.failure_reasons()
        ),
    )


def _chol(cov):
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    return V * np.sqrt(np.clip(w, 0.0, None))


def predict_record(model, theta, r, prep, bands=(), vals=None) -> tuple[float, list[float]]:
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
