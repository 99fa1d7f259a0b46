"""Loop fit: the four Iwan parameters from a measured force-displacement record.

The exact :class:`IwanJoint` is driven by the (de-noised) measured displacement and the force
residuals are minimised by bounded least squares, with the two sensor zero offsets as
nuisance parameters: ``F = F_iwan(u - du0) + dF0``.

How it is made fast
    For a displacement-driven record the reversal points, and so the Masing branch each
    sample lies on, do not depend on the parameters; they are found once and each evaluation
    is a few numpy operations (:mod:`iwan_element.core.history`, verified against
    ``IwanJoint.force_history`` to round-off). The fitted samples are decimated to
    ``max_samples`` but the reversal points of the full record are kept. At fixed
    ``(phi_max, chi, beta)`` the force is linear in ``Fs`` and in ``dF0`` (the backbone is
    ``Fs f(u/phi_max)``, paper eq. 12), so both are eliminated in closed form (variable
    projection) and the optimiser searches only ``(ln phi_max, chi, ln(1 + beta))``.

Start of the record and offsets
    The residuals are taken from the second turning point of the displacement on (see
    :mod:`iwan_element.identify.loops.model_fit`): the joint's state at the start of a measured
    record is unknown, and after one full sweep it differs from the model's only by a constant
    force, which ``dF0`` absorbs. The displacement offset ``du0`` is estimated from the
    curvature of the residual sum of squares in ``du0`` (a Gauss-Newton step from 0, refitted
    once if it is large); when the record depends only on displacement differences (no
    excursion beyond the first sweep) it is reported as not determined.

Identifiability, uncertainties and the verdict: :mod:`iwan_element.identify.loops.identifiability`.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time

import numpy as np
from scipy.special import fdtrc

from ...base.plausibility import record_failure
from ...base.validation import (
    check_int,
    check_magnitude,
    check_scalar,
    check_time,
    check_varies,
    finite_array,
    same_length,
)
from ...core.history import REVERSAL_TOL, History
from ...core.parameters import IwanParameters
from .cycles import split_cycles
from .identifiability import _identify, min_macroslip
from .model_fit import burn_in_index, drive_displacement
from .noise import estimate_noise
from .result import FitResult, _finish
from .solver import _Problem

__all__ = ["fit_loops"]


def _check_record(t, u, F):
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=32), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=32), unit="N")
    n = same_length(u=uu, F=FF)
    tt = check_time(t, n)
    if not np.any(FF != 0.0):
        raise ValueError("F is all zero: there is no force to fit")
    check_varies("u", uu, unit="m", what="a loop fit needs cycles of displacement")
    check_varies(
        "F",
        FF,
        unit="N",
        what="the joint force does not follow the displacement; check the force channel",
    )
    c = np.corrcoef(uu, FF)[0, 1] if np.ptp(FF) > 0 else 0.0
    if c < -0.2:
        raise ValueError(
            f"F decreases with u (correlation {c:.2f}): the joint force must have "
            "the sign of the displacement; flip the sign of one of them"
        )
    return tt, uu, FF


def _weights(noise, n):
    if noise is None:
        return np.ones(n)
    if np.ndim(noise) == 0:
        return np.full(n, 1.0 / check_scalar("noise", noise, low=0.0, low_open=True))
    s = finite_array("noise", noise, ndim=1)
    if s.size != n or np.any(s <= 0):
        raise ValueError(f"noise must be a positive scalar or have {n} positive entries")
    return 1.0 / s


def _setup(u_drive, FF, w_full, keep, hysteresis_tol):
    hist = History(u_drive, keep=keep, tol=hysteresis_tol)
    prob = _Problem(
        FF[keep],
        hist.forces,
        w=w_full[keep],
        log_space=False,
        entry_x=hist.x[hist.out],
        min_macro=min_macroslip(keep.size),
        offset=True,
        timeseries=True,
    )
    return hist, prob


def _shifted(hist: History, u_drive: np.ndarray, shift: float) -> History:
    """``hist`` for the displacement ``u_drive - shift`` with the same reversal structure.

    On a Masing branch the backbone argument depends on displacement differences only; the
    shift changes the samples on the virgin curve (``|mult| == 1``), whose argument is ``|u|``.
    For a small shift the structure itself does not change.
    """
    hs = copy.copy(hist)
    v = np.abs(hist.mult) == 1.0
    uu = u_drive[hist.index[v]] - shift
    hs.x = hist.x.copy()
    hs.mult = hist.mult.copy()
    hs.x[v] = np.abs(uu)
    hs.mult[v] = np.where(uu >= 0.0, 1.0, -1.0)
    return hs


def _ssr_at(hist, u_drive, shift, prob, params):
    """Residual sum of squares with the displacement shifted by ``-shift``, shape fixed,
    ``Fs`` and ``dF0`` re-projected.
    """
    g = _shifted(hist, u_drive, shift).forces(
        IwanParameters(1.0, params.KT / params.Fs, params.chi, params.beta)
    )
    _, r = prob.project_g(g)
    return float(np.einsum("i,i->", r, r))


def _displacement_offset(hist, u_drive, prob, out, amp):
    """``(du0, stderr)`` from the curvature of the SSR in ``du0`` (NaN stderr: not determined,
    i.e. the standard error would exceed 10 % of the half range).
    """
    h = 2e-3 * amp
    p = out["params"]
    s0 = _ssr_at(hist, u_drive, 0.0, prob, p)
    sp = _ssr_at(hist, u_drive, h, prob, p)
    sm = _ssr_at(hist, u_drive, -h, prob, p)
    curv = (sp + sm - 2.0 * s0) / (h * h)
    s2tau = s0 / max(prob.y.size - out["n_free"] - 2, 1) * out["tau"]
    if not curv > 0:
        return 0.0, math.nan
    se = math.sqrt(2.0 * s2tau / curv)
    if se > 0.1 * amp:
        return 0.0, math.nan
    return float(-(sp - sm) / (2.0 * h) / curv), float(se)


def _explains(out, prob):
    """F-test of the fitted joint against a constant force (offset only), with the effective
    number of residuals: ``(p_value, R^2)``.
    """
    y, w = prob.y, prob.w
    ybar = float(np.sum(w * w * y) / np.sum(w * w))
    ssr0 = float(np.sum((w * (y - ybar)) ** 2))
    ssr, k = out["ssr"], out["n_free"]
    m_eff = y.size / out["tau"]
    if ssr <= 0.0:
        return 0.0, 1.0
    if ssr0 <= ssr or m_eff <= k + 2:
        return 1.0, max(0.0, 1.0 - ssr / ssr0) if ssr0 > 0 else 0.0
    F_stat = (ssr0 - ssr) / k / (ssr / (y.size - k - 1)) / out["tau"]
    return float(fdtrc(k, m_eff - k - 1, F_stat)), 1.0 - ssr / ssr0


def _check_cycles(tt, uu, FF, hysteresis):
    """The record's cycles, and a warning when most do not close or drift."""
    cycles = split_cycles(tt, uu, FF, hysteresis=hysteresis)
    if len(cycles) < 2:
        raise ValueError(f"u contains {len(cycles)} complete cycle(s); at least 2 are needed")
    warns = []
    bad = [c.index for c in cycles if not c.closed or c.drifting]
    if len(bad) > len(cycles) // 2:
        warns.append(
            f"{len(bad)} of {len(cycles)} cycles do not close or their centre moves "
            f"relative to the others (cycles {bad[:8]}); constant sensor offsets are "
            "fitted and do not cause this"
        )
    return cycles, warns


