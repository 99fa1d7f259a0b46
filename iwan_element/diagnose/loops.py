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

import numpy as np
from scipy.signal import butter, sosfiltfilt

from ..core.history import REVERSAL_TOL, unit_params
from ..core.validation import (MAGNITUDE_RANGE, check_int, check_time, check_magnitude,
                                check_scalar, finite_array, same_length)
from ..effects import EFFECTS
from ..effects.evaluate import Evaluator, build_element, order_stack, stack_ok
from ..ensemble.runner import progress_bar
from ..identify.testdata import find_reversals, split_cycles
from . import _model as M
from ._locate import _check_candidates, _locate, _untestable
from ._noise import noise_estimate, pure_noise
from ..identify.result import settle_verdict
from ..core.serialize import json_safe
from ..core.threads import one_blas_thread
from .results import Diagnosis
from .selection import criterion_text, stepwise_select

__all__ = ["CANDIDATES", "diagnose"]

log = logging.getLogger(__name__)

#: Candidate effects tried by :func:`diagnose`, in the order they are reported.
CANDIDATES = ("viscous_damping", "pinning_stiffness", "backlash", "slip_degradation",
              "asymmetric_slip", "breakaway")
_SLOW_FIT_SAMPLES = 300          # samples fitted for stacks without a vectorised form


def _rest_index(u, noise_u):
    """Samples before the motion starts (at least 1)."""
    thr = max(1e-6 * float(np.ptp(u)), 5.0 * noise_u)
    moved = np.flatnonzero(np.abs(u - u[0]) > thr)
    return max(int(moved[0]) if moved.size else 1, 1)


def _prepare(t, u, F, noise, lowpass):
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=40), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=40), unit="N")
    n = same_length(u=uu, F=FF)
    tt = None if t is None else check_time(t, n)
    if not np.ptp(uu) > 0:
        raise ValueError("u never moves: a displacement-driven test is needed")
    scale_F = max(float(np.max(np.abs(FF))), 1e-300)
    if noise is not None:
        noise = check_scalar("noise", noise, low=MAGNITUDE_RANGE[0], high=MAGNITUDE_RANGE[1])
        if noise < 1e-9 * scale_F:
            raise ValueError(f"noise = {noise:g} N is below the floating-point resolution of the "
                             f"force record (1e-9 x max|F| = {1e-9 * scale_F:.3g} N); give a "
                             "realistic noise level or leave noise=None to estimate it")
    lp = None
    if lowpass is not None:
        if tt is None:
            raise ValueError("lowpass needs the time vector t")
        fs = 1.0 / float(np.median(np.diff(tt)))
        lp = check_scalar("lowpass", lowpass, low=0.0, high=0.5 * fs, low_open=True,
                          high_open=True)
    return uu, FF, tt, n, noise, lp


def _filter(tt, x, lp):
    fs = 1.0 / float(np.median(np.diff(tt)))
    sos = butter(4, lp, fs=fs, output="sos")
    return sosfiltfilt(sos, x)


def _noise_level(tt, r, noise, lp, channel=None):
    """``(sigma [N], tau [samples], text, warnings)`` of the force as fitted, from the
    residual ``r`` of a fit to the raw force (the model removes the loops' corners, the
    estimator the smooth rest of any model error); ``channel``: the measured force, whose
    loading time scale sets the estimator's window."""
    if noise is not None:
        return noise, 1.0, "given", ()
    sigma, tau, method, warns = noise_estimate(tt, r, channel)
    text = f"estimated from the record ({method})"
    if lp is not None:                       # white noise through the low-pass
        fs = 1.0 / float(np.median(np.diff(tt)))
        frac = min(2.0 * lp / fs, 1.0)
        sigma *= math.sqrt(frac)
        tau = max(tau, 1.0 / frac)
        text += f", reduced to the {lp:g} Hz band"
    if not sigma > 0:
        sigma = 1e-9 * float(np.max(np.abs(r))) or 1e-300
        warns = tuple(warns) + ("no noise found in the force: a floor of 1e-9 x max|F| is "
                                "used",)
    return sigma, tau, text, tuple(warns)


def _evaluators(uj, v, max_samples):
    n = uj.size
    rev = find_reversals(uj) if n > 2 else np.zeros(0, np.intp)
    tol = REVERSAL_TOL * float(np.abs(uj).max())
    keep = np.unique(np.round(np.linspace(0, n - 1, min(n, max_samples))).astype(np.intp))
    ev = Evaluator(uj, v, keep, rev, tol=tol)
    sub = keep[np.unique(np.round(np.linspace(0, keep.size - 1,
                                              min(keep.size, _SLOW_FIT_SAMPLES))).astype(np.intp))]
    ev_slow = Evaluator(uj, v, sub, rev, tol=tol)
    return ev, ev_slow, keep, sub


def _base_start(tt, uj, FF, seed):
    """Shape start ``(phi_max, chi, beta)`` from the plain loop fit, or None."""
    from ..identify.loops import fit_loops
    from ..identify.result import quiet_fits
    try:
        with quiet_fits():
            res = fit_loops(tt, uj, FF, seed=seed, max_samples=3000, n_starts=3)
        p = res.params
        return (p.phi_max, p.chi, p.beta)
    except (ValueError, FloatingPointError, ZeroDivisionError):
        return None


