"""Loop diagnosis: what the four-parameter Iwan model misses in a displacement-driven test.

:func:`diagnose` works on a record (time, displacement, force):

1. the joint's unloaded state is the rest position the record starts from: the displacement
   offset is the mean displacement before the motion starts; the force offset is fitted with
   every model (linear, eliminated in closed form with ``Fs``), the rest samples (where the
   unloaded joint carries no force) being part of the fitted data. Offsets are nuisance
   parameters: reported, never named as an effect;
2. the force noise and its correlation time are estimated from the record itself
   (:func:`iwan_element.identify.noise.estimate_noise`; no repeated cycles needed, so
   ramped, swept and random-amplitude protocols work), unless ``noise`` is given;
3. the plain Iwan model is fitted, then effects of :data:`~iwan_element.EFFECTS` are tried
   one after the other with the selection rule of :mod:`iwan_element.diagnose.selection`
   (information criterion on the noise-normalised residual with ``n / tau`` independent
   samples, an "explains little" guard, and "no effect" when the rest is noise);
4. the augmented model is refitted on the whole record and its uncertainty stated (delta
   method, residual variance inflated by the residual's correlation time).

A property of the test rig is not an effect of the joint: ``lowpass`` removes structural
ringing of the rig (e.g. the 40-50 Hz ringing of the ARTS damper rig after each break-away),
with a zero-phase Butterworth filter on both channels, stating the reason in the result.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import replace

import numpy as np

from ..core.serialize import json_safe
from ..core.threads import one_blas_thread
from ..core.validation import check_int, check_scalar
from ..effects import EFFECTS
from ..effects.evaluate import Evaluator, build_element, order_stack, stack_ok
from ..ensemble.runner import progress_bar
from ..identify.result import settle_verdict
from ..identify.testdata import split_cycles
from . import _model as M
from ._locate import _check_candidates, _locate, _untestable
from ._noise import noise_level, pure_noise
from .prepare import check_record, dissipation_scale, prepare_record
from .results import Diagnosis
from .selection import criterion_text, stepwise_select

__all__ = ["diagnose", "loop_candidates"]

log = logging.getLogger(__name__)

def loop_candidates() -> tuple:
    """Names of the effects :func:`diagnose` tries by default, in the order they are reported:
    every effect in :data:`~iwan_element.EFFECTS` that declares a ``loop_rank``, by that rank
    (read when called, as :func:`~iwan_element.diagnose.vibration.vibration_candidates` is, so
    an effect registered later joins too)."""
    return tuple(sorted((n for n, c in EFFECTS.items() if c.loop_rank is not None),
                        key=lambda n: EFFECTS[n].loop_rank))


def _base_start(tt, uj, FF, seed):
    """Shape start ``(phi_max, chi, beta)`` from the plain loop fit, or None."""
    from ..identify.loops import fit_loops
    from ..identify.result import quiet_fits
    try:
        with quiet_fits():
            res = fit_loops(tt, uj, FF, seed=seed, max_samples=3000, n_starts=3)
        p = res.joint
        return (p.phi_max, p.chi, p.beta)
    except (ValueError, FloatingPointError, ZeroDivisionError):
        return None


class _Fitter:
    """Fits stacks on one record; scores them as noise-normalised chi2 on the full keep set."""

    def __init__(self, rec, sigma=1.0, F0=None):
        self.ev, self.ev_slow, self.scales = rec.ev, rec.ev_slow, rec.scales
        self.s2 = sigma * sigma
        self.F0 = F0
        self.y, self.y_sub = rec.F[rec.keep], rec.F[rec.sub]
        self.nfev = 0

    def model(self, names, *, full=True):
        fast = Evaluator.fast(names)
        if full or fast:
            return M.LoopModel(self.ev, self.y, names, self.scales, self.F0)
        return M.LoopModel(self.ev_slow, self.y_sub, names, self.scales, self.F0)

    def run(self, names, starts, scan=None):
        """Fit ``names`` from ``starts``; ``scan``: the newly added effect, whose ``fit_scan``
        grid (if it has one) seeds the starts by a 1-D scan (:func:`_model.scan_starts`).
        Fits do not depend on sigma, so a re-selection reuses them (memo)."""
        key = (tuple(names), scan, b"".join(np.asarray(z, float).tobytes() for z in starts))
        row = self.__dict__.setdefault("_memo", {}).get(key)
        if row is None:
            fast = Evaluator.fast(names)
            mdl = self.model(names, full=False)
            grid = getattr(EFFECTS[scan], "fit_scan", None) if scan else None
            if grid is not None:
                k = M.var_index(names, scan)
                starts = M.scan_starts(mdl, starts[0], k, grid) + list(starts[:1])
                self.nfev += len(grid)
            max_nfev = 200 if fast else 60
            res, nfev = M.fit(mdl, starts if fast else starts[:2], max_nfev=max_nfev)
            if fast and any(getattr(EFFECTS[nm], "force_jumps", False) for nm in names):
                # (not for stacks run element by element: 16 more fits cost minutes there)
                res, n_hop = M.hop(mdl, res, max_nfev=max_nfev)
                nfev += n_hop
            start, res, n_start = M.fit_start(mdl, res, max_nfev=max_nfev)
            self.nfev += nfev + n_start
            full = self.model(names)
            full.start = start
            r = full.residual(res.x)
            row = {"names": tuple(names), "ssr": float(r @ r), "z": res.x, "start": start,
                   "status": int(res.status), "message": str(res.message), "model": full}
            self._memo[key] = row
        return dict(row, chi2=row["ssr"] / self.s2)


def _z_start(names, prev_names, prev_z, which):
    """Start vector for ``names`` from a previous fit (effects it had keep their values)."""
    z = list(prev_z[:3])
    k_prev, pos = 3, {}
    for nm in prev_names:
        q = len(EFFECTS[nm].specs)
        pos[nm] = prev_z[k_prev:k_prev + q]
        k_prev += q
    for nm in names:
        if nm in pos:
            z.extend(pos[nm])
        else:
            z.extend(s.fit_starts[min(which, len(s.fit_starts) - 1)] for s in EFFECTS[nm].specs)
    return np.array(z, float)


def _allowed(names, cand):
    """Whether ``cand`` may join the stack ``names`` (:func:`stack_ok`)."""
    return stack_ok(tuple(names) + (cand,))


def _fit_base(fitter, ev, shape0):
    """The plain Iwan model (with the force offset), from the loop fit's shape and defaults."""
    starts = [np.array([0.0, -0.5, math.log1p(0.5)]), np.array([-1.0, -0.8, math.log1p(3.0)])]
    if shape0 is not None:
        phi, chi, beta = shape0
        starts.insert(0, np.array([math.log(min(max(phi / ev.x_max, M.PHI_RANGE[0]),
                                                    M.PHI_RANGE[1])),
                                   min(max(chi, M.CHI_BOUNDS[0]), M.CHI_BOUNDS[1]),
                                   math.log1p(min(max(beta, 0.0), M.BETA_MAX))]))
    return fitter.run((), starts)


