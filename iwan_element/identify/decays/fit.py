"""Direct fit of the modal Iwan model to a free-decay record (no amplitude curve in between).

:func:`fit_decay` fits one nonlinear mode with an Iwan joint and a viscous floor (the model
of :func:`iwan_element.fit_modal_iwan`; Segalman 2005, J. Appl. Mech. 72:752-760) to the
band-passed analytic signal of the record itself, sample by sample. The equations and their
sources are in the project's ``docs/decay_fit.md``; in short:

1. Slowly varying amplitude and phase (first-order averaging; Nayfeh & Mook 1979,
   *Nonlinear Oscillations*, ch. 4) of the displacement at the sensor, ``x = a cos(theta)``::

       da/dt = -zeta(a) w(a) a,      dtheta/dt = w(a) sqrt(1 - zeta(a)**2)

   with ``w(a)``, ``zeta(a)`` the modal Iwan curves (:func:`model_curve`: the parametrisation
   and regimes of :func:`fit_modal_iwan`), integrated once per parameter set by quadrature in
   ``u = ln a`` (``dt/du = -1 / (zeta w)``, ``dtheta/du = -sqrt(1 - zeta**2) / zeta``;
   cumulative Simpson on a fixed grid of 2000 log-amplitudes) and interpolated to the sample
   times (cubic spline).
2. The measured quantity is, to first order in the slow variation,
   ``y = a w**k cos(theta + k asin(zeta) + phi_s)`` (k = 0, 1, 2 for displacement,
   velocity, acceleration; ``phi_s`` absorbs the initial phase and the ``k pi / 2``), zero
   before the start of the decay. Out-of-band modes that show as clear spectral peaks next
   to the band are added as linear decaying sinusoids (frequency, decay rate and two
   amplitudes each, fitted along): released with the mode, their abrupt start leaks through
   the band-pass far more than their steady attenuation says, and unmodelled that leak was
   taken for the joint. This model record, made at the record's rate, goes through
   the *same* decimation (``resample_poly``), zero padding, zero-phase band-pass and Hilbert
   transform as the data, so every end effect is modelled rather than cut away: the fit uses
   the record from the release or impact on.
3. Least squares (``scipy.optimize.least_squares``) on the analytic signal in log-polar form:
   residuals ``|z| (ln|z| - ln|z_m|)`` and ``|z| (arg z - arg z_m)`` (unwrapped phases), which
   to first order in noise / signal are the complex residual ``z - z_m`` turned by the
   signal's phase, without the 2 pi wrap that gives a complex residual many minima in the
   frequency. Samples are decimated to a few per noise correlation time ``1/B`` and used while
   the envelope is above ``snr_min`` times the noise; they are weighted by their local noise
   (the transient an abruptly starting out-of-band mode leaks through the band-pass is
   weighted down).
4. Uncertainty: the exact covariance of the least-squares estimate for band-passed white
   noise, whose correlation follows from the filter (``|H|**4``), with the noise level the
   residual's sum of squares over its degrees of freedom under that correlation (a short
   record holds few independent noise samples and the fit absorbs many of them), scaled up
   by the residual's unexplained structure when there is any. The noise level's own
   chi-square degrees of freedom (Satterthwaite 1946, Biometrics Bulletin 2:110-114) are
   reported; below 5 the result is not a success.
5. Regimes as in :func:`fit_modal_iwan`: in microslip only ``f0, zeta0, chi, delta`` are
   identified; the full set (``kappa, phi_max, beta``) is reported only when a likelihood
   ratio test rejects microslip at ``significance``, ``phi_max`` is known within a factor e
   and lies inside the decay's amplitudes. When the full fit puts ``phi_max`` (known within
   a factor e) below the release amplitude but is not reported, the microslip result is
   returned with ``success=False`` and a warning: its closed forms hold for ``X << phi_max``.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy import stats

from ...base.plausibility import level_failure, record_failure
from ...base.progress import complete, finish, progress_bar, tick
from ...base.threads import one_blas_thread
from ...base.validation import check_scalar
from ..modal.result import ModalIwanFit
from ._fit_model import _covariance, _fit_regime, _local_weights, _misfit_ratio, _Objective
from ._fit_prepare import _prepare, _starts, _window_curve

__all__ = ["fit_decay"]

log = logging.getLogger(__name__)


def _full_starts(micro_x, X_max, x_ref, curve_full):
    """Starts of the full model: the window-curve fit's macroslip solution if any, and
    ``phi_max`` at 0.3, 1 and 3 times the initial amplitude with the microslip ``chi`` (and
    ``chi = -0.5``, since microslip estimates are biased when the data leave microslip), the
    stiffness ratio matching the microslip ``delta``.
    """
    f0, z0, chi_m, delta = micro_x[:4]
    out = [] if curve_full is None else [np.concatenate([curve_full, micro_x[4:]])]
    for ratio in (0.3, 1.0, 3.0):
        for chi in (chi_m, -0.5) if ratio < 3.0 else (chi_m,):
            phimax, beta = ratio * X_max, 0.5
            kappa = delta * (chi + 2.0) * (1.0 + beta) * (phimax / x_ref) ** (chi + 1.0)
            if 0.0 < kappa < 1.0:
                out.append(
                    np.concatenate([[f0, z0, chi, kappa, math.log(phimax), beta], micro_x[4:]])
                )
    return out


def _microslip_saturates(x, x_ref):
    """True when the microslip law reaches, at the release amplitude ``exp(x[-2])``,
    ``(chi + 2) delta (X / X_ref)**(chi + 1) >= 1``: the tangent's relative drop. In the full
    model that drop is ``kappa r**(chi+1) / (1 + beta)`` at ``r = X / phi_max < 1``, below 1
    for ``kappa <= 1``, ``beta >= 0``; reaching 1 means the record passes ``phi_max``.
    """
    chi, delta = x[2], x[3]
    return (chi + 2.0) * delta * (math.exp(x[-2]) / x_ref) ** (chi + 1.0) >= 1.0


def _span(prob, info, i_b, spc):
    """Decimated sample indices of the fit and the log-amplitude span of the quadrature."""
    i_s, env = info["i_s"], info["env"]
    step = max(
        1, min(int(prob.fs / (spc * prob.bw)), (i_b - i_s) // 400), math.ceil((i_b - i_s) / 4000)
    )
    decay = math.log(env[info["i_top"]] / max(env[i_b - 1], 1e-300)) + max(
        0.0, math.log(env[info["i_top"]] / max(env[i_s], 1e-300))
    )
    prob.span = max(3.0 * decay, decay + 5.0)
    return np.arange(i_s, i_b, step), step


def _bounds(prob, regime, X, x_max, ln_a0):
    lo, hi = prob.band
    if regime == "microslip":
        lb, ub = [0.5 * lo, 0.0, -0.999, 1e-12], [2.0 * hi, 0.999, 1.0, 0.999]
    else:
        lb = [0.5 * lo, 0.0, -0.999, 1e-9, math.log(1e-3 * X.min()), 0.0]
        ub = [2.0 * hi, 0.999, 1.0, 1.0 - 1e-9, math.log(1e3 * x_max), 100.0]
    for f2, s2, _, _ in prob.nb_starts:  # a neighbour stays near its spectral estimate
        df = 0.02 * f2
        lb += [f2 - df, 0.0, -np.inf, -np.inf]
        ub += [f2 + df, 2.0 * s2 + 2.0 * math.pi * df, np.inf, np.inf]
    return np.array(lb + [ln_a0 - 10.0, -np.inf]), np.array(ub + [ln_a0 + 10.0, np.inf])


def _no_mode(prob, snr_min, ratio):
    """Refuse a record without a decaying mode the model can follow (pure noise, a band
    without the mode): a ValueError naming ``y`` and the band, not the model's inner range.
    """
    lo, hi = prob.band
    found = (
        "no decay curve fits it"
        if not math.isfinite(ratio)
        else f"its largest envelope is {ratio:.2g} times the noise RMS a decay model leaves"
    )
    raise ValueError(
        f"y holds no decaying mode in band ({lo:g}, {hi:g}) Hz above snr_min = "
        f"{snr_min:g} times the in-band noise: {found} (pure noise or a band "
        "without the mode); check the band around the mode and the record, or "
        "lower snr_min"
    )


def _fit_micro(prob, info, snr_min, spc):
    """Microslip fit in two stages: over the decay to 5 % of the peak envelope, then over
    every sample above ``snr_min`` x the noise (from the first stage's residual), with the
    local-noise weights of the first stage's residual, starting from its solution.
    """
    X, f, zeta = info["data"]
    nuis, env, i_top = info["nuis"], info["env"], info["i_top"]
    bnd = _bounds(prob, "microslip", X, None, nuis[-2])
    curve_starts, curve_full = _starts(X, f, zeta, prob.conv)
    starts = [np.concatenate([s, nuis]) for s in curve_starts]
    idx, step = _span(prob, info, info["i_a"], spc)
    ref = float(np.abs(prob.z[idx]).max())
    first = _fit_regime(_Objective(prob, "microslip", idx, ref, bnd), starts, bnd)
    lag = math.ceil(2.0 * prob.fs / (prob.bw * step))
    with np.errstate(invalid="ignore", divide="ignore"):  # the weights are not used here
        noise = ref * _local_weights(first.fun, lag)[1] * math.sqrt(2.0)
    if not env[i_top] >= snr_min * noise > 0.0:
        _no_mode(prob, snr_min, env[i_top] / noise if noise > 0 else math.nan)
    low = np.flatnonzero(env[i_top:] < snr_min * noise)
    i_b = max(prob.n if low.size == 0 else i_top + int(low[0]), info["i_s"] + 2 * info["nw"])
    idx, step = _span(prob, info, i_b, spc)
    ref = float(np.abs(prob.z[idx]).max())
    obj = _Objective(prob, "microslip", idx, ref, bnd)
    lag = math.ceil(2.0 * prob.fs / (prob.bw * step))
    weights, _ = _local_weights(obj.resid(first.x), lag)
    try:
        envelope = obj.envelope(first.x)  # weights free of each sample's own noise
    except ValueError:  # no decay curve fits: f or zeta out of range
        _no_mode(prob, snr_min, math.nan)
    obj = _Objective(prob, "microslip", idx, ref, bnd, weights, envelope)
    micro = _fit_regime(obj, [first.x], bnd)
    return (
        micro,
        obj,
        dict(
            idx=idx,
            step=step,
            i_b=i_b,
            noise=noise,
            ref=ref,
            curve_full=curve_full,
            weights=weights,
            envelope=envelope,
        ),
    )


def _fit_models(prob, info, alpha, snr_min, spc, bar=None):
    """Microslip fit, then the full model and the likelihood-ratio test between them
    (``bar``: a progress bar, advanced after each).
    """
    micro, obj, span = _fit_micro(prob, info, snr_min, spc)
    tick(bar, text="microslip fitted")
    idx, ref, X = span["idx"], span["ref"], info["data"][0]
    lags = math.ceil(2.0 * prob.fs / (prob.bw * span["step"]))
    chosen, regime, warns, guard = micro, "microslip", [], []
    cov, kappa, dof = _covariance(obj, micro.fun, micro.jac)
    x_max = math.exp(micro.x[-2])
    full_starts = _full_starts(micro.x, x_max, prob.conv["x_ref"], span["curve_full"])
    if 2 * idx.size > 12 and full_starts:
        bnd = _bounds(prob, "macroslip", X, x_max, info["nuis"][-2])
        obj_f = _Objective(prob, "macroslip", idx, ref, bnd, span["weights"], span["envelope"])
        full = _fit_regime(obj_f, full_starts, bnd)
        tick(bar, text="full model fitted")
        cov_f, kappa_f, dof_f = _covariance(obj_f, full.fun, full.jac)
        s2 = float(np.mean(full.fun**2))
        stat = 2.0 * (micro.cost - full.cost) / max(s2 * kappa_f, 1e-300)
        p_val = float(stats.chi2.sf(max(stat, 0.0), 2))
        log.debug("fit_decay: likelihood-ratio statistic %.3g, p %.3g", stat, p_val)
        phi_known = math.sqrt(max(cov_f[4, 4], 0.0)) < 1.0
        t_end = np.array([(span["i_b"] - 1 - info["i_s"]) / prob.fs])
        a_end = math.exp(prob.trajectory(prob.theta(full.x), "macroslip", full.x[-2], t_end)[0, 0])
        inside = a_end < math.exp(full.x[4]) < math.e * math.exp(full.x[-2])
        complete = False
        if p_val < alpha and phi_known and inside:  # every joint parameter must be fixed
            trial = ModalIwanFit.from_solution(
                full.x[:6],
                cov_f[:6, :6],
                "macroslip",
                {},
                prob.conv,
                chi2_red=1.0,
                weights=(),
                warnings=(),
                optimizer_ok=True,
            )
            complete = len(trial.identified) == len(trial.parameters)
        if complete:
            chosen, regime, cov, kappa, dof = full, "macroslip", cov_f, kappa_f, dof_f
        elif p_val < alpha or (
            p_val < 0.05 and phi_known and inside and math.exp(full.x[4]) < math.exp(full.x[-2])
        ):
            # microslip closed forms hold for X << phi_max only
            guard.append(
                f"the record leaves microslip (likelihood-ratio p = {p_val:.2g}; the full "
                f"model puts phi_max at {math.exp(full.x[4]):.3g} m against a release "
                f"amplitude of {math.exp(full.x[-2]):.3g} m) but does not fix the full model: "
                "the microslip parameters f0, zeta0, chi and delta describe amplitudes beyond "
                "the validity of the microslip model and may be biased; not a success"
            )
            warns.append(guard[-1])
        else:
            warns.append(
                f"the decay never leaves microslip (likelihood-ratio p = {p_val:.2g}, "
                f"phi_max {'not ' if not phi_known else ''}bounded"
                f"{'' if inside else ', outside the decay amplitudes'}"
                f"{'' if complete or not (phi_known and inside) else ', joint not fixed'}"
                "): KT, phi_max, beta "
                "and Fs are not identified; reported f0, zeta0, chi and delta"
            )
    if regime == "microslip" and _microslip_saturates(micro.x, prob.conv["x_ref"]):
        guard.append(
            "the microslip curve's tangent stiffness vanishes inside the record: "
            "its largest amplitudes are beyond phi_max for any joint not stiffer "
            "than the mode; the microslip parameters may be biased; not a success"
        )
        warns.append(guard[-1])
    chi2_red = _misfit_ratio(chosen.fun, lags)
    if chi2_red > 1.0:  # structure beyond the noise model: widen (as fit_modal_iwan)
        cov = cov * chi2_red
    span.update(
        kappa=kappa, dof=dof, chi2_red=chi2_red, regime=regime, warns=warns, cov=cov, guard=guard
    )
    return chosen, span


def _describe_span(prob, conv, info, span, best):
    """The fitted span into ``conv`` (times, samples, noise, amplitudes, neighbour modes),
    with a warning when the amplitude hardly changes over it; the number of model parameters.
    """
    regime, warns, i_s, i_b = span["regime"], span["warns"], info["i_s"], span["i_b"]
    t0 = info["t0"]
    n_th = best.x.size - prob.n_nuis
    a_end = float(
        np.exp(
            prob.trajectory(
                best.x[:n_th], regime, best.x[-2], np.array([(i_b - 1 - i_s) / prob.fs])
            )[0, 0]
        )
    )
    conv.update(
        t_fit=[t0 + i_s / prob.fs, t0 + (i_b - 1) / prob.fs],
        samples=int(span["idx"].size),
        sample_step=float(span["step"] / prob.fs),
        noise_rms=span["noise"] / math.sqrt(2.0),
        correlation_factor=float(span["kappa"]),
        residual_dof=float(span["dof"][0]),
        noise_dof=float(span["dof"][1]),
        amplitude_range=[math.exp(best.x[-2]), a_end],
        neighbour_modes=[
            dict(frequency=float(v[0]), decay_rate=float(v[1]))
            for v in best.x[n_th : n_th + 4 * prob.nb].reshape(-1, 4)
        ],
    )
    if best.x[-2] - math.log(a_end) < 0.1:
        change = 100 * (math.exp(best.x[-2]) / a_end - 1)
        warns.append(
            f"the amplitude changes by only {change:.2g} % over the fitted span: the "
            "amplitude dependence rests on very little"
        )
    return n_th


def _decay_fit_result(prob, conv, info, span, best, n_th):
    """The window estimates over the fitted span as data, and the :class:`ModalIwanFit`
    (not a success when a guard holds).
    """
    X, f, zeta, _ = _window_curve(prob, info["i_s"], span["i_b"], info["nw"])
    data = dict(
        amplitude=X,
        frequency=f,
        damping_ratio=zeta,
        frequency_std=np.full(X.size, np.nan),
        damping_ratio_std=np.full(X.size, np.nan),
    )
    fit = ModalIwanFit.from_solution(
        best.x[:n_th],
        span["cov"][:n_th, :n_th],
        span["regime"],
        data,
        conv,
        chi2_red=span["chi2_red"],
        weights=(),
        warnings=tuple(w for w in [info["clip_note"]] + span["warns"] if w),
        optimizer_ok=bool(best.success),
        noise_dof=span["dof"][1],
        noise_source=(
            " (the record holds few independent noise samples "
            "beyond what the fit absorbs; a longer record, a "
            "wider band or less noise would help)"
        ),
    )
    guard = _implausible(prob, X, f) + tuple(span["guard"])
    if guard:
        fit = dataclasses.replace(
            fit,
            success=False,
            failures=guard + fit.failure_reasons(),
            warnings=tuple(w for w in guard if w not in fit.warnings) + fit.warnings,
        )
    return fit


def _implausible(prob, X, f) -> tuple:
    """The record's plausibility (:mod:`iwan_element.base.plausibility`): its derivatives
    at the working rate and the window estimates' velocity and acceleration.
    """
    quantity = ("displacement", "velocity", "acceleration")[prob.k]
    why = record_failure(prob.y, 1.0 / prob.fs, quantity=quantity, name="y") or level_failure(
        X, f, quantity=quantity, name="y"
    )
    return (why,) if why else ()


def fit_decay(
    t,
    y,
    *,
    quantity: str = "acceleration",
    band,
    order: int = 4,
    stiffness: str = "harmonic",
    floor: str = "dashpot",
    x_ref: float | None = None,
    t_start: float | None = None,
    snr_min: float = 10.0,
    samples_per_correlation: float = 4.0,
    significance: float = 1e-3,
    progress: bool = False,
) -> ModalIwanFit:
    """Fit the modal Iwan model directly to a free-decay record of one mode.

    The slowly varying amplitude and phase of the mode (averaging) with the modal Iwan
    frequency and damping curves (Segalman 2005, J. Appl. Mech. 72:752-760) are passed through
    the same zero-phase band-pass and Hilbert transform as the record and fitted to its
    analytic signal sample by sample (least squares in log-polar form, samples weighted by
    their local noise, covariance for band-passed noise from the filter's correlation, widened
    by unexplained structure). The module docstring and the project's
    ``docs/decay_fit.md`` give the equations. Unlike ``fit_modal_iwan(amplitude_curve(...))``
    no windows are needed, so short and heavily damped decays are used to their start.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s], strictly increasing and uniform (jitter up to 5 % of the step).
    y : array_like, shape (n,)
        Response at the sensor in SI units of ``quantity``; at least 64 samples.
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
        What ``y`` is: [m/s^2], [m/s] or [m].
    band : (float, float), keyword-only
        Pass band ``(f_lo, f_hi)`` [Hz] around one mode, inside ``(0, fs/2)``; other modes
        should be outside it.
    order : int, keyword-only
        Butterworth order (default 4, range 1..10).
    stiffness, floor : str, keyword-only
        As in :func:`fit_modal_iwan` (default first-harmonic stiffness, dashpot floor).
    x_ref : float, optional
        Reference displacement amplitude [m] of ``delta``; default the geometric mean of the
        amplitudes in the fitted span.
    t_start : float, optional
        Time [s] at which the free decay starts (release, end of the impact); default the
        record's start when the band-passed peak is there, else the largest raw sample near
        the band-passed peak. The model is zero before it.
    snr_min : float, keyword-only
        Samples are used while the envelope is above ``snr_min`` times the in-band noise
        RMS (default 10, range [2, 1e6]).
    samples_per_correlation : float, keyword-only
        Decimation: samples per noise correlation time ``1/B`` (default 4, range [1, 100]).
    significance : float, keyword-only
        Level of the likelihood-ratio test that must reject microslip before ``phi_max`` and
        ``beta`` are reported (default 1e-3, range (0, 0.5)). Under microslip ``phi_max`` is
        not identified, so the statistic's null distribution is heavier than the chi-square
        with 2 degrees of freedom it is compared with (Davies 1987, Biometrika 74:33-43);
        the small default allows for that.
    progress : bool, keyword-only
        Show a tqdm bar over the stages (record prepared, microslip fit, full-model fit,
        uncertainty) with its ETA; needs tqdm (:mod:`iwan_element.base.progress`).

    Returns
    -------
    ModalIwanFit
        As from :func:`fit_modal_iwan` (parameters in the sensor coordinate with unit modal
        mass, ``stderr``, ``predict``, ``warnings``, ``success``); ``data`` holds local
        window estimates of the record (for plots only), ``conventions["method"]`` is
        ``"direct signal fit"`` with the band, the fitted span, the noise and
        ``neighbour_modes`` (frequency [Hz] and decay rate [1/s] of each out-of-band mode
        modelled), ``residual_dof`` (samples) and ``noise_dof`` (chi-square degrees of
        freedom of the noise level, on which every stderr rests). ``success`` is False when
        microslip is reported although the full model places ``phi_max`` below the release
        amplitude, or when ``noise_dof < 5`` (+-2 stderr would cover less than 90 %).

    Raises
    ------
    ValueError
        Bad input (NaN, non-uniform ``t``, band outside ``(0, fs/2)``, unknown quantity), or
        no decaying mode above ``snr_min`` times the noise in the band.
    """
    snr_min = check_scalar("snr_min", snr_min, low=2.0, high=1e6)
    spc = check_scalar("samples_per_correlation", samples_per_correlation, low=1.0, high=100.0)
    alpha = check_scalar(
        "significance", significance, low=0.0, high=0.5, low_open=True, high_open=True
    )
    bar = progress_bar(progress, total=4, desc="fit_decay", unit="stage")
    try:
        prob, conv, info = _prepare(t, y, quantity, band, order, stiffness, floor, x_ref, t_start)
        tick(bar, text="record prepared")
        with one_blas_thread():  # the Jacobian's SVD per step is small: threads cost
            best, span = _fit_models(prob, info, alpha, snr_min, spc, bar)
        tick(bar, text="uncertainty")
        complete(bar, "done (no full model to fit)")  # the full model's stage when skipped
    finally:
        finish(bar)
    n_th = _describe_span(prob, conv, info, span, best)
    fit = _decay_fit_result(prob, conv, info, span, best, n_th)
    log.debug("fit_decay: %s", conv)
    return fit