def _drive(tt, uu, smooth, warns):
    """The displacement that drives the model, its noise and the record's half range."""
    u_drive, dinfo = drive_displacement(tt, uu, smooth)
    sigma_u = dinfo["displacement_noise"]
    amp = 0.5 * float(np.ptp(uu))
    if dinfo["smooth"] == 0 and sigma_u > 1e-3 * amp:
        warns.append(
            f"displacement noise ({sigma_u:.2g} m, {100 * sigma_u / amp:.2g} % of the "
            "half range) drives the model unfiltered (only a dead band of 3 sigma keeps "
            "its reversals out); use smooth='auto'"
        )
    return u_drive, dinfo, sigma_u, amp


def _fitted_samples(u_drive, n, max_samples, hysteresis):
    """The burn-in index and at most ``max_samples`` fitted samples after it."""
    b = burn_in_index(u_drive, hysteresis=hysteresis)
    m_all = n - b
    keep = b + np.unique(
        np.round(np.linspace(0, m_all - 1, min(m_all, max_samples))).astype(np.intp)
    )
    return b, keep


def _misfit(out, prob, hist, alpha, warns):
    """Whether the joint explains the force, the fitted force and the NRMSE, with warnings."""
    p_noise, r2 = _explains(out, prob)
    dF0, se_dF0 = out["dF0"]
    if p_noise >= alpha:
        out["explains"] = False
        warns.append(
            f"the force is indistinguishable from noise: the joint explains "
            f"{100 * r2:.2g} % of its variance, not significantly more than a constant "
            f"(p = {p_noise:.2g} >= {alpha:g}); nothing is identified"
        )
    F_fit = hist.forces(out["params"])
    y = prob.y
    nrmse = math.sqrt(np.mean((y - dF0 - F_fit) ** 2)) / float(np.ptp(y))
    if out["tau"] > 3.0 and nrmse > 1e-6:
        warns.append(
            f"the residuals are correlated over {out['tau']:.3g} samples (a systematic "
            f"misfit or coloured noise): the std. errors are widened by "
            f"sqrt(tau) = {math.sqrt(out['tau']):.3g}"
        )
    return dF0, se_dF0, F_fit, y, nrmse, p_noise, r2