def _fit_result(row, fitter, FF, F_model, t_start, base_identified=None, extra_warns=(),
                noise_only=False):
    """FitResult of a fitted stack on the whole record, with stderr and identification."""
    mdl, z = row["model"], row["z"]
    p, effs, F0 = mdl.physical(z)
    r = mdl.residual(z)
    se, corr, se_start = M.uncertainty(mdl, z, r)
    vals, labels = M.flat(p, effs, mdl.names, F0)
    stderr = dict(zip(M.PARAM_NAMES, se[:4].tolist()))
    at_bound = np.isclose(z, mdl.lower, atol=1e-6) | np.isclose(z, mdl.upper, atol=1e-6)
    # the package's one identification rule (identify.result.settle_verdict): finite stderr of at
    # most half the value (chi: of chi + 1), not at a bound (phi_max's bound is KT's)
    ranges = {}
    ident, settle_warns = settle_verdict({"identified": dict.fromkeys(M.PARAM_NAMES, True),
                                   "params": p, "stderr": stderr, "ranges": ranges,
                                   "at_bound": {k for k, b in zip(("KT", "chi", "beta"),
                                                                  at_bound[:3]) if b}}, ())
    eff_out, k0 = [], 4
    for nm, d in zip(mdl.names, effs):
        q = len(EFFECTS[nm].specs)
        eff_out.append({"name": nm, "parameters": dict(d),
                        "stderr": dict(zip(EFFECTS[nm].parameter_names, se[k0:k0 + q].tolist())),
                        "units": {s.name: s.unit for s in EFFECTS[nm].specs}})
        k0 += q
    warns = list(extra_warns) + settle_warns
    if noise_only:                       # a force that is noise identifies nothing
        ident = dict.fromkeys(M.PARAM_NAMES, False)
        warns.append("the force is indistinguishable from noise: no parameter is identified")
    if row["status"] <= 0:
        warns.append(f"the fit did not converge: {row['message']}")
    span = float(np.ptp(FF)) or 1.0
    return M.make_fit_result(
        params=p, stderr=stderr, correlation=corr[:4, :4], identified=ident, fixed=(),
        ranges=ranges, residual_norm=math.sqrt(float(r @ r)),
        nrmse=float(np.sqrt(np.mean((FF - F_model) ** 2)) / span),
        success=bool(row["status"] > 0 and all(ident[k] for k in ("Fs", "KT", "chi"))),
        message=row["message"],
        nfev=int(fitter.nfev), method="loops+" + "+".join(mdl.names) if mdl.names else "loops",
        n_data=int(r.size), warnings=tuple(warns), wall_time=time.perf_counter() - t_start,
        details=json_safe({"effects": eff_out, "labels": labels, "force_offset": F0,
                       "force_offset_stderr": float(se[-1]), "correlation_all": corr,
                       "start_displacement": float(mdl.start),
                       "start_displacement_stderr": se_start}))