class _Fitter:
    """Fits stacks on one record; scores them as noise-normalised chi2 on the full keep set."""

    def __init__(self, ev, ev_slow, FF, keep, sub, scales, sigma, F0=None):
        self.ev, self.ev_slow, self.scales, self.s2 = ev, ev_slow, scales, sigma * sigma
        self.F0 = F0
        self.y, self.y_sub = FF[keep], FF[sub]
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
        Effects to try (default :data:`CANDIDATES`).
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
    uu, FF_in, tt, n, noise, lp = _prepare(t, u, F, noise, lowpass)
    cand = _check_candidates(candidates, CANDIDATES)
    max_effects = check_int("max_effects", max_effects, 1)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    ambiguity = check_scalar("ambiguity", ambiguity, low=0.0)
    max_samples = check_int("max_samples", max_samples, 100)
    bar = progress_bar(progress, desc="diagnose", unit="fit")
    try:
        with one_blas_thread():          # tall, narrow least squares: threads only spin
            return _diagnose(tt, uu, FF_in, n, noise, lp, cand, max_effects, alpha, ambiguity,
                             max_samples, seed, bar, t_start)
    finally:
        if bar is not None:
            bar.close()


def _diagnose(tt, uu, FF_in, n, noise, lp, cand, max_effects, alpha, ambiguity, max_samples,
              seed, bar, t_start):
    """The procedure of :func:`diagnose` on checked input (see the module docstring)."""
    FF = FF_in
    if lp is not None:
        # both channels, as the rig's dynamics and the sensor noise are in both: the joint is
        # driven by the displacement without them. Raw displacement noise makes turning
        # points by the hundred (154 on a 1 Hz damper record at the fitted samples, 26 after
        # a 20 Hz low-pass), and every one re-sticks the sliders of a break-away model
        FF, uu = _filter(tt, FF_in, lp), _filter(tt, uu, lp)
    i_rest = _rest_index(uu, noise_estimate(tt, uu)[0])
    u_off = float(np.mean(uu[:i_rest]))
    # the force offset is always fitted (linear, with Fs), the rest samples being part of the
    # fitted data: a mean over a few rest samples has an error of sigma/sqrt(n_rest) that a
    # fixed offset would leave in the residual as a constant misfit (a false "effect")
    F_rest = None
    uj = uu - u_off
    v = np.zeros(n) if tt is None else np.gradient(uj, tt)
    ev, ev_slow, keep, sub = _evaluators(uj, v, max_samples)
    fitter = _Fitter(ev, ev_slow, FF, keep, sub, {"u_max": float(np.abs(uj).max()), "1": 1.0,
                                                  "v_rms": float(np.sqrt(np.mean(v ** 2))) or 1.0,
                                                  "D_ref": 1.0}, 1.0, F_rest)
    base = _fit_base(fitter, ev, _base_start(tt, uj, FF, seed))
    if bar is not None:
        bar.set_postfix_str("Iwan")
        bar.update(1)
    r_raw = FF_in - _record_force(base, uj, v)[0]
    sigma, tau, noise_text, nwarn = _noise_level(tt, r_raw, noise, lp, FF_in)
    fitter.s2 = sigma * sigma
    base["chi2"] = base["ssr"] / fitter.s2
    shape_b, _ = base["model"].decode(base["z"])
    fitter.scales["D_ref"] = float(ev.unit_dissipation(unit_params(*shape_b))[-1]) or 1.0
    tau_k = max(1.0, tau * keep.size / n)
    n_eff = keep.size / tau_k
    sel = _select(fitter, base, cand, tt, v, uj, FF, tau_k, n_eff, alpha, max_effects, ambiguity,
                  bar=bar)
    for _ in range(2 if noise is None else 0):
        # a large misfit leaks into the plain fit's residual and inflates the noise estimate,
        # which can hide a further effect: the noise is re-read from the residual of the
        # model selected, and the selection is repeated with it (the fits are reused)
        if not sel.named:
            break
        r_fin = FF_in - _record_force(sel.final["state"], uj, v)[0]
        s_new, t_new, noise_text, nwarn = _noise_level(tt, r_fin, noise, lp, FF_in)
        if abs(s_new - sigma) <= 0.05 * sigma and abs(t_new - tau) <= 0.1 * tau:
            break
        sigma, tau = s_new, t_new
        noise_text += ", from the residual of the model selected"
        fitter.s2 = sigma * sigma
        base["chi2"] = base["ssr"] / fitter.s2
        tau_k = max(1.0, tau * keep.size / n)
        n_eff = keep.size / tau_k
        sel = _select(fitter, base, cand, tt, v, uj, FF, tau_k, n_eff, alpha, max_effects,
                      ambiguity, bar=bar)
    ctx = dict(t_start=t_start, uu=uu, FF_in=FF_in, FF=FF, tt=tt, n=n, noise=noise, lp=lp,
               sigma=sigma, tau=tau, noise_text=noise_text, nwarn=nwarn, u_off=u_off, uj=uj,
               v=v, keep=keep, fitter=fitter, base=base, tau_k=tau_k, n_eff=n_eff, sel=sel,
               alpha=alpha, ambiguity=ambiguity, cand=cand)
    return _assemble(ctx)