def _details(n, keep, b, hist, cycles, noise, p_noise, r2, dinfo):
    """The fit's details: samples, burn-in, model samples, cycles, noise test, drive."""
    return {
        "samples": n,
        "fitted_samples": int(keep.size),
        "burn_in": int(b),
        "model_samples": int(hist.index.size),
        "reversal_depth": hist.depth,
        "cycles": len(cycles),
        "weighted": noise is not None,
        "p_explains": p_noise,
        "r_squared": r2,
        **dinfo,
    }


def fit_loops(
    t,
    u,
    F,
    *,
    noise=None,
    smooth="auto",
    max_samples: int | None = 20000,
    n_starts: int = 6,
    seed=0,
    alpha: float = 1e-3,
    hysteresis: float | None = None,
    initial: IwanParameters | None = None,
    max_nfev: int = 300,
) -> FitResult:
    """Fit all four Iwan parameters and the sensor offsets to a measured force history.

    Parameters
    ----------
    t : array_like, shape (n,)
        Time [s], strictly increasing. Not modified.
    u : array_like, shape (n,)
        Measured joint displacement [m]. Not modified.
    F : array_like, shape (n,)
        Measured joint force [N]. Not modified.
    noise : float or array_like of shape (n,), optional, keyword-only
        Force noise standard deviation [N] (weights ``1/noise``; the package's one name for a
        given noise level, as in :func:`~iwan_element.diagnose`); default uniform weights.
        It overrides the estimated noise in the report.
    smooth : "auto", 0 or odd int, keyword-only
        De-noising of the displacement that drives the model (quintic Savitzky-Golay window,
        see :func:`~iwan_element.identify.loops.model_fit.drive_displacement`); ``"auto"``
        (default) filters only when the displacement noise exceeds ``1e-4`` of its half
        range. Displacement noise is an error in the model's input: unfiltered it creates
        spurious reversals and biases ``KT`` low and ``chi`` high.
    max_samples : int or None, keyword-only
        Most samples whose residuals are fitted (evenly spaced; the reversal points of the
        whole record are always used), ``>= 100``; ``None`` fits every sample. Default 20000.
    n_starts : int, keyword-only
        Starts of the four-parameter fit, ``>= 1``: four deterministic ones from the
        microslip fit, the rest drawn from ``seed``. Default 6.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the random starts (default 0: reproducible).
    alpha : float, keyword-only
        Significance level, in ``(0, 0.5)``, of the test that the data reach macroslip and of
        the test that the joint explains more than noise.
    hysteresis : float, optional, keyword-only
        Dead band [m] to count cycles (see
        :func:`iwan_element.identify.loops.cycles.find_reversals`).
    initial : IwanParameters, optional, keyword-only
        An extra start (for instance a previous fit).
    max_nfev : int, keyword-only
        Evaluations per start, ``>= 10``.

    Returns
    -------
    FitResult
        ``method="loops"``; ``offsets`` holds ``dF0`` [N] and ``du0`` [m] with standard
        errors, ``noise`` the estimated noise of both channels.

    Raises
    ------
    ValueError
        NaN/inf, unequal lengths, fewer than 32 samples, non-increasing ``t``, an all-zero
        force, a displacement that does not vary, a force of the opposite sign convention,
        fewer than two cycles, or an option out of range.

    Warns
    -----
    IdentifiabilityWarning
        When a parameter is not identified or the fit is not successful; the same text is in
        ``result.warnings``.
    """
    t0 = time.perf_counter()
    tt, uu, FF = _check_record(t, u, F)
    n = uu.size
    w_full = _weights(noise, n)
    max_samples = n if max_samples is None else check_int("max_samples", max_samples, 100)
    n_starts = check_int("n_starts", n_starts, 1)
    max_nfev = check_int("max_nfev", max_nfev, 10)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    if initial is not None and not isinstance(initial, IwanParameters):
        raise ValueError(f"initial must be an IwanParameters or None, got {type(initial).__name__}")
    rng = np.random.default_rng(seed)
    cycles, warns = _check_cycles(tt, uu, FF, hysteresis)
    noise_F = estimate_noise(tt, FF)
    u_drive, dinfo, sigma_u, amp = _drive(tt, uu, smooth, warns)
    b, keep = _fitted_samples(u_drive, n, max_samples, hysteresis)
    # reversals smaller than the noise left in the driving displacement are noise, not the
    # joint's: a dead band of 3 sigma keeps them from adding stiff micro-loops (errors in
    # variables: they bias KT low and chi high)
    tol = max(REVERSAL_TOL * float(np.abs(u_drive).max()), 3.0 * dinfo["drive_noise"])
    hist, prob = _setup(u_drive, FF, w_full, keep, tol)
    half = int(keep.size / max(2 * len(cycles), 1))
    prob.block = half
    out = _identify(
        prob, n_starts=n_starts, rng=rng, alpha=alpha, max_nfev=max_nfev, initial=initial
    )
    du0, se_du0, hist, prob, out = _fit_displacement_offset(
        (hist, prob),
        out,
        u_drive,
        FF,
        w_full,
        keep,
        tol,
        amp,
        dict(rng=rng, alpha=alpha, max_nfev=max_nfev),
    )
    dF0, se_dF0, F_fit, y, nrmse, p_noise, r2 = _misfit(out, prob, hist, alpha, warns)
    out["details"].update(_details(n, keep, b, hist, cycles, noise, p_noise, r2, dinfo))
    noise_out = {
        "force": noise_F.sigma if noise is None else float(np.median(1.0 / w_full)),
        "displacement": sigma_u,
        "tau": out["tau"],
        "force_method": noise_F.method if noise is None else "given",
    }
    curves = {"u": u_drive[keep] - du0, "F": y - dF0, "F_fit": F_fit}
    result = _finish(
        "loops",
        out,
        converged=out["res"].status > 0,
        message=out["res"].message,
        nfev=prob.nfev,
        nrmse=nrmse,
        t0=t0,
        extra_warnings=warns,
        offsets={"force": (dF0, se_dF0), "displacement": (du0, se_du0)},
        noise=noise_out,
        curves=curves,
    )
    return _plausible(result, uu, tt)


