"""Which Iwan parameters the data determine, and how well.

Identifiability
    If the data never reach macroslip, the loops (and ``F0``, ``D``) depend on ``KT``, ``chi``
    and ``R`` only; ``Fs`` and ``beta`` enter only through ``R`` and cannot be separated
    (docs/equations.md section 2). Every fit therefore also fits the microslip-only model
    (``beta = 0`` with ``phi_max`` above the largest backbone argument reached by the data, which
    represents
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
    time of the residuals (:func:`~iwan_element.identify.loops.noise.integrated_time`): 1 for
    white residuals, large for coloured noise or a systematic misfit, so a model that does not
    follow the data gets wider, not narrower, intervals. ``s^2`` holds the noise of both
    channels (force noise plus tangent stiffness times the displacement error); the
    displacement that drives the model is de-noised first so that its noise does not create
    spurious reversals (errors in variables). ``benchmarks/bench_coverage.py`` checks the
    95 % intervals' coverage. The covariance is the package's one routine,
    :func:`iwan_element.fitting.covariance` (docs/fitting.md): column-scaled, a parameter
    along a degenerate direction gets a NaN error.

Verdict
    :func:`~iwan_element.identify.loops.joint_verdict.settle_verdict` applies the package's one rule
    (:func:`iwan_element.fitting.verdict`, docs/fitting.md section 5): identified means a
    finite standard error of at most half the value (``chi + 1`` for ``chi``) and not at a
    bound of the search range.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import fdtrc

from ...core.closed_form import backbone
from ...core.history import unit_params
from ...core.parameters import IwanParameters
from .joint_verdict import PARAM_NAMES
from .noise import integrated_time
from .solver import _multistart, _Problem, _q_to_shape, _uncertainty

_CHI_BOUNDS = (-0.98, 1.0)  # search range of chi (physical joints: -1 < chi <= 0)
_BETA_MAX = 100.0
_PHI_RANGE = (1e-3, 1e4)  # search range of phi_max / x_max


#: Fewest amplitude points (of a dissipation or modal curve) beyond the fitted ``phi_max``
#: before the joint's macroslip parameters count as identified: fewer, and the fit may put
#: its slip onset among the last points to bend them (noise), which fixes nothing.
MIN_MACRO_POINTS = 4


def min_macroslip(n: int) -> int:
    """Fitted samples that must lie in macroslip (backbone argument above the fitted
    ``phi_max``) before ``Fs`` and ``beta`` can count as identified: ``max(10, 0.5 %)`` of the
    ``n`` fitted samples. Fewer, and the fit may put its slip onset at the largest excursion
    to bend the last few samples (noise), which fixes nothing (docs/guards.md).
    """
    return max(10, int(0.005 * n))


def microslip_warning(n_macro: int, n: int, x_max: float, phi_max: float) -> str:
    """Why ``Fs`` and ``beta`` are not identified when only ``n_macro`` of ``n`` samples
    reach macroslip (the tester's words of :func:`min_macroslip`).
    """
    return (
        f"Fs and beta are NOT identified by these data: the loops stay in microslip (only "
        f"{n_macro} of {n} fitted samples beyond the fitted slip onset phi_max = "
        f"{phi_max:.4g} m, largest excursion {x_max:.4g} m; {min_macroslip(n)} needed); "
        "only KT, chi and their microslip combination are fixed. Test to larger amplitudes "
        "to identify them"
    )


def _range_warnings(params: IwanParameters) -> list[str]:
    out = []
    if params.chi > 0:
        out.append(f"chi = {params.chi:.3g} > 0 is outside the physical range -1 < chi <= 0")
    return out


def _identify(
    prob: _Problem,
    *,
    n_starts: int,
    rng: np.random.Generator,
    alpha: float,
    max_nfev: int,
    initial: IwanParameters | None,
):
    """Microslip-only fit, four-parameter multi-start fit, macroslip test, covariance.

    Returns a dict with the chosen params, stderr, correlation, identified, ranges, residuals
    and diagnostics.
    """
    micro = _fit_microslip(prob, max_nfev=max_nfev)
    full = _fit_full(prob, micro, n_starts=n_starts, rng=rng, max_nfev=max_nfev, initial=initial)
    macro, details = _macroslip_test(prob, micro, full, alpha)
    out = _macro_result(prob, full, details) if macro else _micro_result(prob, micro, full, details)
    out["warnings"] += _range_warnings(out["params"])
    details["tau"] = out["tau"]
    r = out["r"]
    out.update(details=details, ssr=float(r @ r), n_free=4 if macro else 3)
    return out


def _fit_microslip(prob: _Problem, *, max_nfev: int) -> dict:
    """The microslip-only fit: beta = 0, phi_max >= x_max (it represents every microslip
    model, docs/equations.md section 2 (seed paper eq. 10)).
    """
    lower = np.array([0.0, _CHI_BOUNDS[0]])
    upper = np.array([math.log(_PHI_RANGE[1]), _CHI_BOUNDS[1]])
    starts = [
        (math.log(2.0), -0.5),
        (math.log(1.2), -0.2),
        (math.log(5.0), -0.8),
        (math.log(1.5), 0.3),
    ]
    res = _multistart(prob, starts, lower, upper, beta_fixed=0.0, max_nfev=max_nfev)
    phi, chi, _ = _q_to_shape(res.x, prob.x_max, 0.0)
    Fs, r = prob.projected(phi, chi, 0.0)
    return {"res": res, "phi": phi, "chi": chi, "Fs": Fs, "r": r}


def _fit_full(
    prob: _Problem,
    micro: dict,
    *,
    n_starts: int,
    rng: np.random.Generator,
    max_nfev: int,
    initial: IwanParameters | None,
) -> dict:
    """The four-parameter multi-start fit, started from the microslip fit, the user's
    ``initial`` and random shapes.
    """
    xm, chi_m = prob.x_max, micro["chi"]
    lower = np.array([math.log(_PHI_RANGE[0]), _CHI_BOUNDS[0], 0.0])
    upper = np.array([math.log(_PHI_RANGE[1]), _CHI_BOUNDS[1], math.log1p(_BETA_MAX)])
    starts = [
        (micro["res"].x[0], chi_m, 0.0),
        (math.log(0.7), chi_m, math.log(2.0)),
        (math.log(0.4), chi_m, 0.0),
        (math.log(0.9), chi_m, math.log(4.0)),
    ]
    if initial is not None:
        starts.insert(0, (math.log(initial.phi_max / xm), initial.chi, math.log1p(initial.beta)))
    while len(starts) < n_starts:
        starts.append(
            (
                rng.uniform(math.log(0.2), math.log(2.0)),
                rng.uniform(-0.9, -0.05),
                rng.uniform(0.0, math.log(4.0)),
            )
        )
    starts = starts[: max(n_starts, 1 if initial is None else 2)]
    res = _multistart(prob, starts, lower, upper, beta_fixed=None, max_nfev=max_nfev)
    phi, chi, beta = _q_to_shape(res.x, xm, None)
    Fs, r = prob.projected(phi, chi, beta)
    return {
        "res": res,
        "phi": phi,
        "chi": chi,
        "beta": beta,
        "Fs": Fs,
        "r": r,
        "starts": len(starts),
    }


def _tau(prob: _Problem, r) -> float:
    """Correlation time of a residual [samples]: 1 for points that are not a time series."""
    return integrated_time(r) if prob.timeseries else 1.0


def _macroslip_test(prob: _Problem, micro: dict, full: dict, alpha: float):
    """Whether the data reach macroslip: the four-parameter fit puts macroslip samples in the
    data and lowers the residual significantly (F test on the effective samples).
    Returns ``(macro, details)``.
    """
    xm, r_f = prob.x_max, full["r"]
    ssr_m, ssr_f = float(micro["r"] @ micro["r"]), float(r_f @ r_f)
    m = r_f.size
    n_macro = prob.n_macro(full["phi"])
    tau_f = _tau(prob, r_f)
    m_eff = m / tau_f  # correlated residuals carry fewer independent data
    if ssr_f > 0 and m_eff > 5:
        F_stat = max(ssr_m - ssr_f, 0.0) / (ssr_f / (m - 4)) / tau_f
        p_value = float(fdtrc(1, m_eff - 4, F_stat))  # F-distribution survival
    else:
        F_stat, p_value = (math.inf, 0.0) if ssr_m > ssr_f else (0.0, 1.0)
    macro = full["phi"] < xm and n_macro >= prob.min_macro and p_value < alpha
    details = {
        "x_max": xm,
        "ssr_microslip": ssr_m,
        "ssr_full": ssr_f,
        "F_statistic": F_stat,
        "p_value": p_value,
        "alpha": alpha,
        "macroslip_residuals": n_macro,
        "macroslip_reached": bool(macro),
        "starts": full["starts"],
    }
    return macro, details


def _macro_result(prob: _Problem, full: dict, details: dict) -> dict:
    """All four parameters identified: their covariance in (ln Fs, ln KT, chi, ln(1+beta))."""
    xm, off = prob.x_max, prob.offset
    Fs, chi, beta, phi_f = full["Fs"], full["chi"], full["beta"], full["phi"]
    KT = Fs * unit_params(phi_f, chi, beta).KT
    params = IwanParameters(Fs, KT, chi, beta)
    r = full["r"]
    dF0 = prob.dF0 if off else 0.0
    tau = _tau(prob, r)
    theta = np.array([math.log(Fs), math.log(KT), chi, math.log1p(beta)] + ([dF0] if off else []))

    def fun(th):
        return prob.residual(
            IwanParameters(math.exp(th[0]), math.exp(th[1]), th[2], math.expm1(th[3])),
            th[4] if off else 0.0,
        )

    se, corr = _uncertainty(
        fun,
        theta,
        r,
        [Fs, KT, 1.0, 1.0 + beta] + ([1.0] if off else []),
        at_lower_bound=3,
        tau=tau,
        timeseries=prob.timeseries,
        block=prob.block,
    )
    at_bound = [
        k
        for k, v, (lo, hi) in (("chi", chi, _CHI_BOUNDS), ("beta", beta, (0, _BETA_MAX)))
        if min(abs(v - lo), abs(v - hi)) < 1e-6
    ]
    if phi_f <= xm * _PHI_RANGE[0] * (1 + 1e-6):
        at_bound += ["Fs", "KT"]
    details["macroslip_fraction"] = details["macroslip_residuals"] / r.size
    return {
        "params": params,
        "stderr": dict(zip(PARAM_NAMES, se[:4].tolist())),
        "correlation": corr[:4, :4],
        "identified": dict.fromkeys(PARAM_NAMES, True),
        "ranges": {},
        "res": full["res"],
        "r": r,
        "warnings": [],
        "at_bound": at_bound,
        "dF0": (dF0, float(se[4]) if off else math.nan),
        "tau": tau,
    }


def _micro_result(prob: _Problem, micro: dict, full: dict, details: dict) -> dict:
    """Microslip only: KT, chi and R identified (docs/equations.md section 2 (seed paper
    eq. 10)); Fs and beta given as
    the range of the family that fits equally, with a warning that says why.
    """
    xm, off = prob.x_max, prob.offset
    Fs0, phi0, chi = micro["Fs"], micro["phi"], micro["chi"]
    KT = Fs0 * unit_params(phi0, chi, 0.0).KT
    params = IwanParameters(Fs0, KT, chi, 0.0)
    R = params.R
    r = micro["r"]
    prob.projected(phi0, chi, 0.0)  # the offset of this member (prob.dF0)
    dF0 = prob.dF0 if off else 0.0
    tau = _tau(prob, r)
    theta = np.array([math.log(KT), chi, math.log(R)] + ([dF0] if off else []))

    def fun(th):
        # the beta = 0 member for (KT, chi, R): R phi^(chi+1) = (chi+1) KT, eq. 10
        KT_, chi_, R_ = math.exp(th[0]), th[1], math.exp(th[2])
        phi_ = ((chi_ + 1.0) * KT_ / R_) ** (1.0 / (chi_ + 1.0))
        return prob.residual(
            IwanParameters(KT_ * phi_ * (chi_ + 1.0) / (chi_ + 2.0), KT_, chi_, 0.0),
            th[3] if off else 0.0,
        )

    se3, c3 = _uncertainty(
        fun,
        theta,
        r,
        [KT, 1.0, R] + ([1.0] if off else []),
        tau=tau,
        timeseries=prob.timeseries,
        block=prob.block,
    )
    corr = np.full((4, 4), np.nan)
    corr[1:3, 1:3] = c3[:2, :2]
    at_bound = [
        k for k, v, (lo, hi) in (("chi", chi, _CHI_BOUNDS),) if min(abs(v - lo), abs(v - hi)) < 1e-6
    ]
    # family members that fit equally: phi_max in [x_max, phi0], beta = (phi0/phi)^(chi+1) - 1
    beta_hi = (phi0 / xm) ** (chi + 1.0) - 1.0
    Fs_lo = backbone(xm, params)  # phi_max = x_max: Fs is the force reached
    details.update({"R": R, "stderr_R": se3[2], "corr_KT_chi_R": c3[:3, :3]})
    p_value, alpha = details["p_value"], details["alpha"]
    if details["macroslip_residuals"] >= prob.min_macro and full["phi"] < xm:
        why = (
            f"the four-parameter fit puts macroslip in the data but does not improve "
            f"the residual significantly (p = {p_value:.2g} >= {alpha:g})"
        )
    else:
        why = f"the data do not reach macroslip (largest backbone argument {xm:.4g} m <= phi_max)"
    warns = [
        f"Fs and beta are NOT identified: {why}; the data determine only KT, chi "
        f"and R = {R:.5g}. Any Fs in [{Fs_lo:.5g}, {Fs0:.5g}] N with beta in "
        f"[0, {beta_hi:.4g}] fits equally; params reports the beta = 0 member. "
        "Test to larger amplitudes to identify them."
    ]
    if phi0 <= xm * (1 + 1e-9):
        warns.append(
            "the microslip fit sits at its bound phi_max = x_max: the backbone's "
            "tangent vanishes at the largest excursion; more data near macroslip "
            "would settle Fs"
        )
    return {
        "params": params,
        "stderr": {"Fs": math.nan, "KT": se3[0], "chi": se3[1], "beta": math.nan},
        "correlation": corr,
        "identified": {"Fs": False, "KT": True, "chi": True, "beta": False},
        "ranges": {"Fs": (float(Fs_lo), float(Fs0)), "beta": (0.0, float(beta_hi))},
        "res": micro["res"],
        "r": r,
        "warnings": warns,
        "at_bound": at_bound,
        "dF0": (dF0, float(se3[3]) if off else math.nan),
        "tau": tau,
    }
