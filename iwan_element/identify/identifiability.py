"""Which Iwan parameters the data determine, and how well.

Identifiability
    If the data never reach macroslip, the loops (and ``F0``, ``D``) depend on ``KT``, ``chi``
    and ``R`` only; ``Fs`` and ``beta`` enter only through ``R`` and cannot be separated
    (REFERENCE.md sec. 2). Every fit therefore also fits the microslip-only model (``beta = 0``
    with ``phi_max`` above the largest backbone argument reached by the data, which represents
    the whole family) and keeps the four-parameter fit only if it reaches macroslip on enough
    data and improves the residual significantly (F-test at level ``alpha``). Otherwise the
    result marks ``Fs`` and ``beta`` as not identified, gives their range compatible with the
    data and reports the ``beta = 0`` member of the family as ``params``.

Uncertainties
    Standard errors and correlations come from the Jacobian of the residuals with respect to
    the transformed parameters ``(ln Fs, ln KT, chi, ln(1 + beta))`` (and the force offset
    ``dF0`` of a loop fit), central differences at the optimum:
    ``cov = tau s^2 (J^T J)^-1`` with ``s^2 = SSR/(m - p)``, mapped back to
    ``(Fs, KT, chi, beta)`` with the delta method. ``tau`` is the integrated autocorrelation
    time of the residuals (:func:`~iwan_element.identify.model_fit.integrated_time`): 1 for
    white residuals, large for coloured noise or a systematic misfit, so a model that does not
    follow the data gets wider, not narrower, intervals. ``s^2`` holds the noise of both
    channels (force noise plus tangent stiffness times the displacement error); the
    displacement that drives the model is de-noised first so that its noise does not create
    spurious reversals (errors in variables). ``benchmarks/bench_coverage.py`` checks the
    95 % intervals' coverage.

Verdict
    :func:`~iwan_element.identify.result._settle` applies one rule to every fit: identified
    means a finite standard error of at most half the value (``chi + 1`` for ``chi``) and not
    at a bound of the search range.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.special import fdtrc

from ..core._history import unit_params
from ..core.closed_form import backbone
from ..core.parameters import IwanParameters
from ._solver import _multistart, _Problem, _q_to_shape, _uncertainty
from .model_fit import integrated_time
from .result import PARAM_NAMES

_CHI_BOUNDS = (-0.98, 1.0)            # search range of chi (physical joints: -1 < chi <= 0)
_BETA_MAX = 100.0
_PHI_RANGE = (1e-3, 1e4)              # search range of phi_max / x_max


def _range_warnings(params: IwanParameters) -> list[str]:
    out = []
    if params.chi > 0:
        out.append(f"chi = {params.chi:.3g} > 0 is outside the physical range -1 < chi <= 0")
    return out


def _identify(prob: _Problem, *, n_starts: int, rng: np.random.Generator, alpha: float,
              max_nfev: int, initial: IwanParameters | None):
    """Microslip-only fit, four-parameter multi-start fit, macroslip test, covariance.

    Returns a dict with the chosen params, stderr, correlation, identified, ranges, residuals
    and diagnostics.
    """
    xm = prob.x_max
    lo_q, hi_q = math.log(_PHI_RANGE[0]), math.log(_PHI_RANGE[1])
    # ---- microslip only: beta = 0, phi_max >= x_max (represents every microslip model)
    lower_m = np.array([0.0, _CHI_BOUNDS[0]])
    upper_m = np.array([hi_q, _CHI_BOUNDS[1]])
    starts_m = [(math.log(2.0), -0.5), (math.log(1.2), -0.2), (math.log(5.0), -0.8),
                (math.log(1.5), 0.3)]
    res_m = _multistart(prob, starts_m, lower_m, upper_m, beta_fixed=0.0, max_nfev=max_nfev)
    phi_m, chi_m, _ = _q_to_shape(res_m.x, xm, 0.0)
    Fs_m, r_m = prob.projected(phi_m, chi_m, 0.0)
    ssr_m = float(r_m @ r_m)
    # ---- all four parameters
    lower = np.array([lo_q, _CHI_BOUNDS[0], 0.0])
    upper = np.array([hi_q, _CHI_BOUNDS[1], math.log1p(_BETA_MAX)])
    starts = [(res_m.x[0], chi_m, 0.0), (math.log(0.7), chi_m, math.log(2.0)),
              (math.log(0.4), chi_m, 0.0), (math.log(0.9), chi_m, math.log(4.0))]
    if initial is not None:
        starts.insert(0, (math.log(initial.phi_max / xm), initial.chi, math.log1p(initial.beta)))
    while len(starts) < n_starts:
        starts.append((rng.uniform(math.log(0.2), math.log(2.0)), rng.uniform(-0.9, -0.05),
                       rng.uniform(0.0, math.log(4.0))))
    starts = starts[:max(n_starts, 1 if initial is None else 2)]
    res_f = _multistart(prob, starts, lower, upper, beta_fixed=None, max_nfev=max_nfev)
    phi_f, chi_f, beta_f = _q_to_shape(res_f.x, xm, None)
    Fs_f, r_f = prob.projected(phi_f, chi_f, beta_f)
    ssr_f = float(r_f @ r_f)
    m = r_f.size
    n_macro = prob.n_macro(phi_f)
    tau_f = integrated_time(r_f) if prob.timeseries else 1.0
    m_eff = m / tau_f                      # correlated residuals carry fewer independent data
    if ssr_f > 0 and m_eff > 5:
        F_stat = max(ssr_m - ssr_f, 0.0) / (ssr_f / (m - 4)) / tau_f
        p_value = float(fdtrc(1, m_eff - 4, F_stat))      # F-distribution survival
    else:
        F_stat, p_value = (math.inf, 0.0) if ssr_m > ssr_f else (0.0, 1.0)
    macro = (phi_f < xm and n_macro >= prob.min_macro and p_value < alpha)
    details = {"x_max": xm, "ssr_microslip": ssr_m, "ssr_full": ssr_f, "F_statistic": F_stat,
               "p_value": p_value, "alpha": alpha, "macroslip_residuals": n_macro,
               "macroslip_reached": bool(macro), "starts": len(starts)}
    warns: list[str] = []
    tau_of = (lambda r_: integrated_time(r_)) if prob.timeseries else (lambda r_: 1.0)
    off = prob.offset
    if macro:
        Fs, chi, beta = Fs_f, chi_f, beta_f
        KT = Fs * unit_params(phi_f, chi, beta).KT
        params = IwanParameters(Fs, KT, chi, beta)
        res, r = res_f, r_f
        dF0 = prob.dF0 if off else 0.0
        tau = tau_of(r)
        theta = np.array([math.log(Fs), math.log(KT), chi, math.log1p(beta)] + ([dF0] if off else []))

        def fun(th):
            return prob.residual(IwanParameters(math.exp(th[0]), math.exp(th[1]), th[2],
                                                math.expm1(th[3])), th[4] if off else 0.0)

        se, corr = _uncertainty(fun, theta, r, [Fs, KT, 1.0, 1.0 + beta] + ([1.0] if off else []),
                                at_lower_bound=3, tau=tau,
                                timeseries=prob.timeseries, block=prob.block)
        stderr = dict(zip(PARAM_NAMES, se[:4].tolist()))
        se_off = float(se[4]) if off else math.nan
        corr = corr[:4, :4]
        identified = dict.fromkeys(PARAM_NAMES, True)
        ranges = {}
        at_bound = [k for k, v, (lo, hi) in (("chi", chi, _CHI_BOUNDS), ("beta", beta, (0, _BETA_MAX)))
                    if min(abs(v - lo), abs(v - hi)) < 1e-6]
        if phi_f <= xm * _PHI_RANGE[0] * (1 + 1e-6):
            at_bound += ["Fs", "KT"]
        details["macroslip_fraction"] = n_macro / m
    else:
        Fs0, phi0, chi = Fs_m, phi_m, chi_m
        KT = Fs0 * unit_params(phi0, chi, 0.0).KT
        params = IwanParameters(Fs0, KT, chi, 0.0)
        R = params.R
        res, r = res_m, r_m
        prob.projected(phi_m, chi_m, 0.0)
        dF0 = prob.dF0 if off else 0.0
        tau = tau_of(r)
        theta = np.array([math.log(KT), chi, math.log(R)] + ([dF0] if off else []))

        def fun(th):
            # the beta = 0 member for (KT, chi, R): R phi^(chi+1) = (chi+1) KT, eq. 10
            KT_, chi_, R_ = math.exp(th[0]), th[1], math.exp(th[2])
            phi_ = ((chi_ + 1.0) * KT_ / R_) ** (1.0 / (chi_ + 1.0))
            return prob.residual(IwanParameters(KT_ * phi_ * (chi_ + 1.0) / (chi_ + 2.0), KT_,
                                                chi_, 0.0), th[3] if off else 0.0)

        se3, c3 = _uncertainty(fun, theta, r, [KT, 1.0, R] + ([1.0] if off else []), tau=tau,
                               timeseries=prob.timeseries, block=prob.block)
        se_off = float(se3[3]) if off else math.nan
        stderr = {"Fs": math.nan, "KT": se3[0], "chi": se3[1], "beta": math.nan}
        corr = np.full((4, 4), np.nan)
        corr[1:3, 1:3] = c3[:2, :2]
        at_bound = [k for k, v, (lo, hi) in (("chi", chi, _CHI_BOUNDS),)
                    if min(abs(v - lo), abs(v - hi)) < 1e-6]
        identified = {"Fs": False, "KT": True, "chi": True, "beta": False}
        # family members that fit equally: phi_max in [x_max, phi0], beta = (phi0/phi)^(chi+1) - 1
        beta_hi = (phi0 / xm) ** (chi + 1.0) - 1.0
        Fs_lo = backbone(xm, params)             # phi_max = x_max: Fs is the force reached
        ranges = {"Fs": (float(Fs_lo), float(Fs0)), "beta": (0.0, float(beta_hi))}
        details.update({"R": R, "stderr_R": se3[2], "corr_KT_chi_R": c3[:3, :3]})
        if n_macro >= prob.min_macro and phi_f < xm:
            why = (f"the four-parameter fit puts macroslip in the data but does not improve "
                   f"the residual significantly (p = {p_value:.2g} >= {alpha:g})")
        else:
            why = ("the data do not reach macroslip (largest backbone argument "
                   f"{xm * 1e3:.4g} mm <= phi_max)")
        warns.append(f"Fs and beta are NOT identified: {why}; the data determine only KT, chi "
                     f"and R = {R:.5g}. Any Fs in [{Fs_lo:.5g}, {Fs0:.5g}] N with beta in "
                     f"[0, {beta_hi:.4g}] fits equally; params reports the beta = 0 member. "
                     "Test to larger amplitudes to identify them.")
        if phi0 <= xm * (1 + 1e-9):
            warns.append("the microslip fit sits at its bound phi_max = x_max: the backbone's "
                         "tangent vanishes at the largest excursion; more data near macroslip "
                         "would settle Fs")
    warns += _range_warnings(params)
    details["tau"] = tau
    return {"params": params, "stderr": stderr, "correlation": corr, "identified": identified,
            "ranges": ranges, "res": res, "r": r, "warnings": warns, "details": details,
            "at_bound": at_bound, "dF0": (dF0, se_off), "tau": tau,
            "ssr": float(r @ r), "n_free": 4 if macro else 3}


