"""Identification of the four Iwan parameters ``(Fs, KT, chi, beta)`` from test data.

Two fitters return one result type, :class:`FitResult`:

* :func:`fit_dissipation` works on a table of per-cycle amplitudes (the paper's Fig. 7 data).
  ``method="seed"`` reproduces the seed paper's procedure (sec. 2): for a trial ``KT``,
  Nelder-Mead (the equivalent of Matlab's ``fminsearch``) finds ``chi(KT), beta(KT)`` that
  match the dissipation of eq. 17 at the force amplitudes through eq. 20, and a Newton
  iteration moves ``KT`` until the secant stiffness of eq. 24 matches the measured ``F0/u0``.
  ``Fs`` is given, as in the paper. ``method="least_squares"`` fits all four parameters to the
  exact closed forms of ``F0(u0)`` and ``D(u0)`` (micro- and macroslip) in log space.
* :func:`fit_loops` fits the measured force history itself: the exact :class:`IwanJoint`
  is driven by the measured displacement and the force residuals are minimised by bounded
  least squares, with several starts drawn from an explicit seed.

How the loop fit is made fast
    For a displacement-driven record the reversal points, and so the Masing branch each
    sample lies on, do not depend on the parameters; they are found once and each evaluation
    is a few numpy operations (:mod:`iwan_element.core._history`, verified against
    ``IwanJoint.force_history`` to round-off). The fitted samples are decimated to
    ``max_samples`` but the reversal points of the full record are kept. At fixed
    ``(phi_max, chi, beta)`` the force is linear in ``Fs`` (the backbone is ``Fs f(u/phi_max)``,
    paper eq. 12), so ``Fs`` is eliminated in closed form (variable projection) and the
    optimiser searches only ``(ln phi_max, chi, ln(1 + beta))``; the dissipation fit eliminates
    ``ln Fs`` the same way.

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
    the transformed parameters ``(ln Fs, ln KT, chi, ln(1 + beta))`` (central differences at the
    optimum), ``cov = s^2 (J^T J)^-1`` with ``s^2 = SSR/(m - p)``, mapped back to
    ``(Fs, KT, chi, beta)`` with the delta method (the map is diagonal, so correlations are the
    same in both sets). They assume independent residuals; the residuals of a loop fit are
    correlated in time when the model is imperfect, so treat them as lower bounds.
"""
from __future__ import annotations

import logging
import math
import time
import warnings
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy import optimize
from scipy.special import fdtrc

from ..core._history import History, unit_params
from ..core.closed_form import backbone, dissipation, force_amplitude
from ..core.parameters import IwanParameters
from ..core._validation import _check_int, _check_time, check_scalar, finite_array, same_length
from .testdata import _noise_sigma, split_cycles

__all__ = ["FitResult", "IdentifiabilityWarning", "fit_dissipation", "fit_loops", "PARAM_NAMES"]

log = logging.getLogger(__name__)

#: Order of the parameters in ``FitResult.correlation``.
PARAM_NAMES = ("Fs", "KT", "chi", "beta")
_UNITS = {"Fs": "N", "KT": "N/m", "chi": "1", "beta": "1"}
_CHI_BOUNDS = (-0.98, 1.0)            # search range of chi (physical joints: -1 < chi <= 0)
_BETA_MAX = 100.0
_PHI_RANGE = (1e-3, 1e4)              # search range of phi_max / x_max
_SEED_PLATEAU = 0.01                  # seed method: cycles with F0 >= (1 - this) Fs are macroslip


class IdentifiabilityWarning(UserWarning):
    """A parameter is not, or only poorly, determined by the data (see ``FitResult.warnings``)."""


# ================================================================== result
def _json(x):
    """Recursively convert to JSON-safe Python types (NaN and inf become None)."""
    if isinstance(x, dict):
        return {str(k): _json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_json(v) for v in (x.tolist() if isinstance(x, np.ndarray) else x)]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if x is None or isinstance(x, str):
        return x
    return str(x)


