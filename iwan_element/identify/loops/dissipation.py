"""Dissipation fits: the Iwan parameters from per-cycle amplitudes (the paper's Fig. 7 data).

* ``method="seed"`` reproduces the seed paper's procedure (sec. 2): for a trial ``KT``,
  Nelder-Mead (the equivalent of Matlab's ``fminsearch``) finds ``chi(KT), beta(KT)`` that
  match the dissipation of eq. 17 at the force amplitudes through eq. 20, and a Newton
  iteration moves ``KT`` until the secant stiffness of eq. 24 matches the measured ``F0/u0``.
  ``Fs`` is given, as in the paper.
* ``method="least_squares"`` fits all four parameters to the exact closed forms of ``F0(u0)``
  and ``D(u0)`` (micro- and macroslip) in log space, with ``ln Fs`` eliminated in closed form.

What a table can support: each distinct amplitude gives two numbers (``F0`` and ``D``), so
four parameters need at least three distinct amplitudes (two for the seed method, which is
given ``Fs``); fewer are refused. A fit whose relative RMS error exceeds
:data:`NRMSE_LIMIT` does not describe the data and is not successful.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import optimize

from ...base.validation import check_int, check_magnitude, check_scalar, finite_array, same_length
from ...core.closed_form import dissipation as cycle_dissipation
from ...core.closed_form import force_amplitude
from ...core.parameters import IwanParameters
from .identifiability import MIN_MACRO_POINTS, _identify, _range_warnings
from .result import FitResult, _finish
from .solver import _Problem, _uncertainty

__all__ = ["fit_dissipation", "NRMSE_LIMIT"]

_SEED_PLATEAU = 0.01  # seed method: cycles with F0 >= (1 - this) Fs are macroslip
#: Largest relative RMS error [-] of a successful dissipation fit.
NRMSE_LIMIT = 0.25


def _distinct(u0: np.ndarray, rtol: float = 0.02) -> int:
    """Number of distinct amplitudes (sorted values more than ``rtol`` apart)."""
    v = np.sort(u0)
    return 1 + int(np.count_nonzero(np.diff(v) > rtol * v[1:]))


def _misfit_warning(nrmse: float) -> list[str]:
    if nrmse > NRMSE_LIMIT:
        return [
            f"the fit does not describe the data: relative RMS error {100 * nrmse:.3g} % "
            f"> {100 * NRMSE_LIMIT:g} %; the Iwan closed forms do not follow this table "
            "(wrong units, mixed tests, or a joint this model does not cover)"
        ]
    return []


def _seed_gamma(F0n, chi, beta):
    """Solve paper eq. 20, ``F0/Fs = g (beta + 1 - g**(chi+1)/(chi+2)) / c``, for ``g = u0/phi_max``
    in ``(0, 1]`` (safeguarded Newton; the right side increases monotonically to 1 at g = 1).
    """
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
        bis = ~((g_new >= lo) & (g_new <= hi))  # also catches NaN
        g_new = np.where(bis, 0.5 * (lo + hi), g_new)
        if np.all(np.abs(g_new - g) <= 1e-14 * g):
            return g_new
        g = g_new
    return g


def _seed_model(F0, u0, Fs, KT, chi, beta):
    """Paper eqs. 20, 17 and 24: ``gamma`` from ``F0``, then ``D`` and the secant stiffness."""
    c = beta + (chi + 1.0) / (chi + 2.0)
    g = _seed_gamma(F0 / Fs, chi, beta)
    D = (
        4.0
        * g ** (chi + 3.0)
        * Fs**2
        * (beta + 1.0)
        * (chi + 1.0)
        / (KT * c**2 * (chi + 3.0) * (chi + 2.0))
    )  # eq. 17
    K = KT * (1.0 - g ** (chi + 1.0) / ((chi + 2.0) * (beta + 1.0)))  # eq. 24
    return D, K


def _seed_solve(F0, D, u0, Fs, counter, *, max_newton=50):
    """Seed paper sec. 2 for one set of cycles: ``KT`` by Newton, ``chi(KT), beta(KT)`` by
    Nelder-Mead. Returns ``(KT, chi, beta, converged, message, iterations)``.
    """
    lnD = np.log(D)
    lnK = np.log(F0 / u0)

    def decode(z):
        return -1.0 + math.exp(z[0]), z[1] * z[1]  # chi > -1, beta >= 0, unconstrained z

    def inner(KT, z0):
        """Fminsearch for chi(KT), beta(KT): least squares of ln D (eqs. 17, 20)."""

        def obj(z):
            chi, beta = decode(z)
            if not -1.0 < chi < 50.0:
                return 1e30
            counter[0] += 1
            Dm, _ = _seed_model(F0, u0, Fs, KT, chi, beta)
            return float(np.sum((np.log(Dm) - lnD) ** 2))

        res = optimize.minimize(
            obj, z0, method="Nelder-Mead", options={"xatol": 1e-9, "fatol": 1e-15, "maxiter": 2000}
        )
        return res.x

    def h(lnKT, z0):
        """Mean log mismatch of the secant stiffness (eq. 24) with chi, beta re-fitted."""
        KT = math.exp(lnKT)
        z = inner(KT, z0)
        _, Km = _seed_model(F0, u0, Fs, KT, *decode(z))
        return float(np.mean(np.log(Km) - lnK)), z

    lnKT = math.log(1.2 * float(np.max(F0 / u0)))  # K_sec < KT always (eq. 24)
    z = np.array([math.log(0.5), math.sqrt(0.5)])  # chi = -0.5, beta = 0.5
    dh = 1e-4
    for it in range(1, max_newton + 1):
        hv, z = h(lnKT, z)
        slope = (h(lnKT + dh, z)[0] - hv) / dh
        step = -hv / slope if slope != 0 and math.isfinite(slope) else -0.1 * math.copysign(1, hv)
        step = float(np.clip(step, -0.5, 0.5))
        lnKT += step
        if abs(step) < 1e-9:
            hv, z = h(lnKT, z)
            return (
                math.exp(lnKT),
                *decode(z),
                True,
                f"Newton on KT converged in {it} iterations (|h| = {abs(hv):.1e})",
                it,
            )
    return (
        math.exp(lnKT),
        *decode(z),
        False,
        f"Newton on KT did not converge in {max_newton} iterations",
        max_newton,
    )


def _microslip_fit(F0, D, u0, Fs, counter, warns):
    """The seed solution on the microslip cycles: cycles near ``Fs`` left out, then those
    beyond the fitted ``phi_max`` (up to 4 rounds).
    """
    keep = F0 < (1.0 - _SEED_PLATEAU) * Fs
    if not keep.all():
        warns.append(
            f"{int((~keep).sum())} cycle(s) with F0 >= {1 - _SEED_PLATEAU:g} Fs were left "
            "out: eqs. 17 and 20 of the seed method hold only in microslip"
        )
    for round_ in range(4):
        if keep.sum() < 2:
            raise ValueError(
                f"method='seed' needs at least 2 microslip cycles (F0 < 0.99 Fs = "
                f"{0.99 * Fs:g} N, u0 < phi_max), got {int(keep.sum())}"
            )
        KT, chi, beta, converged, msg, it = _seed_solve(F0[keep], D[keep], u0[keep], Fs, counter)
        phi = IwanParameters(Fs, KT, chi, beta).phi_max
        macro = keep & (u0 > phi)
        if not macro.any():
            break
        if round_ == 3:
            warns.append(f"{int(macro.sum())} cycle(s) still have u0 > phi_max = {phi:.4g} m")
            break
        warns.append(
            f"{int(macro.sum())} cycle(s) with u0 > phi_max = {phi:.4g} m "
            "(macroslip) were left out and the fit repeated"
        )
        keep = keep & ~macro
    return keep, KT, chi, beta, converged, msg, it


def _fit_seed(F0, D, u0, Fs, *, t0):
    """The seed paper's identification (sec. 2) with a microslip guard: cycles with
    ``F0 >= 0.99 Fs`` (at or near the macroslip plateau) are left out, and cycles whose
    measured ``u0`` exceeds the fitted ``phi_max`` are dropped and the fit repeated (up to three
    times): eqs. 17 and 20 hold only in microslip.
    """
    counter = [0]
    warns = []
    keep, KT, chi, beta, converged, msg, it = _microslip_fit(F0, D, u0, Fs, counter, warns)
    F0, D, u0 = F0[keep], D[keep], u0[keep]
    params = IwanParameters(Fs, KT, chi, beta)
    n = F0.size
    lnD = np.log(D)
    lnK = np.log(F0 / u0)

    def resid(th):
        counter[0] += 1
        Dm, Km = _seed_model(F0, u0, Fs, math.exp(th[0]), th[1], math.expm1(th[2]))
        with np.errstate(invalid="ignore", divide="ignore"):  # NaN marks an invalid step
            return np.concatenate([np.log(Dm) - lnD, np.log(Km) - lnK])

    theta = np.array([math.log(KT), chi, math.log1p(beta)])
    r = resid(theta)
    se, c3 = _uncertainty(resid, theta, r, [KT, 1.0, 1.0 + beta], at_lower_bound=2)
    stderr = {"Fs": math.nan, "KT": float(se[0]), "chi": float(se[1]), "beta": float(se[2])}
    corr = np.full((4, 4), np.nan)
    corr[1:, 1:] = c3
    warns.append(
        f"beta = {beta:.4g} follows from the given Fs = {Fs:.6g} N: microslip data "
        f"determine only KT, chi and R = {params.R:.5g}; a different Fs gives a "
        "different beta with the same fit"
    )
    warns += _range_warnings(params)
    Dm, Km = _seed_model(F0, u0, Fs, KT, chi, beta)
    nrmse = math.sqrt(np.mean(np.concatenate([Dm / D - 1.0, Km / (F0 / u0) - 1.0]) ** 2))
    warns += _misfit_warning(nrmse)
    if beta < 1e-6:
        warns.append(
            f"beta is at its bound 0: if the given Fs exceeds the largest slip force "
            f"compatible with the data (the beta = 0 one), no beta can compensate and KT "
            f"and chi come out distorted; compare the NRMSE ({100 * nrmse:.3g} %) with "
            "the noise or use method='least_squares'"
        )
    out = {
        "params": params,
        "stderr": stderr,
        "correlation": corr,
        "identified": {"Fs": False, "KT": True, "chi": True, "beta": False},
        "ranges": {},
        "r": r,
        "warnings": warns,
        "details": {"newton_iterations": it, "cycles_used": n, "x_max": float(u0.max())},
        "at_bound": ["chi"] if chi <= -1.0 + 1e-6 else [],
        "explains": nrmse <= NRMSE_LIMIT,
    }
    curves = {"F0": F0, "D": D, "F0_fit": F0, "D_fit": Dm}
    return _finish(
        "seed",
        out,
        converged=converged,
        message=msg,
        nfev=counter[0],
        nrmse=nrmse,
        t0=t0,
        fixed=("Fs",),
        stacklevel=4,
        curves=curves,
    )


def fit_dissipation(
    amplitude,
    force,
    dissipation,
    *,
    method: str = "least_squares",
    Fs: float | None = None,
    n_starts: int = 6,
    seed=0,
    alpha: float = 1e-3,
    max_nfev: int = 300,
) -> FitResult:
    """Fit the Iwan parameters to per-cycle force amplitude and dissipation (paper Fig. 7).

    Parameters
    ----------
    amplitude : array_like, shape (m,)
        Displacement amplitude ``u0`` of each cycle [m], ``> 0``. The seed method needs it for
        the secant stiffness ``F0/u0`` of eq. 24; the least-squares fit for ``F0(u0)``,
        ``D(u0)``. Not modified.
    force : array_like, shape (m,)
        Force amplitude ``F0`` of each cycle [N], ``> 0``. Not modified.
    dissipation : array_like, shape (m,)
        Energy ``D`` dissipated per cycle [J], ``> 0``. Not modified.
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
        NaN/inf, non-positive values, unequal lengths, fewer than 2 cycles, fewer distinct
        amplitudes than the method needs (3, or 2 for ``"seed"``), an unknown method, or
        ``Fs`` missing for ``"seed"`` / given for ``"least_squares"``.

    Warns
    -----
    IdentifiabilityWarning
        As for :func:`fit_loops`; ``"seed"`` always warns that ``beta`` is conditional on the
        given ``Fs``.
    """
    t0 = time.perf_counter()
    ua = check_magnitude(
        "amplitude", finite_array("amplitude", amplitude, ndim=1, min_size=2), unit="m"
    )
    F0a = check_magnitude("force", finite_array("force", force, ndim=1, min_size=2), unit="N")
    Da = check_magnitude(
        "dissipation", finite_array("dissipation", dissipation, ndim=1, min_size=2), unit="J"
    )
    same_length(amplitude=ua, force=F0a, dissipation=Da)
    for name, arr in (("amplitude", ua), ("force", F0a), ("dissipation", Da)):
        if np.any(arr <= 0):
            raise ValueError(f"{name} must be > 0 for every cycle (got {arr.min():g})")
    if method not in ("least_squares", "seed"):
        raise ValueError(f"method must be 'least_squares' or 'seed', got {method!r}")
    need = 2 if method == "seed" else 3
    k = _distinct(ua)
    if k < need:
        raise ValueError(
            f"amplitude holds {k} distinct value(s) (2 % apart); method={method!r} "
            f"needs at least {need}: each amplitude gives two numbers (F0, D), "
            f"too few for {'three' if method == 'seed' else 'four'} parameters. "
            "Test at more amplitudes, or fit the force history with fit_loops"
        )
    if method == "seed":
        if Fs is None:
            raise ValueError(
                "method='seed' needs Fs [N]: the paper takes the slip force as known "
                "(eq. 20 is normalised by it)"
            )
        Fs = check_scalar("Fs", Fs, low=0.0, low_open=True)
        return _fit_seed(F0a, Da, ua, Fs, t0=t0)
    if Fs is not None:
        raise ValueError("Fs is only used by method='seed'; least_squares fits it")
    n_starts = check_int("n_starts", n_starts, 1)
    max_nfev = check_int("max_nfev", max_nfev, 10)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    rng = np.random.default_rng(seed)

    def unit(p1):
        return np.concatenate([force_amplitude(ua, p1), cycle_dissipation(ua, p1)])

    prob = _Problem(
        np.concatenate([F0a, Da]),
        unit,
        w=np.ones(2 * ua.size),
        log_space=True,
        entry_x=np.concatenate([ua, ua]),
        min_macro=MIN_MACRO_POINTS,
    )
    out = _identify(prob, n_starts=n_starts, rng=rng, alpha=alpha, max_nfev=max_nfev, initial=None)
    fit = unit(out["params"])
    nrmse = math.sqrt(np.mean((fit / prob.y - 1.0) ** 2))
    out["details"]["cycles"] = int(ua.size)
    out["warnings"] += _misfit_warning(nrmse)
    out["explains"] = nrmse <= NRMSE_LIMIT
    m = ua.size
    curves = {"F0": F0a, "D": Da, "F0_fit": fit[:m], "D_fit": fit[m:]}
    return _finish(
        "least_squares",
        out,
        converged=out["res"].status > 0,
        message=out["res"].message,
        nfev=prob.nfev,
        nrmse=nrmse,
        t0=t0,
        curves=curves,
    )