def _record_force(row, uj, v):
    """Force [N] of a fitted stack on the whole record, offset included, and the element."""
    p, effs, F0 = row["model"].physical(row["z"])
    el = build_element(p, row["names"], effs)
    s = row.get("start", 0.0)
    ue, ve = np.concatenate([[s], uj]), np.concatenate([[0.0], v])
    F = el.force_history(ue, ve) if row["names"] else el.force_history(ue)
    return F[1:] + F0, el


def diagnose(t, u, F, *, candidates=None, max_effects: int = 3, noise: float | None = None,
             alpha: float = 1e-3, ambiguity: float = 10.0, max_samples: int = 1500,
             lowpass: float | None = None, seed=0, progress: bool = False) -> Diagnosis:
    """Find what the four-parameter Iwan model misses in a displacement-driven test.

    See the module docstring for the procedure.

    Parameters
    ----------
    t : array_like, shape (n,), or None
        Time [s], strictly increasing. Needed for velocity-dependent effects and ``lowpass``;
        with ``None`` viscous damping is reported as untestable. Not modified.
    u, F : array_like, shape (n,)
        Measured displacement [m] and force [N], ``n >= 40``, starting at rest (any sensor
        zero offsets are absorbed as nuisance parameters). Not modified.
    candidates : sequence of str, optional, keyword-only
        Effects to try (default :func:`loop_candidates`).
    max_effects : int, keyword-only
        Most effects named, ``>= 1`` (default 3: a real damper can show a gap, a
        direction-dependent grip and break-away at once; each must pass the selection
        rule on top of the others, so a record that needs fewer names fewer).
    noise : float, optional, keyword-only
        Force noise standard deviation [N], ``> 1e-9 max|F|`` and in ``[1e-100, 1e100]``,
        taken as white. Default: estimated from the record.
    alpha : float, keyword-only
        Level of the "rest is noise" test, in ``(0, 0.5)`` (default 1e-3).
    ambiguity : float, keyword-only
        Criterion difference below which another effect counts as nearly as good, ``>= 0``.
    max_samples : int, keyword-only
        Samples scored per model (evenly spaced; every turning point is kept), ``>= 100``.
    lowpass : float, optional, keyword-only
        Cut-off [Hz] of a zero-phase low-pass applied to both channels before fitting, to
        remove test-rig dynamics (structural ringing) that is not joint behaviour; in
        ``(0, sample rate / 2)``. Needs ``t``. Default: none.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the starting loop fit's random starts.
    progress : bool, keyword-only
        Show a tqdm progress bar counting the model fits (the base fit, then each
        candidate stack), with the stack being fitted (needs tqdm).

    Returns
    -------
    Diagnosis

    Raises
    ------
    ValueError
        Bad arrays (NaN, unequal lengths, fewer than 40 samples, no motion), a noise level
        below the record's resolution, or an option out of range.
    """
    t_start = time.perf_counter()
    tt, uu, FF, n, noise, lp = check_record(t, u, F, noise, lowpass)
    cand = _check_candidates(candidates, loop_candidates())
    max_effects = check_int("max_effects", max_effects, 1)
    opts = dict(alpha=check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True,
                                   high_open=True),
                ambiguity=check_scalar("ambiguity", ambiguity, low=0.0),
                max_effects=max_effects)
    max_samples = check_int("max_samples", max_samples, 100)
    bar = progress_bar(progress, desc="diagnose", unit="fit")
    try:
        with one_blas_thread():          # tall, narrow least squares: threads only spin
            rec = prepare_record(tt, uu, FF, n, lp, max_samples)
            fitter = _Fitter(rec)
            base = _fit_base(fitter, rec.ev, _base_start(rec.t, rec.uj, rec.F, seed))
            _tick(bar, "Iwan")
            nl = noise_level(rec, rec.F_raw - _record_force(base, rec.uj, rec.v)[0], noise)
            shape_b, _ = base["model"].decode(base["z"])
            fitter.scales["D_ref"] = dissipation_scale(rec.ev, shape_b)
            sel, nl = _select_with_noise(fitter, base, rec, nl, noise, cand, opts, bar)
            return _assemble(rec, fitter, base, nl, sel, opts, t_start)
    finally:
        if bar is not None:
            bar.close()


