"""Assembly of a campaign fit's result: the law coefficients' covariance (delta method),
the coefficients in the conditions' own units, the per-record agreement table and the
record-to-record scatter, gathered into a :class:`~.result.CampaignFit`
(steps 4-6 of :mod:`.fit`; equations in ``docs/campaign.md``).
"""

from __future__ import annotations

import math
import time

import numpy as np
from numpy.typing import NDArray

from ...fitting import Parameter, ParameterTable, covariance, verdict
from ...identify.loops.noise import integrated_time
from ..loops.batch import band_misfit
from . import model as CM
from .model import full_force
from .result import CampaignFit, law_at
from .scatter import deviations, scatter_coef_cov, scatter_cov

__all__ = ["assemble", "to_physical"]

Z_AGREE = 3.0  # |z| above which a record disagrees with a law


def _covariance(model, theta, T):
    """Covariance of ``theta`` by the package's one routine
    (:func:`iwan_element.fitting.covariance`, docs/fitting.md): rows of record ``r`` weighted
    by ``1 / (s_r sqrt(tau_r))`` with ``s_r``, ``tau_r`` the RMS and correlation time of the
    campaign residual on that record, ``s^2 = n / (n - p)``; the law coefficients
    ``T theta[:n_glob]`` by the delta method (NaN along a degenerate direction). Returns
    ``(cov, J, s, tau, stderr of the coefficients)``.
    """
    J = model.jacobian(theta)
    s, tau = [], []
    Jw = np.empty_like(J)
    for r in range(len(model.records)):
        e = model.record_residual(theta, r)
        s.append(float(np.sqrt(np.mean(e * e))) or 1e-300)
        tau.append(integrated_time(e))
        sl = slice(model.rows[r], model.rows[r + 1])
        Jw[sl] = J[sl] / (s[-1] * math.sqrt(tau[-1]))
    n, p = J.shape
    s2 = n / max(n - p, 1)
    if not np.all(np.isfinite(Jw)):
        return (np.full((p, p), np.nan), J, np.array(s), np.array(tau), np.full(T.shape[0], np.nan))
    Jp = np.zeros((T.shape[0], p))
    Jp[:, : T.shape[1]] = T
    cov = covariance(Jw, s2=s2).covariance
    return cov, J, np.array(s), np.array(tau), covariance(Jw, s2=s2, Jp=Jp).stderr


def to_physical(model) -> tuple[NDArray[np.float64], list[tuple[str, str]]]:
    """Matrix ``T`` with ``coefficients = T theta[:n_glob]`` (laws in the conditions' own
    units: ``q = a + sum_c b_c x_c``) and the coefficient labels ``(quantity, term)``.
    """
    T = np.zeros((model.n_glob, model.n_glob))
    labels = []
    for q in model.qnames:
        sl, qs = model.slices[q], model.qscale[q]
        k0 = sl.start
        T[k0, k0] = qs
        labels.append((q, "1"))
        for i, c in enumerate(model.laws[q], start=1):
            j = model.cnames.index(c)
            T[k0 + i, k0 + i] = qs / model.cscale[j]
            T[k0, k0 + i] = -qs * model.centre[j] / model.cscale[j]
            labels.append((q, c))
    return T, labels


def _rows(model, theta, cov_int, preps, labels):
    rows, warns = [], []
    stack = set(model.names)
    for r, p in enumerate(preps):
        vals, se = law_at(model, theta, cov_int, model.X[r])
        F, F0 = full_force(model, theta, r, p)
        band = band_misfit(p["F"], F, CM.BAND) if F is not None else math.nan
        z = {}
        for q in model.qnames:
            est, s_est = p["estimates"].get(q, math.nan), p["stderr"].get(q, math.nan)
            if math.isfinite(est) and math.isfinite(s_est):
                z[q] = (est - vals[q]) / math.hypot(s_est, se[q]) if (s_est or se[q]) else 0.0
        named = set(p["effects"])
        row = {
            "record": labels[r],
            "conditions": dict(zip(model.cnames, model.X[r].tolist())),
            "named": " + ".join(p["effects"]) or "none",
            "missing": sorted(stack - named),
            "extra": sorted(named - stack),
            "band_own": p["band_own"],
            "band_campaign": band,
            "band_ratio": band / p["band_own"] if p["band_own"] > 0 else math.nan,
            "force_offset": F0,
            "start": model.start(theta, r),
            "z": z,
            "law": vals,
            "law_stderr": se,
        }
        rows.append(row)
        far = sorted((q for q, v in z.items() if abs(v) > Z_AGREE), key=lambda q: -abs(z[q]))
        if row["missing"] or row["extra"]:
            warns.append(
                f"{labels[r]}: named {row['named']}; the campaign stack "
                f"{' + '.join(model.names) or 'Iwan'} "
                + (f"adds {', '.join(row['missing'])}" if row["missing"] else "")
                + (" and " if row["missing"] and row["extra"] else "")
                + (f"lacks {', '.join(row['extra'])}" if row["extra"] else "")
            )
        if far:
            warns.append(
                f"{labels[r]}: own estimates off the law by more than {Z_AGREE:g} "
                "standard errors: " + ", ".join(f"{q} (z = {z[q]:.1f})" for q in far)
            )
    return rows, warns


