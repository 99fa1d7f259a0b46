"""The fit stage of a loop diagnosis: effect stacks fitted on a prepared record.

:class:`StackFitter` fits a stack of effects on the Iwan joint to a
:class:`~.prepare.PreparedRecord` (the loop model of :mod:`.model`: ``Fs`` and the force
offset eliminated in closed form, the joint's starting state as a nuisance) and scores it as a
noise-normalised chi-square; :func:`fit_base` fits the plain joint; :func:`stack_fit` states
a fitted stack on the whole record with its uncertainty (:class:`~iwan_element.FitResult`);
:func:`record_force` runs the fitted element over the record. Nothing here selects or
reports: the selection rule and the report read what this stage returns.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...base.serialize import json_safe
from ...effects import EFFECTS
from ...effects.engine.evaluate import Evaluator, build_element
from ...fitting import fit_success
from ...identify.loops.fit import fit_loops
from ...identify.loops.identifiability import microslip_warning, min_macroslip
from ...identify.loops.joint_verdict import failure_list, required_parameters, settle_verdict
from ...identify.loops.result import quiet_fits
from . import model as M

if TYPE_CHECKING:
    from ...identify.loops.result import FitResult
    from .model import LoopModel

__all__ = [
    "StackFitter",
    "FinalFits",
    "fit_base",
    "z_start",
    "stack_fit",
    "record_force",
    "final_fits",
]


def _base_start(tt, uj, FF, seed):
    """Shape start ``(phi_max, chi, beta)`` from the plain loop fit, or None."""
    try:
        with quiet_fits():
            res = fit_loops(tt, uj, FF, seed=seed, max_samples=3000, n_starts=3)
        p = res.joint
        return (p.phi_max, p.chi, p.beta)
    except (ValueError, FloatingPointError, ZeroDivisionError):
        return None


class StackFitter:
    """Fits stacks on one record; scores them as noise-normalised chi2 on the full keep set."""

    _memo: dict[tuple, dict[str, Any]]  # the rows fitted so far (made on first use, in run)

    def __init__(self, rec, sigma=1.0, F0=None):
        self.ev, self.ev_slow, self.scales = rec.ev, rec.ev_slow, rec.scales
        self.s2 = sigma * sigma
        self.F0 = F0
        self.y, self.y_sub = rec.F[rec.keep], rec.F[rec.sub]
        self.nfev = 0

    def model(self, names, *, full=True) -> LoopModel:
        """The :class:`LoopModel` of effects ``names`` on the full keep set or the subsample."""
        fast = Evaluator.fast(names)
        if full or fast:
            return M.LoopModel(self.ev, self.y, names, self.scales, self.F0)
        return M.LoopModel(self.ev_slow, self.y_sub, names, self.scales, self.F0)

    def run(self, names, starts, scan=None) -> dict[str, Any]:
        """Fit ``names`` from ``starts``; ``scan``: the newly added effect, whose ``fit_scan``
        grid (if it has one) seeds the starts by a 1-D scan (:func:`.model.scan_starts`).
        Fits do not depend on sigma, so a re-selection reuses them (memo).
        """
        key = (tuple(names), scan, b"".join(np.asarray(z, float).tobytes() for z in starts))
        row = self.__dict__.setdefault("_memo", {}).get(key)
        if row is None:
            fast = Evaluator.fast(names)
            mdl = self.model(names, full=False)
            grid = EFFECTS[scan].fit_scan if scan else None
            if grid is not None:
                k = M.var_index(names, scan)
                starts = M.scan_starts(mdl, starts[0], k, grid) + list(starts[:1])
                self.nfev += len(grid)
            max_nfev = 200 if fast else 60
            res, nfev = M.fit(mdl, starts if fast else starts[:2], max_nfev=max_nfev)
            if fast and any(EFFECTS[nm].force_jumps for nm in names):
                # (not for stacks run element by element: 16 more fits cost minutes there)
                res, n_hop = M.hop(mdl, res, max_nfev=max_nfev)
                nfev += n_hop
            start, res, n_start = M.fit_start(mdl, res, max_nfev=max_nfev)
            self.nfev += nfev + n_start
            full = self.model(names)
            full.start = start
            r = full.residual(res.x)
            row = {
                "names": tuple(names),
                "ssr": float(r @ r),
                "z": res.x,
                "start": start,
                "status": int(res.status),
                "message": str(res.message),
                "model": full,
                "cache": {},
            }  # shared by the copies handed out (record_force)
            self._memo[key] = row
        return dict(row, chi2=row["ssr"] / self.s2)


def z_start(names, prev_names, prev_z, which) -> NDArray[np.float64]:
    """Start vector for ``names`` from a previous fit (effects it had keep their values)."""
    z = list(prev_z[:3])
    k_prev, pos = 3, {}
    for nm in prev_names:
        q = len(EFFECTS[nm].specs)
        pos[nm] = prev_z[k_prev : k_prev + q]
        k_prev += q
    for nm in names:
        if nm in pos:
            z.extend(pos[nm])
        else:
            z.extend(s.fit_starts[min(which, len(s.fit_starts) - 1)] for s in EFFECTS[nm].specs)
    return np.array(z, float)


def fit_base(fitter, rec, *, seed) -> dict[str, Any]:
    """The plain Iwan model (with the force offset) on the prepared record ``rec``, from the
    plain loop fit's shape (:func:`~iwan_element.fit_loops`, ``seed`` its random starts) and
    from defaults.
    """
    ev, shape0 = rec.ev, _base_start(rec.t, rec.uj, rec.F, seed)
    starts = [np.array([0.0, -0.5, math.log1p(0.5)]), np.array([-1.0, -0.8, math.log1p(3.0)])]
    if shape0 is not None:
        phi, chi, beta = shape0
        starts.insert(
            0,
            np.array(
                [
                    math.log(min(max(phi / ev.x_max, M.PHI_RANGE[0]), M.PHI_RANGE[1])),
                    min(max(chi, M.CHI_BOUNDS[0]), M.CHI_BOUNDS[1]),
                    math.log1p(min(max(beta, 0.0), M.BETA_MAX)),
                ]
            ),
        )
    return fitter.run((), starts)


def _effect_rows(mdl, effs, se):
    """Each fitted effect's values, standard errors and units (the details' ``effects``)."""
    eff_out, k0 = [], 4
    for nm, d in zip(mdl.names, effs):
        q = len(EFFECTS[nm].specs)
        eff_out.append(
            {
                "name": nm,
                "parameters": dict(d),
                "stderr": dict(zip(EFFECTS[nm].parameter_names, se[k0 : k0 + q].tolist())),
                "units": {s.name: s.unit for s in EFFECTS[nm].specs},
            }
        )
        k0 += q
    return eff_out


def _verdict(row, ident, ranges, noise_only, microslip):
    """``(success, failure reasons)`` of a fitted stack."""
    required = required_parameters(ranges)
    success = fit_success(row["status"] > 0, ident, required)
    failures = (
        ()
        if success
        else failure_list(
            converged=row["status"] > 0,
            message=row["message"],
            explains=not noise_only,
            noise_text="the force is indistinguishable from noise: no parameter is identified",
            ident=ident,
            required=required,
            microslip=microslip,
        )
    )
    return success, failures


def stack_fit(row, fitter, FF, F_model, t_start, *, noise_only=False) -> FitResult:
    """FitResult of a fitted stack on the whole record, with stderr and identification."""
    mdl, z = row["model"], row["z"]
    p, effs, F0 = mdl.physical(z)
    r = mdl.residual(z)
    se, corr, se_start = M.uncertainty(mdl, z, r, jac=row.get("cache", {}).get("jac"))
    vals, labels = M.flat(p, effs, mdl.names, F0)
    stderr = dict(zip(M.PARAM_NAMES, se[:4].tolist()))
    at_bound = np.isclose(z, mdl.lower, atol=1e-6) | np.isclose(z, mdl.upper, atol=1e-6)
    # the package's one identification rule (identify.loops.joint_verdict.settle_verdict):
    # finite stderr of at most half the value (chi: of chi + 1), not at a bound (phi_max's
    # bound is KT's)
    ranges: dict[str, Any] = {}
    ident, settle_warns = settle_verdict(
        {
            "identified": dict.fromkeys(M.PARAM_NAMES, True),
            "params": p,
            "stderr": stderr,
            "ranges": ranges,
            "at_bound": {k for k, b in zip(("KT", "chi", "beta"), at_bound[:3]) if b},
        },
        (),
    )
    eff_out = _effect_rows(mdl, effs, se)
    warns = list(settle_warns)
    hist = mdl.ev.hist  # the backbone argument behind each fitted sample
    x = hist.x[hist.out]
    n_macro = int(np.count_nonzero(x > p.phi_max))
    if n_macro < min_macroslip(x.size) and (ident["Fs"] or ident["beta"]):
        ident = dict(ident, Fs=False, beta=False)
        warns.append(microslip_warning(n_macro, x.size, float(x.max()), p.phi_max))
    if noise_only:  # a force that is noise identifies nothing
        ident = dict.fromkeys(M.PARAM_NAMES, False)
        warns.append("the force is indistinguishable from noise: no parameter is identified")
    if row["status"] <= 0:
        warns.append(f"the fit did not converge: {row['message']}")
    span = float(np.ptp(FF)) or 1.0
    success, failures = _verdict(row, ident, ranges, noise_only, n_macro < min_macroslip(x.size))
    return M.make_fit_result(
        params=p,
        stderr=stderr,
        correlation=corr[:4, :4],
        identified=ident,
        fixed=(),
        ranges=ranges,
        residual_norm=math.sqrt(float(r @ r)),
        nrmse=float(np.sqrt(np.mean((FF - F_model) ** 2)) / span),
        success=success,
        failures=failures,
        message=row["message"],
        nfev=int(fitter.nfev),
        method="loops+" + "+".join(mdl.names) if mdl.names else "loops",
        n_data=int(r.size),
        warnings=tuple(warns),
        wall_time=time.perf_counter() - t_start,
        details=json_safe(
            {
                "effects": eff_out,
                "labels": labels,
                "force_offset": F0,
                "force_offset_stderr": float(se[-1]),
                "correlation_all": corr,
                "start_displacement": float(mdl.start),
                "start_displacement_stderr": se_start,
            }
        ),
    )


def record_force(row, uj, v) -> tuple[NDArray[np.float64], Any]:
    """Force [N] of a fitted stack on the whole record ``uj``, ``v`` (the fitter's record),
    offset included, and the element. Kept in the row's ``cache``: the noise re-reading of
    the selection and the final fits ask for the same stack's force.
    """
    cache = row.get("cache")
    if cache is not None and "force" in cache:
        return cache["force"]
    p, effs, F0 = row["model"].physical(row["z"])
    el = build_element(p, row["names"], effs)
    s = row.get("start", 0.0)
    ue, ve = np.concatenate([[s], uj]), np.concatenate([[0.0], v])
    F = el.force_history(ue, ve) if row["names"] else el.force_history(ue)
    out = (F[1:] + F0, el)
    if cache is not None:
        cache["force"] = out
    return out


@dataclass(frozen=True, eq=False)
class FinalFits:
    """The plain and the selected stack stated on the whole record.

    Attributes
    ----------
    final : dict
        The selected stack's fitted row (the plain joint's when nothing is named).
    F_base, F_after : ndarray
        Force [N] of the plain and of the selected model over the record.
    base_fit, fit : FitResult
        Their parameters with uncertainty (the same object when nothing is named).
    model
        The selected model as a joint element.
    """

    final: dict
    F_base: np.ndarray
    F_after: np.ndarray
    base_fit: object
    fit: object
    model: object


def final_fits(fitter, rec, base, selected, *, noise_only, t_start) -> FinalFits:
    """State the plain fit ``base`` and the ``selected`` stack's row (None: nothing named) on
    the whole prepared record ``rec``; ``noise_only``: the record is noise, nothing is
    identified.
    """
    F_base, _ = record_force(base, rec.uj, rec.v)
    final = base if selected is None else selected
    F_after, model = record_force(final, rec.uj, rec.v)
    base_fit = stack_fit(base, fitter, rec.F, F_base, t_start, noise_only=noise_only)
    fit = base_fit if selected is None else stack_fit(final, fitter, rec.F, F_after, t_start)
    return FinalFits(
        final=final, F_base=F_base, F_after=F_after, base_fit=base_fit, fit=fit, model=model
    )