def _tick(bar, text):
    if bar is not None:
        bar.set_postfix_str(text)
        bar.update(1)


def _select_with_noise(fitter, base, rec, nl, noise, cand, opts, bar):
    """The selection, repeated with the noise re-read from the residual of the model it
    selected (a large misfit leaks into the plain fit's residual and inflates the noise
    estimate, which can hide a further effect; the fits are reused). ``(selection, noise)``."""
    for k in range(3):
        fitter.s2 = nl.sigma ** 2
        base["chi2"] = base["ssr"] / fitter.s2
        sel = _select(fitter, base, cand, rec, nl, opts, bar=bar)
        if noise is not None or not sel.named or k == 2:
            break
        new = noise_level(rec, rec.F_raw - _record_force(sel.final["state"], rec.uj,
                                                         rec.v)[0], noise)
        if abs(new.sigma - nl.sigma) <= 0.05 * nl.sigma and abs(new.tau - nl.tau) <= 0.1 * nl.tau:
            break
        nl = replace(new, text=new.text + ", from the residual of the model selected")
    return sel, nl


def _select(fitter, base, cand, rec, nl, opts, *, bar=None):
    """Run the shared selection rule over the testable candidates (``bar``: a progress bar
    counting the fits)."""
    tt, uj, v, FF = rec.t, rec.uj, rec.v, rec.F
    try:
        cycles = split_cycles(np.arange(uj.size, dtype=float) if tt is None else tt, uj, FF)
    except ValueError:
        cycles = []
    untestable = {k: why for k, why in _untestable(tt, v, cycles).items() if k in cand}
    testable = tuple(c for c in cand if c not in untestable)
    span = float(np.ptp(FF)) or 1.0
    nf = fitter.y.size

    def fit_candidate(cur, name):
        names = order_stack(cur["names"] + (name,))
        k = max(len(s.fit_starts) for s in EFFECTS[name].specs)
        starts = [_z_start(names, cur["names"], cur["state"]["z"], j) for j in range(k)]
        if bar is not None:
            bar.set_postfix_str(" + ".join(names))
        row = fitter.run(names, starts, scan=name)
        if bar is not None:
            bar.update(1)
        q = len(EFFECTS[name].specs)
        ssr = row["chi2"] * fitter.s2
        return {"names": names, "chi2": row["chi2"], "q": q, "state": row,
                "nrmse": math.sqrt(ssr / nf) / span,
                "ratio": math.sqrt(row["chi2"] / max(nf - 5 - q, 1)),
                "message": row["message"]}

    base_state = {"names": (), "chi2": base["chi2"], "q": 5, "state": base}
    sel = stepwise_select(fit_candidate, testable, base_state, tau=nl.tau_k, n_eff=nl.n_eff,
                          allowed=_allowed, **opts)
    sel.untestable = untestable
    sel.cycles = cycles
    return sel