@dataclass(frozen=True, eq=False)
class FitResult:
    """Identified Iwan parameters with uncertainties and diagnostics.

    Attributes
    ----------
    params : IwanParameters
        The fitted joint. When ``Fs`` and ``beta`` are not identified (no macroslip in the
        data) this is the ``beta = 0`` member of the family that fits the data equally well;
        ``identified`` and ``ranges`` say so.
    stderr : dict
        Standard error of each parameter (``Fs`` [N], ``KT`` [N/m], ``chi``, ``beta``); NaN
        where the parameter is not identified or was given.
    correlation : ndarray, shape (4, 4)
        Correlation matrix in the order of :data:`PARAM_NAMES`; NaN rows/columns for
        parameters without a standard error.
    identified : dict
        ``True`` for each parameter the data determine.
    fixed : tuple of str
        Parameters that were given, not fitted (``("Fs",)`` for ``method="seed"``).
    ranges : dict
        For parameters that are not identified: ``(low, high)`` range that fits the data
        equally well.
    residual_norm : float
        Euclidean norm of the residual vector that was minimised (loop fit: force residuals
        [N], divided by ``sigma`` if given; dissipation fits: log residuals [-]).
    nrmse : float
        Normalised RMS error [-]: for loop fits the RMS force error over the force range
        ``max F - min F``; for dissipation fits the RMS relative error of the fitted quantities.
    success : bool
        The optimiser converged and the covariance could be computed.
    message : str
        Optimiser message.
    nfev : int
        Model evaluations (all starts, the Jacobian and the identifiability check included).
    method : str
        ``"loops"``, ``"seed"`` or ``"least_squares"``.
    n_data : int
        Number of residuals fitted.
    warnings : tuple of str
        Everything a user should know before trusting the numbers.
    wall_time : float
        Time taken [s].
    details : dict
        JSON-safe extras (largest backbone argument, macroslip test statistics, starts, ...).
    """

    params: IwanParameters
    stderr: dict
    correlation: np.ndarray
    identified: dict
    fixed: tuple
    ranges: dict
    residual_norm: float
    nrmse: float
    success: bool
    message: str
    nfev: int
    method: str
    n_data: int
    warnings: tuple
    wall_time: float
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN and inf become ``None``). ``IwanParameters.from_dict(d["params"])``
        rebuilds the parameters."""
        return _json({
            "method": self.method,
            "params": self.params.to_dict(),
            "stderr": dict(self.stderr),
            "correlation": {"order": list(PARAM_NAMES), "matrix": self.correlation},
            "identified": dict(self.identified),
            "fixed": list(self.fixed),
            "ranges": {k: list(v) for k, v in self.ranges.items()},
            "residual_norm": self.residual_norm,
            "nrmse": self.nrmse,
            "success": self.success,
            "message": self.message,
            "nfev": self.nfev,
            "n_data": self.n_data,
            "warnings": list(self.warnings),
            "wall_time": self.wall_time,
            "details": self.details,
        })

    def report(self) -> str:
        """Human-readable summary: parameters with standard errors, correlations, fit quality
        and warnings."""
        p = self.params
        title = {"loops": "loop fit (exact IwanJoint on the measured displacement)",
                 "seed": "dissipation fit, seed-paper procedure (Nelder-Mead + Newton on KT)",
                 "least_squares": "dissipation fit, least squares on the exact F0(u0), D(u0)"}
        lines = [f"Iwan joint identification: {title.get(self.method, self.method)}",
                 f"  {self.n_data} residuals, {self.nfev} model evaluations, {self.wall_time:.2f} s, "
                 f"{'converged' if self.success else 'NOT converged'}: {self.message}",
                 "",
                 "  parameter        value        std. error   status"]
        fmt = {"Fs": ("Fs   [N]  ", "{:.6g}"), "KT": ("KT   [N/m]", "{:.6g}"),
               "chi": ("chi  [-]  ", "{:.4f}"), "beta": ("beta [-]  ", "{:.4f}")}
        for k in PARAM_NAMES:
            label, f = fmt[k]
            v = getattr(p, k)
            se = self.stderr.get(k, math.nan)
            if k in self.fixed:
                status, se_txt = "given (not fitted)", ""
            elif not self.identified.get(k, False):
                lo, hi = self.ranges.get(k, (math.nan, math.nan))
                status = (f"NOT identified (data fit equally for {f.format(lo)} .. {f.format(hi)})"
                          if k in self.ranges else "NOT identified")
                se_txt = "" if not math.isfinite(se) else f"({f.format(se)})"
            else:
                rel = f"{100 * se / abs(v):.2g} %" if v != 0 and k in ("Fs", "KT") else ""
                se_txt = f.format(se) if math.isfinite(se) else "n/a"
                status = f"identified {rel}".rstrip()
            lines.append(f"  {label}  {f.format(v):>12}  {se_txt:>12}   {status}")
        lines.append(f"  derived: phi_max = {p.phi_max * 1e3:.5g} mm, R = {p.R:.5g}, "
                     f"S = {p.S:.5g} N/m")
        have = [k for k in PARAM_NAMES if math.isfinite(self.stderr.get(k, math.nan))]
        if len(have) > 1:
            lines += ["", "  correlation     " + "".join(f"{k:>8}" for k in have)]
            for i, k in enumerate(PARAM_NAMES):
                if k in have:
                    row = "".join(f"{self.correlation[i, PARAM_NAMES.index(j)]:8.3f}" for j in have)
                    lines.append(f"  {k:<15} {row}")
        unit = "[-]" if self.method != "loops" else "[N]" if not self.details.get("weighted") else "[-]"
        lines += ["", f"  residual norm {self.residual_norm:.4g} {unit}, NRMSE {100 * self.nrmse:.3g} %"]
        if self.warnings:
            lines += ["", "  warnings:"] + [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


# ================================================================== shared machinery
class _Problem:
    """Data ``y`` modelled as ``Fs * g(phi_max, chi, beta)``.

    ``log=False``: residuals ``w (y - Fs g)``; ``log=True``: ``w (ln y - ln Fs - ln g)``.
    ``entry_x`` is the largest backbone argument [m] behind each residual: the residual is in
    macroslip when it exceeds ``phi_max``.
    """

    def __init__(self, y, unit: Callable, *, w, log_space: bool, entry_x, min_macro: int):
        self.y = y
        self.ly = np.log(y) if log_space else None
        self.unit = unit
        self.w = w
        self.w2 = w * w
        self.log = log_space
        self.entry_x = entry_x
        self.x_max = float(entry_x.max())
        self.min_macro = min_macro
        self.nfev = 0

    def g(self, phi_max, chi, beta):
        self.nfev += 1
        return self.unit(unit_params(phi_max, chi, beta))

    def projected(self, phi_max, chi, beta):
        """Best ``Fs`` for the shape ``(phi_max, chi, beta)`` and the residuals."""
        g = self.g(phi_max, chi, beta)
        if self.log:
            lg = np.log(g)
            lnFs = np.sum(self.w2 * (self.ly - lg)) / np.sum(self.w2)
            return math.exp(lnFs), self.w * (self.ly - lnFs - lg)
        den = np.sum(self.w2 * g * g)
        Fs = np.sum(self.w2 * g * self.y) / den if den > 0 else 1.0
        Fs = Fs if Fs > 0 else 1e-300
        return Fs, self.w * (self.y - Fs * g)

    def residual(self, params: IwanParameters):
        """Residuals of a full parameter set (no projection)."""
        self.nfev += 1
        model = self.unit(params)
        if self.log:
            return self.w * (self.ly - np.log(model))
        return self.w * (self.y - model)

    def n_macro(self, phi_max):
        return int(np.count_nonzero(self.entry_x > phi_max))


def _q_to_shape(q, x_max, beta_fixed):
    phi = x_max * math.exp(q[0])
    beta = beta_fixed if beta_fixed is not None else math.expm1(q[2])
    return phi, float(q[1]), beta


@dataclass
class _LsqResult:
    x: np.ndarray
    cost: float
    status: int              # > 0 converged, 0 evaluation budget used up
    message: str
    nfev: int


def _lsq_box(fun, x0, lower, upper, *, max_nfev: int, ftol: float = 1e-12,
             xtol: float = 1e-10) -> _LsqResult:
    """Levenberg-Marquardt with box bounds (projected steps) for a few parameters.

    Minimises ``0.5 |fun(x)|^2`` for ``lower <= x <= upper``. The Jacobian is taken by
    forward differences; the normal equations are formed with ``einsum``. Why not
    ``scipy.optimize.least_squares``: for a tall Jacobian (thousands of residuals, three
    parameters) its trust-region steps spend their time in multithreaded OpenBLAS
    matrix-vector products, which ran 7-10 times slower than single-threaded on a busy
    2-core machine; this loop needs no BLAS. ``tests/test_fit.py`` checks that it reaches the
    same minimum as ``least_squares(method="trf")``.
    """
    x = np.clip(np.asarray(x0, float), lower, upper)
    r = fun(x)
    nfev = 1
    cost = 0.5 * float(np.einsum("i,i->", r, r))
    lam = 1e-3
    p = x.size
    while nfev + p < max_nfev:
        J = np.empty((r.size, p))
        for j in range(p):
            h = 1e-7 * max(1.0, abs(x[j]))
            if x[j] + h > upper[j]:
                h = -h                                   # step inwards at an upper bound
            xh = x.copy()
            xh[j] += h
            J[:, j] = (fun(xh) - r) / h
        nfev += p
        g = np.einsum("ij,i->j", J, r)
        A = np.einsum("ij,ik->jk", J, J)
        free = ~(((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0)))
        if not free.any() or np.max(np.abs(g[free])) <= 1e-14 * max(cost, 1e-300):
            return _LsqResult(x, cost, 1, "projected gradient is zero", nfev)
        Af = A[np.ix_(free, free)]
        while nfev < max_nfev:
            M = Af + lam * np.diag(np.diag(Af) + 1e-30)
            try:
                d = np.zeros(p)
                d[free] = np.linalg.solve(M, -g[free])
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            x_new = np.clip(x + d, lower, upper)
            r_new = fun(x_new)
            nfev += 1
            cost_new = 0.5 * float(np.einsum("i,i->", r_new, r_new))
            if cost_new < cost:
                step = x_new - x
                predicted = -(g @ step + 0.5 * step @ A @ step)
                small_f = cost - cost_new <= ftol * cost and predicted <= ftol * cost
                # a short step means convergence only when damping did not shorten it
                small_x = lam < 1e-2 and np.all(np.abs(step) <= xtol * (xtol + np.abs(x)))
                x, r, cost = x_new, r_new, cost_new
                lam = max(lam / 3.0, 1e-12)
                if small_f or small_x:
                    return _LsqResult(x, cost, 2, "relative reduction of the cost below "
                                      f"{ftol:g}" if small_f else f"step below xtol = {xtol:g}",
                                      nfev)
                break
            lam *= 4.0
            if lam > 1e16:
                return _LsqResult(x, cost, 3, "no step reduces the cost further (at a minimum "
                                  "to round-off)", nfev)
    return _LsqResult(x, cost, 0, f"evaluation budget max_nfev = {max_nfev} used up", nfev)


def _multistart(prob: _Problem, starts, lower, upper, *, beta_fixed, max_nfev):
    """Least squares on ``q = (ln(phi_max/x_max), chi[, ln(1+beta)])`` from each start; best wins."""
    best = None

    def fun(q):
        return prob.projected(*_q_to_shape(q, prob.x_max, beta_fixed))[1]

    for q0 in starts:
        res = _lsq_box(fun, np.asarray(q0, float), lower, upper, max_nfev=max_nfev)
        log.debug("start %s -> cost %.6g (%s)", np.round(q0, 3), res.cost, res.message)
        if best is None or res.cost < best.cost:
            best = res
    return best


def _fd_jacobian(fun, theta, steps):
    """Central-difference Jacobian of ``fun`` at ``theta``."""
    cols = []
    for j, h in enumerate(steps):
        tp = theta.copy()
        tm = theta.copy()
        tp[j] += h
        tm[j] -= h
        cols.append((fun(tp) - fun(tm)) / (2.0 * h))
    return np.column_stack(cols)


def _uncertainty(fun, theta, r, scale, *, at_lower_bound=None):
    """Standard errors and correlations from the Jacobian (see the module docstring).

    ``fun`` maps the transformed parameters ``theta`` to residuals, ``r`` are the residuals at
    the optimum and ``scale = |d p / d theta|`` is the (diagonal) delta-method factor. A
    parameter whose index is ``at_lower_bound`` is evaluated one step inside its bound 0.
    Returns ``(stderr of p, correlation)``.
    """
    h = 1e-5
    th = np.array(theta, float)
    if at_lower_bound is not None:
        th[at_lower_bound] = max(th[at_lower_bound], h)
    J = _fd_jacobian(fun, th, np.full(th.size, h))
    s2 = float(r @ r) / max(r.size - th.size, 1)
    try:
        cov = s2 * np.linalg.pinv(J.T @ J, rcond=1e-12, hermitian=True)
    except np.linalg.LinAlgError:
        cov = np.full((th.size, th.size), np.nan)
    se_t = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se_t, se_t)
    return se_t * np.asarray(scale, float), corr


def _range_warnings(params: IwanParameters) -> list[str]:
    out = []
    if params.chi > 0:
        out.append(f"chi = {params.chi:.3g} > 0 is outside the physical range -1 < chi <= 0")
    if any(abs(params.chi - b) < 1e-6 for b in _CHI_BOUNDS):
        out.append(f"chi reached the end of its search range {_CHI_BOUNDS}")
    return out


def _poorly_determined(params: IwanParameters, stderr: dict, names) -> list[str]:
    """Warnings for the named parameters whose standard error is missing or large."""
    out = []
    for name in names:
        value, se = getattr(params, name), stderr[name]
        limit = {"Fs": 0.1 * abs(value), "KT": 0.1 * abs(value), "chi": 0.05,
                 "beta": 0.25 * max(abs(value), 0.2)}[name]
        if not math.isfinite(se):
            out.append(f"{name}: no standard error (singular Jacobian)")
        elif se > limit:
            out.append(f"{name} is poorly determined by the data (std. error {se:.3g})")
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
    if ssr_f > 0 and m > 4:
        F_stat = max(ssr_m - ssr_f, 0.0) / (ssr_f / (m - 4))
        p_value = float(fdtrc(1, m - 4, F_stat))          # F-distribution survival
    else:
        F_stat, p_value = (math.inf, 0.0) if ssr_m > ssr_f else (0.0, 1.0)
    macro = (phi_f < xm and n_macro >= prob.min_macro and p_value < alpha)
    details = {"x_max": xm, "ssr_microslip": ssr_m, "ssr_full": ssr_f, "F_statistic": F_stat,
               "p_value": p_value, "alpha": alpha, "macroslip_residuals": n_macro,
               "macroslip_reached": bool(macro), "starts": len(starts)}
    warns: list[str] = []
    if macro:
        Fs, chi, beta = Fs_f, chi_f, beta_f
        KT = Fs * unit_params(phi_f, chi, beta).KT
        params = IwanParameters(Fs, KT, chi, beta)
        res, r = res_f, r_f
        theta = np.array([math.log(Fs), math.log(KT), chi, math.log1p(beta)])

        def fun(th):
            return prob.residual(IwanParameters(math.exp(th[0]), math.exp(th[1]), th[2],
                                                math.expm1(th[3])))

        se, corr = _uncertainty(fun, theta, r, [Fs, KT, 1.0, 1.0 + beta], at_lower_bound=3)
        stderr = dict(zip(PARAM_NAMES, se.tolist()))
        identified = dict.fromkeys(PARAM_NAMES, True)
        ranges = {}
        warns += _poorly_determined(params, stderr, PARAM_NAMES)
        if beta_f <= 1e-9:
            warns.append("beta is at its lower bound 0; its standard error is one-sided")
        details["macroslip_fraction"] = n_macro / m
    else:
        Fs0, phi0, chi = Fs_m, phi_m, chi_m
        KT = Fs0 * unit_params(phi0, chi, 0.0).KT
        params = IwanParameters(Fs0, KT, chi, 0.0)
        R = params.R
        res, r = res_m, r_m
        theta = np.array([math.log(KT), chi, math.log(R)])

        def fun(th):
            # the beta = 0 member for (KT, chi, R): R phi^(chi+1) = (chi+1) KT, eq. 10
            KT_, chi_, R_ = math.exp(th[0]), th[1], math.exp(th[2])
            phi_ = ((chi_ + 1.0) * KT_ / R_) ** (1.0 / (chi_ + 1.0))
            return prob.residual(IwanParameters(KT_ * phi_ * (chi_ + 1.0) / (chi_ + 2.0), KT_,
                                                chi_, 0.0))

        se3, c3 = _uncertainty(fun, theta, r, [KT, 1.0, R])
        stderr = {"Fs": math.nan, "KT": se3[0], "chi": se3[1], "beta": math.nan}
        corr = np.full((4, 4), np.nan)
        corr[1:3, 1:3] = c3[:2, :2]
        identified = {"Fs": False, "KT": True, "chi": True, "beta": False}
        # family members that fit equally: phi_max in [x_max, phi0], beta = (phi0/phi)^(chi+1) - 1
        beta_hi = (phi0 / xm) ** (chi + 1.0) - 1.0
        Fs_lo = backbone(xm, params)             # phi_max = x_max: Fs is the force reached
        ranges = {"Fs": (float(Fs_lo), float(Fs0)), "beta": (0.0, float(beta_hi))}
        details.update({"R": R, "stderr_R": se3[2], "corr_KT_chi_R": c3})
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
        warns += _poorly_determined(params, stderr, ("KT", "chi"))
        if phi0 <= xm * (1 + 1e-9):
            warns.append("the microslip fit sits at its bound phi_max = x_max: the backbone's "
                         "tangent vanishes at the largest excursion; more data near macroslip "
                         "would settle Fs")
    warns += _range_warnings(params)
    return {"params": params, "stderr": stderr, "correlation": corr, "identified": identified,
            "ranges": ranges, "res": res, "r": r, "warnings": warns, "details": details}


def _finish(method, out, *, converged, message, nfev, nrmse, t0, extra_warnings=(),
            fixed=(), stacklevel=3) -> FitResult:
    """Build the FitResult from the dict of :func:`_identify` (or its seed-method twin) and
    issue one IdentifiabilityWarning carrying every warning."""
    warns = list(extra_warnings) + out["warnings"]
    se_ok = all(math.isfinite(out["stderr"][k]) for k in PARAM_NAMES
                if out["identified"][k] and k not in fixed)
    if not converged:
        warns.append(f"the optimiser did not converge: {message}")
    result = FitResult(params=out["params"], stderr=out["stderr"], correlation=out["correlation"],
                       identified=out["identified"], fixed=tuple(fixed), ranges=out["ranges"],
                       residual_norm=float(np.sqrt(out["r"] @ out["r"])), nrmse=float(nrmse),
                       success=bool(converged and se_ok), message=str(message), nfev=int(nfev),
                       method=method, n_data=int(out["r"].size), warnings=tuple(warns),
                       wall_time=time.perf_counter() - t0, details=_json(out["details"]))
    if warns and _EMIT.get():
        warnings.warn("Iwan identification: " + " | ".join(warns), IdentifiabilityWarning,
                      stacklevel=stacklevel)
    return result


# Whether fits issue their IdentifiabilityWarning (the warnings stay in FitResult.warnings).
# Library callers that report the warnings themselves switch it off for their own context
# only, instead of changing the process-wide warning filters.
_EMIT: ContextVar[bool] = ContextVar("iwan_fit_emit_warnings", default=True)


@contextmanager
def _quiet():
    """Within this context (thread / task), fits do not call ``warnings.warn``."""
    token = _EMIT.set(False)
    try:
        yield
    finally:
        _EMIT.reset(token)


# ================================================================== loop fit
def fit_loops(u, F, *, t=None, sigma=None, smooth: int = 0, max_samples: int | None = 20000,
              n_starts: int = 6, seed=0, alpha: float = 1e-3, hysteresis: float | None = None,
              initial: IwanParameters | None = None, max_nfev: int = 300) -> FitResult:
    """Fit all four Iwan parameters to a measured force history (paper Fig. 8).

    The exact :class:`IwanJoint` is driven by the measured displacement from the virgin,
    unloaded state, and the squared force residuals are minimised by bounded least squares
    (a box-bounded Levenberg-Marquardt, checked against ``scipy.optimize.least_squares``) in
    the transformed parameters ``(ln phi_max, chi, ln(1 + beta))`` with ``Fs`` eliminated in
    closed form, from ``n_starts`` starts. See the module docstring for identifiability and
    uncertainties.

    Parameters
    ----------
    u : array_like, shape (n,)
        Measured joint displacement [m], starting at rest. Not modified.
    F : array_like, shape (n,)
        Measured joint force [N]. Not modified.
    t : array_like, shape (n,), optional, keyword-only
        Time [s]; checked to be strictly increasing (the model is rate independent).
    sigma : float or array_like of shape (n,), optional, keyword-only
        Force noise standard deviation [N] (weights ``1/sigma``); default uniform.
    smooth : int, keyword-only
        Savitzky-Golay window (odd number of samples ``>= 5``, quadratic) applied to the
        displacement that drives the model; 0 (default) uses the measured displacement as is.
        Displacement noise is an error in the model's input: its jitter creates spurious
        reversals and biases ``KT`` low and ``chi`` high. Choose a window well below a
        quarter period (for instance 1-3 % of a cycle's samples).
    max_samples : int or None, keyword-only
        Most samples whose residuals are fitted (evenly spaced; the reversal points of the
        whole record are always used), ``>= 100``; ``None`` fits every sample. Default 20000.
    n_starts : int, keyword-only
        Starts of the four-parameter fit, ``>= 1``: four deterministic ones from the
        microslip fit, the rest drawn from ``seed``. Default 6.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the random starts (default 0: reproducible).
    alpha : float, keyword-only
        Significance level of the test that the data reach macroslip, in ``(0, 0.5)``.
    hysteresis : float, optional, keyword-only
        Dead band [m] to count cycles (see :func:`iwan_element.identify.testdata.find_reversals`).
    initial : IwanParameters, optional, keyword-only
        An extra start (for instance a previous fit).
    max_nfev : int, keyword-only
        Evaluations per start, ``>= 10``.

    Returns
    -------
    FitResult
        ``method="loops"``.

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, non-increasing ``t``, an all-zero force, a constant
        displacement, a force of the opposite sign convention, fewer than two cycles, or an
        option out of range.

    Warns
    -----
    IdentifiabilityWarning
        When a parameter is not or poorly identified; the same text is in ``result.warnings``.
    """
    t0 = time.perf_counter()
    uu = finite_array("u", u, ndim=1, min_size=10)
    FF = finite_array("F", F, ndim=1, min_size=10)
    n = same_length(u=uu, F=FF)
    if t is not None:
        _check_time(t, n)
    if not np.any(FF != 0.0):
        raise ValueError("F is all zero: there is no force to fit")
    if np.ptp(uu) == 0.0:
        raise ValueError("u is constant: the displacement must vary")
    if np.dot(uu - uu.mean(), FF - FF.mean()) <= 0.0:
        raise ValueError("F does not increase with u (they are anti-correlated): the joint force "
                         "must have the sign of the displacement; flip the sign of one of them")
    if sigma is None:
        w_full = np.ones(n)
    elif np.ndim(sigma) == 0:
        w_full = np.full(n, 1.0 / check_scalar("sigma", sigma, low=0.0, low_open=True))
    else:
        s = finite_array("sigma", sigma, ndim=1)
        if s.size != n or np.any(s <= 0):
            raise ValueError(f"sigma must be a positive scalar or have {n} positive entries")
        w_full = 1.0 / s
    max_samples = n if max_samples is None else _check_int("max_samples", max_samples, 100)
    smooth = _check_int("smooth", smooth, 0)
    if smooth and (smooth < 5 or smooth % 2 == 0 or smooth >= n):
        raise ValueError(f"smooth must be 0 or an odd window of at least 5 samples below the "
                         f"record length {n}, got {smooth}")
    n_starts = _check_int("n_starts", n_starts, 1)
    max_nfev = _check_int("max_nfev", max_nfev, 10)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    if initial is not None and not isinstance(initial, IwanParameters):
        raise ValueError(f"initial must be an IwanParameters or None, got {type(initial).__name__}")
    rng = np.random.default_rng(seed)
    cycles = split_cycles(uu, FF, hysteresis=hysteresis)
    if len(cycles) < 2:
        raise ValueError(f"u contains {len(cycles)} complete cycle(s); at least 2 are needed")
    warns = []
    if abs(uu[0]) > 0.05 * np.abs(uu).max() or abs(FF[0]) > 0.05 * np.abs(FF).max():
        warns.append("the record does not start at rest (u[0], F[0] not near 0); the model "
                     "starts from the virgin state at u = 0")
    bad = [c.index for c in cycles if not c.closed or c.drifting]
    if len(bad) > len(cycles) // 2:
        warns.append(f"{len(bad)} of {len(cycles)} cycles do not close or drift (cycles {bad[:8]}): "
                     "a rate-independent joint model cannot follow drift")
    sigma_u = _noise_sigma(uu)
    amp_min = min(c.u0 for c in cycles)
    if smooth:
        from scipy.signal import savgol_filter   # imported here: scipy.signal loads in 0.3 s
        u_drive = savgol_filter(uu, smooth, 2)
    else:
        u_drive = uu
        if sigma_u > 1e-3 * amp_min:
            warns.append(f"displacement noise ({sigma_u:.2g} m, {100 * sigma_u / amp_min:.2g} % of "
                         "the smallest amplitude) drives the model and biases KT low and chi "
                         "high; consider smooth= (a Savitzky-Golay window)")
    keep = np.unique(np.round(np.linspace(0, n - 1, min(n, max_samples))).astype(np.intp))
    hist = History(u_drive, keep=keep, tol=1e-12 * float(np.abs(u_drive).max()))
    y = FF[keep]
    prob = _Problem(y, hist.forces, w=w_full[keep], log_space=False, entry_x=hist.x[hist.out],
                    min_macro=max(10, int(0.005 * keep.size)))
    out = _identify(prob, n_starts=n_starts, rng=rng, alpha=alpha, max_nfev=max_nfev,
                    initial=initial)
    F_fit = hist.forces(out["params"])
    nrmse = math.sqrt(np.mean((y - F_fit) ** 2)) / float(np.ptp(y))
    out["details"].update({"samples": n, "fitted_samples": int(keep.size),
                           "model_samples": int(hist.index.size), "reversal_depth": hist.depth,
                           "cycles": len(cycles), "weighted": sigma is not None,
                           "smooth": smooth, "displacement_noise": sigma_u})
    return _finish("loops", out, converged=out["res"].status > 0, message=out["res"].message,
                   nfev=prob.nfev, nrmse=nrmse, t0=t0, extra_warnings=warns)


# ================================================================== dissipation fits
def _seed_gamma(F0n, chi, beta):
    """Solve paper eq. 20, ``F0/Fs = g (beta + 1 - g**(chi+1)/(chi+2)) / c``, for ``g = u0/phi_max``
    in ``(0, 1]`` (safeguarded Newton; the right side increases monotonically to 1 at g = 1)."""
    c = beta + (chi + 1.0) / (chi + 2.0)
    lo = np.zeros_like(F0n)
    hi = np.ones_like(F0n)
    g = np.clip(F0n * c / (beta + 1.0), 1e-300, 1.0)
    for _ in range(100):
        q = g ** (chi + 1.0)
        f = g * (beta + 1.0 - q / (chi + 2.0)) / c - F0n
        lo = np.where(f < 0, g, lo)
        hi = np.where(f >= 0, g, hi)
        d = (beta + 1.0 - q) / c
        with np.errstate(divide="ignore", invalid="ignore"):
            g_new = g - f / d
        bis = ~((g_new >= lo) & (g_new <= hi))            # also catches NaN
        g_new = np.where(bis, 0.5 * (lo + hi), g_new)
        if np.all(np.abs(g_new - g) <= 1e-14 * g):
            return g_new
        g = g_new
    return g


def _seed_model(F0, u0, Fs, KT, chi, beta):
    """Paper eqs. 20, 17 and 24: ``gamma`` from ``F0``, then ``D`` and the secant stiffness."""
    c = beta + (chi + 1.0) / (chi + 2.0)
    g = _seed_gamma(F0 / Fs, chi, beta)
    D = (4.0 * g ** (chi + 3.0) * Fs ** 2 * (beta + 1.0) * (chi + 1.0)
         / (KT * c ** 2 * (chi + 3.0) * (chi + 2.0)))                          # eq. 17
    K = KT * (1.0 - g ** (chi + 1.0) / ((chi + 2.0) * (beta + 1.0)))            # eq. 24
    return D, K


def _seed_solve(F0, D, u0, Fs, counter, *, max_newton=50):
    """Seed paper sec. 2 for one set of cycles: ``KT`` by Newton, ``chi(KT), beta(KT)`` by
    Nelder-Mead. Returns ``(KT, chi, beta, converged, message, iterations)``."""
    lnD = np.log(D)
    lnK = np.log(F0 / u0)

    def decode(z):
        return -1.0 + math.exp(z[0]), z[1] * z[1]          # chi > -1, beta >= 0, unconstrained z

    def inner(KT, z0):
        """fminsearch for chi(KT), beta(KT): least squares of ln D (eqs. 17, 20)."""
        def obj(z):
            chi, beta = decode(z)
            if not -1.0 < chi < 50.0:
                return 1e30
            counter[0] += 1
            Dm, _ = _seed_model(F0, u0, Fs, KT, chi, beta)
            return float(np.sum((np.log(Dm) - lnD) ** 2))
        res = optimize.minimize(obj, z0, method="Nelder-Mead",
                                options={"xatol": 1e-9, "fatol": 1e-15, "maxiter": 2000})
        return res.x

    def h(lnKT, z0):
        """Mean log mismatch of the secant stiffness (eq. 24) with chi, beta re-fitted."""
        KT = math.exp(lnKT)
        z = inner(KT, z0)
        _, Km = _seed_model(F0, u0, Fs, KT, *decode(z))
        return float(np.mean(np.log(Km) - lnK)), z

    lnKT = math.log(1.2 * float(np.max(F0 / u0)))       # K_sec < KT always (eq. 24)
    z = np.array([math.log(0.5), math.sqrt(0.5)])       # chi = -0.5, beta = 0.5
    dh = 1e-4
    for it in range(1, max_newton + 1):
        hv, z = h(lnKT, z)
        slope = (h(lnKT + dh, z)[0] - hv) / dh
        step = -hv / slope if slope != 0 and math.isfinite(slope) else -0.1 * math.copysign(1, hv)
        step = float(np.clip(step, -0.5, 0.5))
        lnKT += step
        if abs(step) < 1e-9:
            hv, z = h(lnKT, z)
            return (math.exp(lnKT), *decode(z), True,
                    f"Newton on KT converged in {it} iterations (|h| = {abs(hv):.1e})", it)
    return (math.exp(lnKT), *decode(z), False,
            f"Newton on KT did not converge in {max_newton} iterations", max_newton)


def _fit_seed(F0, D, u0, Fs, *, t0):
    """The seed paper's identification (sec. 2) with a microslip guard: cycles with
    ``F0 >= 0.99 Fs`` (at or near the macroslip plateau) are left out, and cycles whose
    measured ``u0`` exceeds the fitted ``phi_max`` are dropped and the fit repeated (up to three
    times): eqs. 17 and 20 hold only in microslip."""
    counter = [0]
    warns = []
    keep = F0 < (1.0 - _SEED_PLATEAU) * Fs
    if not keep.all():
        warns.append(f"{int((~keep).sum())} cycle(s) with F0 >= {1 - _SEED_PLATEAU:g} Fs were left "
                     "out: eqs. 17 and 20 of the seed method hold only in microslip")
    for round_ in range(4):
        if keep.sum() < 2:
            raise ValueError(f"method='seed' needs at least 2 microslip cycles (F0 < 0.99 Fs = "
                             f"{0.99 * Fs:g} N, u0 < phi_max), got {int(keep.sum())}")
        KT, chi, beta, converged, msg, it = _seed_solve(F0[keep], D[keep], u0[keep], Fs, counter)
        phi = IwanParameters(Fs, KT, chi, beta).phi_max
        macro = keep & (u0 > phi)
        if not macro.any():
            break
        if round_ == 3:
            warns.append(f"{int(macro.sum())} cycle(s) still have u0 > phi_max = {phi * 1e3:.4g} mm")
            break
        warns.append(f"{int(macro.sum())} cycle(s) with u0 > phi_max = {phi * 1e3:.4g} mm "
                     "(macroslip) were left out and the fit repeated")
        keep = keep & ~macro
    F0, D, u0 = F0[keep], D[keep], u0[keep]
    params = IwanParameters(Fs, KT, chi, beta)
    n = F0.size
    lnD = np.log(D)
    lnK = np.log(F0 / u0)

    def resid(th):
        counter[0] += 1
        Dm, Km = _seed_model(F0, u0, Fs, math.exp(th[0]), th[1], math.expm1(th[2]))
        with np.errstate(invalid="ignore", divide="ignore"):   # NaN marks an invalid step
            return np.concatenate([np.log(Dm) - lnD, np.log(Km) - lnK])

    theta = np.array([math.log(KT), chi, math.log1p(beta)])
    r = resid(theta)
    se, c3 = _uncertainty(resid, theta, r, [KT, 1.0, 1.0 + beta], at_lower_bound=2)
    stderr = {"Fs": math.nan, "KT": float(se[0]), "chi": float(se[1]), "beta": float(se[2])}
    corr = np.full((4, 4), np.nan)
    corr[1:, 1:] = c3
    warns.append(f"beta = {beta:.4g} follows from the given Fs = {Fs:.6g} N: microslip data "
                 f"determine only KT, chi and R = {params.R:.5g}; a different Fs gives a "
                 "different beta with the same fit")
    warns += _poorly_determined(params, stderr, ("KT", "chi"))
    warns += _range_warnings(params)
    Dm, Km = _seed_model(F0, u0, Fs, KT, chi, beta)
    nrmse = math.sqrt(np.mean(np.concatenate([Dm / D - 1.0, Km / (F0 / u0) - 1.0]) ** 2))
    if beta < 1e-6:
        warns.append(f"beta is at its bound 0: if the given Fs exceeds the largest slip force "
                     f"compatible with the data (the beta = 0 one), no beta can compensate and KT "
                     f"and chi come out distorted; compare the NRMSE ({100 * nrmse:.3g} %) with "
                     "the noise or use method='least_squares'")
    out = {"params": params, "stderr": stderr, "correlation": corr,
           "identified": {"Fs": False, "KT": True, "chi": True, "beta": False}, "ranges": {},
           "r": r, "warnings": warns,
           "details": {"newton_iterations": it, "cycles_used": n, "x_max": float(u0.max())}}
    return _finish("seed", out, converged=converged, message=msg, nfev=counter[0], nrmse=nrmse,
                   t0=t0, fixed=("Fs",), stacklevel=4)


def fit_dissipation(F0, D, *, u0, method: str = "least_squares", Fs: float | None = None,
                    n_starts: int = 6, seed=0, alpha: float = 1e-3,
                    max_nfev: int = 300) -> FitResult:
    """Fit the Iwan parameters to per-cycle force amplitude and dissipation (paper Fig. 7).

    Parameters
    ----------
    F0 : array_like, shape (m,)
        Force amplitude of each cycle [N], ``> 0``. Not modified.
    D : array_like, shape (m,)
        Energy dissipated per cycle [J], ``> 0``. Not modified.
    u0 : array_like, shape (m,), keyword-only (required)
        Displacement amplitude of each cycle [m], ``> 0``. The seed method needs it for the
        secant stiffness ``F0/u0`` of eq. 24; the least-squares fit for ``F0(u0)``, ``D(u0)``.
    method : {"least_squares", "seed"}, keyword-only
        ``"least_squares"`` (default): bounded least squares of ``ln F0`` and ``ln D``
        against the exact closed forms (micro- and macroslip), multi-start, with the
        identifiability test of the module docstring. ``"seed"``: the paper's procedure,
        valid in microslip only (cycles with ``F0 >= 0.99 Fs`` or with ``u0`` beyond the fitted
        ``phi_max`` are left out).
    Fs : float, keyword-only
        Slip force [N], ``> 0``. Required by (and only used by) ``method="seed"``, which
        takes it as known, as the paper does.
    n_starts, seed, alpha, max_nfev : keyword-only
        As in :func:`fit_loops` (``"least_squares"`` only).

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        NaN/inf, non-positive values, unequal lengths, fewer than 2 cycles, an unknown
        method, or ``Fs`` missing for ``"seed"`` / given for ``"least_squares"``.

    Warns
    -----
    IdentifiabilityWarning
        As for :func:`fit_loops`; ``"seed"`` always warns that ``beta`` is conditional on the
        given ``Fs``.
    """
    t0 = time.perf_counter()
    F0a = finite_array("F0", F0, ndim=1, min_size=2)
    Da = finite_array("D", D, ndim=1, min_size=2)
    ua = finite_array("u0", u0, ndim=1, min_size=2)
    same_length(F0=F0a, D=Da, u0=ua)
    for name, arr in (("F0", F0a), ("D", Da), ("u0", ua)):
        if np.any(arr <= 0):
            raise ValueError(f"{name} must be > 0 for every cycle (got {arr.min():g})")
    if method not in ("least_squares", "seed"):
        raise ValueError(f"method must be 'least_squares' or 'seed', got {method!r}")
    if method == "seed":
        if Fs is None:
            raise ValueError("method='seed' needs Fs [N]: the paper takes the slip force as known "
                             "(eq. 20 is normalised by it)")
        Fs = check_scalar("Fs", Fs, low=0.0, low_open=True)
        return _fit_seed(F0a, Da, ua, Fs, t0=t0)
    if Fs is not None:
        raise ValueError("Fs is only used by method='seed'; least_squares fits it")
    n_starts = _check_int("n_starts", n_starts, 1)
    max_nfev = _check_int("max_nfev", max_nfev, 10)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    rng = np.random.default_rng(seed)

    def unit(p1):
        return np.concatenate([force_amplitude(ua, p1), dissipation(ua, p1)])

    prob = _Problem(np.concatenate([F0a, Da]), unit, w=np.ones(2 * ua.size), log_space=True,
                    entry_x=np.concatenate([ua, ua]), min_macro=4)
    out = _identify(prob, n_starts=n_starts, rng=rng, alpha=alpha, max_nfev=max_nfev,
                    initial=None)
    fit = unit(out["params"])
    nrmse = math.sqrt(np.mean((fit / prob.y - 1.0) ** 2))
    out["details"]["cycles"] = int(ua.size)
    return _finish("least_squares", out, converged=out["res"].status > 0,
                   message=out["res"].message, nfev=prob.nfev, nrmse=nrmse, t0=t0)