def _scatter(model, theta, free):
    """``(sd per quantity, covariance)`` of the record-to-record scatter about the laws
    (empty dict and None without ``free``).
    """
    if free is None or sum(f is not None for f in free) < 2:
        return {}, None
    D, dof = deviations(model, theta, free)
    S = scatter_cov(D, dof)
    names = ["ln Fs"] + list(model.qnames[1:])
    return {q: float(math.sqrt(S[k, k])) for k, q in enumerate(names)}, S


def _coef_unit(unit: str, term: str) -> str:
    """Unit of a law coefficient: the quantity's, per unit of the condition for a slope
    (conditions in their own units, ``"[cond]"``).
    """
    return unit if term == "1" else f"{unit}/[{term}]"


def _stderr_dict(labels_c, cov_phys):
    out = {}
    for (q, term), e in zip(labels_c, np.sqrt(np.clip(np.diag(cov_phys), 0.0, None))):
        out.setdefault(q, {})[term] = float(e)
    return out


def _coefficient_table(model, theta, labels_c, coef, se, units, labels, warns):
    """The law coefficients' table with their verdicts, and whether all are identified
    (warnings for a law clipped on some records and for coefficients not identified).
    """
    verdicts = [
        verdict(f"{q}:{t}", float(c), float(e), relative=False)[0] and e > 0
        for (q, t), c, e in zip(labels_c, coef, se)
    ]
    ident = all(verdicts)
    clipped = model.clipped(theta)
    table = ParameterTable(
        [
            Parameter(
                f"{q}:{t}",
                float(c),
                float(e),
                unit=_coef_unit(units.get(q, ""), t),
                identified=ok and q not in clipped,
            )
            for (q, t), c, e, ok in zip(labels_c, coef, se, verdicts)
        ]
    )
    for q, recs in clipped.items():
        ident = False
        names = [labels[r] for r in recs]
        warns.append(
            f"the {q} law leaves the range the model can take on {len(recs)} of "
            f"{len(labels)} records ({', '.join(names[:6])}"
            f"{', ...' if len(names) > 6 else ''}): it is clipped there, so those "
            "records do not determine its coefficients and their standard errors are "
            "not to be trusted; state a law that stays in range (laws=) or drop the "
            "condition"
        )
    if not ident:
        bad = [f"{q}:{t}" for (q, t), e in zip(labels_c, se) if not (math.isfinite(e) and e > 0)]
        warns.append(f"coefficients not identified by the records: {', '.join(bad)}")
    return table, ident


def assemble(
    *, model, preps, labels, res, units, stack_from, warnings, options, times, t0, free=None
) -> CampaignFit:
    """Uncertainty, coefficients, the per-record table, the verdict: a :class:`CampaignFit`."""
    theta = res.x
    t1 = time.perf_counter()
    T, labels_c = to_physical(model)
    cov, J, s, tau, se = _covariance(model, theta, T)
    times = dict(times, uncertainty=time.perf_counter() - t1)
    ng = model.n_glob
    cov_int = cov[:ng, :ng]
    coef = T @ theta[:ng]
    cov_phys = T @ cov_int @ T.T
    rows, awarn = _rows(model, theta, cov_int, preps, labels)
    scatter, S = _scatter(model, theta, free)
    cov_re = None if S is None else scatter_coef_cov(model, theta, S)
    stderr_scatter = {} if cov_re is None else _stderr_dict(labels_c, T @ (cov_int + cov_re) @ T.T)
    warns = list(warnings)
    converged = bool(res.status > 0)
    if not converged:
        warns.append(f"the campaign fit did not converge: {res.message}")
    table, ident = _coefficient_table(model, theta, labels_c, coef, se, units, labels, warns)
    warns += awarn
    details = {
        "weights": [rm.weight for rm in model.records],
        "record_rms": s.tolist(),
        "record_tau": tau.tolist(),
        "cost": float(res.cost),
        "fitted_samples": int(model.rows[-1]),
        "n_coefficients": ng,
        "n_starts": len(model.start_pos),
        "options": options,
        "times": times,
    }
    times["total"] = time.perf_counter() - t0
    return CampaignFit(
        records=tuple(labels),
        condition_names=model.cnames,
        effects=model.names,
        effects_from=stack_from,
        laws={q: tuple(v) for q, v in model.laws.items()},
        units=units,
        params=table,
        covariance=cov_phys,
        coefficient_labels=tuple(f"{q}:{t}" for q, t in labels_c),
        rows=tuple(rows),
        scatter=scatter,
        stderr_scatter=stderr_scatter,
        converged=converged,
        success=converged and ident,
        message=str(res.message),
        nfev=int(res.nfev),
        wall_time=times["total"],
        warnings=tuple(warns),
        details=details,
        _state={
            "model": model,
            "theta": theta,
            "cov_int": cov_int,
            "J": J,
            "preps": preps,
            "cov": cov,
            "free": free,
            "scatter_cov": S,
            "cov_re": cov_re,
        },
    )