def _assemble(rec, fitter, base, nl, sel, opts, t_start) -> Diagnosis:
    """Refit, forces, location, warnings and the result object."""
    FF, uj, v, alpha = rec.F, rec.uj, rec.v, opts["alpha"]
    warns = [f"noise estimate: {w}" for w in nl.warnings]
    F_base, _ = _record_force(base, uj, v)
    noise_only = pure_noise(FF[rec.keep], base["chi2"], nl.sigma, nl.tau_k, nl.n_eff)
    if noise_only:                       # nothing is identified from noise
        sel.named, sel.ambiguous = [], ()
        warns.append("the force is indistinguishable from noise (the Iwan model explains no "
                     "more than a constant): nothing is identified")
    final = sel.final["state"] if sel.named else base
    F_after, model = _record_force(final, uj, v)
    base_fit = _fit_result(base, fitter, FF, F_base, t_start, noise_only=noise_only)
    fit = base_fit if not sel.named else _fit_result(final, fitter, FF, F_after, t_start)
    misfit = sel.p_before < alpha and not noise_only
    r0 = FF - F_base
    where, loc = _locate(rec.t, uj, FF, F_base, r0, sel.cycles, nl.sigma, nl.tau) \
        if sel.cycles else ("", {})
    if not misfit:
        where = (f"The residual is consistent with the noise (RMS {np.sqrt(np.mean(r0 ** 2)):.3g} "
                 f"N vs {nl.sigma:.3g} N); there is no misfit to explain.")
    warns += _verdict_warnings(sel, misfit, alpha)
    details = _details(rec, nl, sel, opts, loc, final, fit, t_start)
    if final.get("start", 0.0) != 0.0:
        warns.append(f"the record does not start from the joint's rest: a path to "
                     f"{final['start']:.4g} +- {details['start_displacement_stderr']:.2g} m "
                     "before the first sample (the joint's unknown "
                     "starting state, fitted as a nuisance) fits better")
    span = float(np.ptp(FF)) or 1.0
    steps = [{"on": st["on"], "candidates": [
        {k: r.get(k) for k in ("name", "nrmse", "ratio", "dIC", "explained", "verdict", "message")}
        for r in st["rows"]]} for st in sel.steps]
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    return Diagnosis(
        effect=sel.named[0] if sel.named else "none", effects=tuple(sel.named),
        ambiguous_with=sel.ambiguous, where=where,
        success=bool(not noise_only and fit.success),
        offsets={"force": fit.details["force_offset"], "displacement": rec.u_offset},
        error_before=float(np.sqrt(np.mean(r0 ** 2)) / span),
        error_after=float(np.sqrt(np.mean((FF - F_after) ** 2)) / span),
        noise_level=nl.sigma / span, noise_sigma=float(nl.sigma), misfit=bool(misfit),
        base_fit=base_fit, fit=fit, model=model, steps=tuple(json_safe(s) for s in steps),
        untestable=sel.untestable, warnings=tuple(warns), force_before=ro(F_base),
        force_after=ro(np.array(F_after)),
        t=ro(np.arange(rec.n, dtype=float) if rec.t is None else rec.t),
        u=ro(rec.u), F=ro(FF), details=json_safe(details))


def _verdict_warnings(sel, misfit, alpha) -> list:
    """What the selection leaves unexplained."""
    if misfit and sel.named and sel.p_after < alpha:
        return [f"misfit beyond the noise remains after {' + '.join(sel.named)}"]
    if misfit and not sel.named:
        return ["the misfit is more than noise but no tested effect explains it" + (
            f"; this record cannot reveal {', '.join(sel.untestable)}" if sel.untestable
            else "")]
    return []


def _details(rec, nl, sel, opts, loc, final, fit, t_start) -> dict:
    """The diagnosis' ``details``: sizes, noise, tests, location and the starting state."""
    return {"samples": rec.n, "fitted_samples": int(rec.keep.size), "tau": nl.tau,
            "n_eff": nl.n_eff, "noise_from": nl.text, "misfit_p": sel.p_before,
            "misfit_p_after": sel.p_after, "alpha": opts["alpha"],
            "ambiguity": opts["ambiguity"], "criterion": criterion_text(), "location": loc,
            "lowpass": rec.lowpass,
            "lowpass_reason": "rig dynamics removed before fitting" if rec.lowpass else None,
            "start_displacement": float(final.get("start", 0.0)),
            "start_displacement_stderr": float(math.nan if (se_s := fit.details.get(
                "start_displacement_stderr")) is None else se_s),     # None: not determined
            "wall_time": time.perf_counter() - t_start}