def _plausible(result, uu, tt):
    """``result``, not usable when the displacement ``uu`` [m] at times ``tt`` [s] moves
    faster than a jointed structure's test (:mod:`iwan_element.base.plausibility`): a
    displacement in mm or um given as m, or another quantity.
    """
    why = record_failure(uu, tt, quantity="displacement", name="u")
    if not why:
        return result
    return dataclasses.replace(
        result, success=False, failures=(why,) + result.failures, warnings=(why,) + result.warnings
    )


def _fit_displacement_offset(setup, out, u_drive, FF, w_full, keep, tol, amp, opts):
    """Gauss-Newton on the displacement offset ``du0``, refitting the joint each time (up to
    4 steps; a shift that does not lower the misfit is not taken). ``setup``: the current
    ``(hist, prob)``; ``amp``: half the measured displacement range [m]; ``opts``: ``rng``,
    ``alpha``, ``max_nfev`` of the joint's fit.
    Returns ``(du0, se_du0, hist, prob, out)`` (``se_du0`` NaN: not determined).
    """
    hist, prob = setup
    half = prob.block
    du0, se_du0 = 0.0, math.nan
    for _ in range(4):
        step, se_du0 = _displacement_offset(hist, u_drive - du0, prob, out, amp)
        if not math.isfinite(se_du0) or abs(step) <= max(0.1 * se_du0, 1e-5 * amp):
            break
        trial = _setup(u_drive - du0 - step, FF, w_full, keep, tol)
        trial[1].block = half
        out_t = _identify(trial[1], n_starts=1, initial=out["params"], **opts)
        if out_t["ssr"] >= out["ssr"]:
            break  # the shift does not improve the fit: keep what we have
        du0 += step
        (hist, prob), out = trial, out_t
    return du0, se_du0, hist, prob, out