def _select(fitter, base, cand, tt, v, uj, FF, tau_k, n_eff, alpha, max_effects, ambiguity, *,
            bar=None):
    """Run the shared selection rule over the testable candidates (``bar``: a progress bar
    counting the fits)."""
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
    sel = stepwise_select(fit_candidate, testable, base_state, tau=tau_k, n_eff=n_eff,
                          alpha=alpha, max_effects=max_effects, ambiguity=ambiguity,
                          allowed=_allowed)
    sel.untestable = untestable
    sel.cycles = cycles
    return sel


def _assemble(c) -> Diagnosis:
    """Refit, forces, location, warnings and the result object."""
    sel, fitter, FF, uj, v = c["sel"], c["fitter"], c["FF"], c["uj"], c["v"]
    warns = [f"noise estimate: {w}" for w in c["nwarn"]]
    base = c["base"]
    F_base, _ = _record_force(base, uj, v)
    noise_only = pure_noise(FF[c["keep"]], base["chi2"], c["sigma"], c["tau_k"], c["n_eff"])
    if noise_only:                       # nothing is identified from noise
        sel.named, sel.ambiguous = [], ()
    final = sel.final["state"] if sel.named else base
    F_after, model = _record_force(final, uj, v)
    if noise_only:
        warns.append("the force is indistinguishable from noise (the Iwan model explains no "
                     "more than a constant): nothing is identified")
    base_fit = _fit_result(base, fitter, FF, F_base, c["t_start"], noise_only=noise_only)
    fit = base_fit if not sel.named else _fit_result(final, fitter, FF, F_after, c["t_start"])
    misfit = sel.p_before < c["alpha"] and not noise_only
    r0 = FF - F_base
    where, loc = _locate(c["tt"], uj, FF, F_base, r0, sel.cycles, c["sigma"], c["tau"]) \
        if sel.cycles else ("", {})
    if not misfit:
        where = (f"The residual is consistent with the noise (RMS {np.sqrt(np.mean(r0 ** 2)):.3g} "
                 f"N vs {c['sigma']:.3g} N); there is no misfit to explain.")
    if misfit and sel.named and sel.p_after < c["alpha"]:
        warns.append(f"misfit beyond the noise remains after {' + '.join(sel.named)}")
    if misfit and not sel.named:
        warns.append("the misfit is more than noise but no tested effect explains it" + (
            f"; this record cannot reveal {', '.join(sel.untestable)}" if sel.untestable else ""))
    span = float(np.ptp(FF)) or 1.0
    steps = [{"on": st["on"], "candidates": [
        {k: r.get(k) for k in ("name", "nrmse", "ratio", "dIC", "explained", "verdict", "message")}
        for r in st["rows"]]} for st in sel.steps]
    F0 = fit.details["force_offset"]
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    details = {"samples": c["n"], "fitted_samples": int(c["keep"].size), "tau": c["tau"],
               "n_eff": c["n_eff"], "noise_from": c["noise_text"], "misfit_p": sel.p_before,
               "misfit_p_after": sel.p_after, "alpha": c["alpha"], "ambiguity": c["ambiguity"],
               "criterion": criterion_text(), "location": loc, "lowpass": c["lp"],
               "lowpass_reason": "rig dynamics removed before fitting" if c["lp"] else None,
               "start_displacement": float(final.get("start", 0.0)),
               "start_displacement_stderr": float(fit.details.get("start_displacement_stderr",
                                                                  0.0)),
               "wall_time": time.perf_counter() - c["t_start"]}
    if final.get("start", 0.0) != 0.0:
        warns.append(f"the record does not start from the joint's rest: a path to "
                     f"{final['start']:.4g} +- {details['start_displacement_stderr']:.2g} m "
                     "before the first sample (the joint's unknown "
                     "starting state, fitted as a nuisance) fits better")
    return Diagnosis(
        effect=sel.named[0] if sel.named else "none", effects=tuple(sel.named),
        ambiguous_with=sel.ambiguous, where=where,
        success=bool(not noise_only and fit.success), offsets={"force": F0, "displacement": c["u_off"]},
        error_before=float(np.sqrt(np.mean(r0 ** 2)) / span),
        error_after=float(np.sqrt(np.mean((FF - F_after) ** 2)) / span),
        noise_level=c["sigma"] / span, noise_sigma=float(c["sigma"]), misfit=bool(misfit),
        base_fit=base_fit, fit=fit, model=model, steps=tuple(json_safe(s) for s in steps),
        untestable=sel.untestable, warnings=tuple(warns), force_before=ro(F_base),
        force_after=ro(np.array(F_after)),
        t=ro(np.arange(c["n"], dtype=float) if c["tt"] is None else c["tt"]),
        u=ro(c["uu"]), F=ro(FF), details=json_safe(details))
