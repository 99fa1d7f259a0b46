"""From a measured free decay to frequency and damping against amplitude.

:func:`amplitude_curve` turns a ring-down record (hammer impact, release test, a simulated
free decay) into an :class:`~iwan_element.identify.curves.AmplitudeCurve`:

1. The record is band-pass filtered around one mode with a zero-phase Butterworth filter
   (``scipy.signal.butter`` as second-order sections, ``scipy.signal.sosfiltfilt``).
2. Its analytic signal ``z(t)`` comes from the Hilbert transform (``scipy.signal.hilbert``,
   zero-padded to at least twice the length so that the FFT's wrap-around does not carry the
   large start of the record into its quiet end).
   For a slowly decaying mode ``z = A(t) exp(i theta(t))``: the envelope ``A`` and the
   unwrapped phase ``theta``.
3. In consecutive, non-overlapping windows (default 20 periods, shortened to at least three
   periods where the envelope would fall by more than ``e**0.5`` within one, so that the
   amplitude at the window centre stands for the window) straight lines are fitted to
   ``ln A`` and ``theta``: their slopes are ``-sigma`` (decay rate) and ``w_d`` (damped
   angular frequency). Then ``w_n = sqrt(sigma**2 + w_d**2)`` (the undamped natural
   frequency, reported as ``frequency``), ``zeta = sigma / w_n`` and the amplitude at the
   window centre is ``A / w_n**k`` (k = 2 for acceleration, 1 for velocity, 0 for
   displacement): the displacement amplitude at the sensor.
4. Per-point uncertainty: the regression standard errors, computed from the residuals
   averaged over blocks of one period (the block means drop the deterministic ripple that
   harmonics of a nonlinear response leave in envelope and phase, and are nearly
   independent samples of the noise); when the filter's noise bandwidth ``B`` is below the
   mode frequency the blocks are ``1 / B`` long, the noise's correlation time.
5. End effects: the filter's impulse response (``sosfilt`` of a unit impulse) is taken to
   last until it stays below 1e-3 of its peak; that time is cut after the largest sample of
   the band-passed record (the impact, or the release at the start of the record) and before
   the end of the record. Those cut stretches are tapered (half-Hann) before the Hilbert
   transform: a record cropped at the impact starts abruptly, and the transform's slowly
   decaying ``1/t`` kernel would otherwise spread that step over the whole record.
6. Noise, from the in-band signal itself (no pre-trigger needed, not fooled by other modes
   outside the band). In consecutive windows after the impact the analytic signal ``z`` is
   compared with its local free-decay model ``exp(a + b t + i (c + d t))`` (straight lines
   through ``ln |z|`` and the phase). In-band real noise of RMS ``s`` adds ``sqrt(2) s`` RMS
   to ``z``, so ``rms|z - model| / sqrt(2)`` is an upper bound on ``s`` (model error, such as
   a frequency drifting within the window, only adds); where the mode has decayed into the
   noise (the residual is above 0.3 of ``rms|z|``) the whole in-band content
   ``rms|z| / sqrt(2)`` is the bound (the record's late tail). Each window's bound rests on
   only ``B T`` independent samples, so the estimate is the median of the lower half of the
   windows' bounds. When the record has a pre-trigger of at least three periods clear of the
   filter's end effects, the RMS of the band-passed pre-trigger is a direct estimate, and the
   smaller of the two is used: no estimate can exceed what a clean stretch of the signal
   allows (an envelope that fits an exponential to 1e-3 bounds the noise at 1e-3 of it).
   The out-of-band spectral level is not used: on an impact test it holds the tails of the
   other modes and overstates the in-band noise by orders of magnitude.
7. Stop and noise floor: ``noise_floor`` is the noise-based amplitude floor, the
   displacement amplitude at which the envelope would be ``snr_min`` times the in-band noise
   RMS ``s_n``. The curve stops where the envelope falls below that, or at the end of the
   record, or (after at least three points) at the first window whose damping ratio has a
   relative standard uncertainty (step 4) above ``max_damping_std`` while the noise alone
   would cause that much (the decay-rate error that noise ``s_n / A`` on ``B T`` independent
   samples gives, ``sqrt(12) (s_n / A) / (T sqrt(B T))``, is above the limit; a scatter that
   the noise cannot explain, such as the change of damping within a window at large
   amplitude, does not stop the curve). Why and at which amplitude the curve stopped is in
   ``notes``; a stop for a reason other than noise (a window that is not a decaying mode in
   the band) is also a warning.

The band must hold one clear mode: a Welch spectrum peak inside it, not at its edges, at
least 10 times the band's median level, with no second peak above a tenth of it.
"""
from __future__ import annotations

import logging
import math

import numpy as np
from scipy import signal

from ..core._validation import check_magnitude, check_scalar, finite_array
from .curves import AmplitudeCurve

__all__ = ["amplitude_curve"]

log = logging.getLogger(__name__)

_QUANTITY_POWER = {"displacement": 0, "velocity": 1, "acceleration": 2}


def _check_uniform_time(t, n):
    tt = finite_array("t", t)
    if tt.size != n:
        raise ValueError(f"t must have the same length as y ({n}), got {tt.size}")
    d = np.diff(tt)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0])
        raise ValueError(f"t (time) must be strictly increasing; it goes from {tt[i]:g} to "
                         f"{tt[i + 1]:g} at samples {i}..{i + 1}")
    idx = np.arange(n)
    dt = (tt[-1] - tt[0]) / (n - 1)
    jitter = np.max(np.abs(tt - (tt[0] + idx * dt)))
    if jitter > 0.05 * dt:
        raise ValueError(f"t must be uniformly sampled: it departs from a uniform grid by "
                         f"{jitter:.3g} s, more than 5 % of the mean step {dt:.3g} s; resample first")
    return tt, dt


def _check_band(band, fs):
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"band must be a pair (f_lo, f_hi) in Hz, got {band!r}") from None
    nyq = 0.5 * fs
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi < nyq):
        raise ValueError(f"band must satisfy 0 < f_lo < f_hi < Nyquist ({nyq:g} Hz), got "
                         f"({lo:g}, {hi:g}) Hz")
    return lo, hi


def _check_mode(y, fs, lo, hi):
    """Welch spectrum of the record: the frequency of the one clear mode in the band."""
    nper = int(min(y.size, 2 ** math.ceil(math.log2(fs / ((hi - lo) / 64.0)))))
    f, P = signal.welch(y, fs=fs, nperseg=nper)
    inb = np.flatnonzero((f >= lo) & (f <= hi))
    if inb.size < 8:
        raise ValueError(f"band ({lo:g}, {hi:g}) Hz is too narrow for the record length "
                         f"({y.size / fs:.3g} s): it holds {inb.size} spectral lines; widen it")
    Pb = P[inb]
    k = int(np.argmax(Pb))
    med = float(np.median(Pb))
    where = f"in band ({lo:g}, {hi:g}) Hz"
    if k < 2 or k > inb.size - 3:
        raise ValueError(f"no clear mode {where}: the strongest content is at its edge "
                         f"({f[inb[k]]:.4g} Hz); move or widen the band around one mode")
    if Pb[k] < 10.0 * med:
        raise ValueError(f"no clear mode {where}: the spectral peak at {f[inb[k]]:.4g} Hz is "
                         f"only {Pb[k] / max(med, 1e-300):.3g} times the band's median level "
                         "(needs 10)")
    peaks, _ = signal.find_peaks(Pb, prominence=0.05 * Pb[k])
    others = [int(j) for j in peaks if abs(int(j) - k) > 3 and Pb[j] > 0.1 * Pb[k]]
    if others:
        raise ValueError(f"band ({lo:g}, {hi:g}) Hz holds more than one mode (peaks at "
                         f"{f[inb[k]]:.4g} Hz and {f[inb[others[0]]]:.4g} Hz); narrow it to one")
    return float(f[inb[k]])


def _filter_extent(sos, fs, lo, hi):
    """Samples until the filter's impulse response stays below 1e-3 of its peak."""
    n = int(max(64, 40.0 * fs / (hi - lo)))
    imp = np.zeros(n)
    imp[0] = 1.0
    h = np.abs(signal.sosfilt(sos, imp))
    above = np.flatnonzero(h > 1e-3 * h.max())
    return int(above[-1]) + 1


def _noise_bandwidth(sos, fs):
    """Noise bandwidth [Hz] of the zero-phase filter (``sosfiltfilt`` applies ``|H|**2``)."""
    w, H = signal.sosfreqz(sos, worN=8192, fs=fs)
    return float(np.trapezoid(np.abs(H) ** 4, w))


def _residual_noise(z, i0, i1, nw):
    """Upper bound on the in-band noise RMS from the analytic signal itself (step 6).

    In consecutive windows of ``nw`` samples, ``z`` is compared with its local model
    ``exp(a + b t + i (c + d t))`` (straight lines through ``ln |z|`` and the phase); the RMS
    of ``|z - model|`` and of ``|z|`` (the whole in-band content, the bound where the mode has
    decayed) are each at least the noise's, which for band-limited real noise of RMS ``s``
    is ``sqrt(2) s`` in the analytic signal. Model error (a drifting frequency, harmonics in
    the band) can only add. Returns the per-window bounds ``min(rms|z - model|, rms|z|) /
    sqrt(2)``.
    """
    out = []
    tw = np.arange(nw) - 0.5 * (nw - 1)
    for s in range(i0, i1 - nw + 1, nw):
        zw = z[s:s + nw]
        mag = np.abs(zw)
        ca = np.polyfit(tw, np.log(np.maximum(mag, 1e-300)), 1)
        cp = np.polyfit(tw, np.unwrap(np.angle(zw)), 1)
        model = np.exp(np.polyval(ca, tw) + 1j * np.polyval(cp, tw))
        res = float(np.sqrt(np.mean(np.abs(zw - model) ** 2)))
        total = float(np.sqrt(np.mean(mag ** 2)))
        # where noise dominates, the fitted phase line follows the noise's own slow phase
        # and the residual understates it: there the whole content is the bound
        out.append((res if res < 0.3 * total else total) / math.sqrt(2.0))
    return np.array(out)


def _noise_rms(yf, z, fs, span, f_peak):
    """In-band noise RMS of the band-passed record and how it was found (step 6)."""
    i_pk, i0, i1, n_trim, nw = span
    bounds = _residual_noise(z, i0, i1, nw)
    how = []
    noise = float("inf")
    if bounds.size:
        # each window is a noisy upper bound (a few B T samples): the median of the lower half
        low = np.sort(bounds)[:(bounds.size + 1) // 2]
        noise = float(np.median(low))
        how.append(f"residual of the analytic signal about its local decaying-sinusoid model "
                   f"(median of the lower half of {bounds.size} windows): {noise:.3g}")
    pre = yf[n_trim:max(n_trim, i_pk - n_trim)]
    if pre.size >= max(64, 3.0 * fs / f_peak):
        quiet = float(np.sqrt(np.mean(pre ** 2)))
        how.append(f"pre-trigger ({pre.size / fs:.3g} s): {quiet:.3g}")
        noise = min(noise, quiet)
    return noise, "; ".join(how)


def _window_fit(tw, lnA, ph, n_block):
    """Straight lines through ln A and phase: coefficients and their standard errors.

    The lines are fitted to every sample; the standard errors come from the residuals
    averaged over blocks of ``n_block`` samples (about one period): the average removes the
    deterministic ripple of a non-sinusoidal response (harmonics leave a ripple at twice the
    frequency that does not bias the slope) and leaves the noise, whose block means are
    nearly independent.
    """
    X = np.column_stack([np.ones_like(tw), tw])
    nb = max(tw.size // n_block, 3)
    edges = np.linspace(0, tw.size, nb + 1).astype(int)
    tb = np.add.reduceat(tw, edges[:-1]) / np.diff(edges)
    Xb = np.column_stack([np.ones_like(tb), tb])
    Xb_inv = np.linalg.inv(Xb.T @ Xb)
    out = []
    for yv in (lnA, ph):
        coef, *_ = np.linalg.lstsq(X, yv, rcond=None)
        res = np.add.reduceat(yv - X @ coef, edges[:-1]) / np.diff(edges)
        s2 = float(res @ res) / (nb - 2)
        out.append((coef, np.sqrt(np.diag(Xb_inv * s2))))
    return out


def _analytic_signal(yy, fs, lo, hi, order):
    """Zero-phase band-passed signal and its analytic signal.

    Returns ``(sos, yf, z, n_trim, i_pk)``: the filter, the filtered signal, its Hilbert
    transform, the number of samples spoiled by the filter's end effects at each end and the
    index of the largest filtered sample.
    """
    n = yy.size
    sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    yf = signal.sosfiltfilt(sos, yy)
    # zero padding to >= 2n: the FFT-based transform is circular, and without padding the
    # large start of a ring-down would leak into its quiet end. The first and last n_trim
    # samples (cut anyway) are tapered: a record cropped at the impact starts abruptly, and
    # the Hilbert kernel's slow 1/t decay would spread that step over the whole record.
    n_trim = _filter_extent(sos, fs, lo, hi)
    i_pk = int(np.argmax(np.abs(yf)))
    m = min(n_trim, n // 4)
    ramp = 0.5 - 0.5 * np.cos(np.pi * (np.arange(m) + 0.5) / m)
    yt = yf.copy()
    yt[:m] *= ramp
    yt[n - m:] *= ramp[::-1]
    z = signal.hilbert(yt, N=int(2 ** math.ceil(math.log2(2 * n))))[:n]
    return sos, yf, z, n_trim, i_pk


def _curve_warnings(a, stop, floor):
    """Warnings on a finished curve: too few points, or stopped early for a reason other
    than noise."""
    warns = []
    if a.shape[0] < 3:
        warns.append(f"only {a.shape[0]} window(s) above the noise floor; the curve is too "
                     "short to show an amplitude dependence")
    x_last = float(a[-1, 0])
    if stop.startswith("window"):
        warns.append(f"the curve stopped early at {x_last:.3g} m ({x_last / floor:.3g} x the "
                     f"noise floor), not because of noise: {stop}")
    return warns


def amplitude_curve(t, y, *, quantity: str = "acceleration", band, n_periods: float = 20.0,
                    window: float | None = None, order: int = 4, snr_min: float = 10.0,
                    max_damping_std: float = 0.01):
    """Frequency and damping ratio against amplitude from a free-decay record of one mode.

    Band-pass (zero-phase Butterworth, ``scipy.signal.sosfiltfilt``) and Hilbert transform
    (``scipy.signal.hilbert``), straight-line fits of log-envelope and phase in windows; see
    the module docstring for every step.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times [s], strictly increasing and uniform (jitter up to 5 % of the step from
        rounded time stamps is accepted).
    y : array_like, shape (n,)
        Response at the sensor, in SI units of ``quantity``.
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
        What ``y`` is: [m/s^2], [m/s] or [m].
    band : (float, float), keyword-only
        Pass band ``(f_lo, f_hi)`` [Hz] around one mode, inside ``(0, fs/2)``.
    n_periods : float, keyword-only
        Window length in periods of the mode (default 20, range [3, 1000]).
    window : float, optional
        Window length [s]; overrides ``n_periods``.
    order : int, keyword-only
        Butterworth order (default 4, range 1..10); zero-phase doubles it.
    snr_min : float, keyword-only
        The curve stops where the envelope is below ``snr_min`` times the in-band noise RMS
        (default 10, range [2, 1e6]).
    max_damping_std : float, keyword-only
        After at least three points, the curve also stops at the first window whose damping
        ratio has a relative standard uncertainty above this while the noise alone would
        cause that much (default 0.01, range (0, 1]); points before it keep their stated
        uncertainty.

    Returns
    -------
    AmplitudeCurve
        ``amplitude`` [m] (displacement at the sensor), ``frequency`` [Hz] (undamped natural
        frequency ``sqrt(sigma**2 + w_d**2) / 2 pi``), ``damping_ratio`` [-], their standard
        uncertainties, ``noise_floor`` [m] (the displacement amplitude at which the signal would
        be ``snr_min`` times the in-band noise), ``method="hilbert"``; ``notes`` state the
        filter, the trimming, the windows, the noise estimate and where and why the curve
        stopped. Points are in time order (decreasing amplitude).

    Raises
    ------
    ValueError
        Bad input (NaN, non-uniform or non-increasing ``t``, too short a record, a band
        outside the Nyquist range), a band holding no clear mode or more than one, or a
        signal that never rises above ``snr_min`` times the noise.
    """
    yy = check_magnitude("y", finite_array("y", y))
    n = yy.size
    if n < 64:
        raise ValueError(f"y must have at least 64 samples, got {n}")
    tt, dt = _check_uniform_time(t, n)
    fs = 1.0 / dt
    if quantity not in _QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(_QUANTITY_POWER)}, got {quantity!r}")
    k_pow = _QUANTITY_POWER[quantity]
    lo, hi = _check_band(band, fs)
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 10:
        raise ValueError(f"order must be an integer in [1, 10], got {order!r}")
    n_periods = check_scalar("n_periods", n_periods, low=3.0, high=1000.0)
    snr_min = check_scalar("snr_min", snr_min, low=2.0, high=1e6)
    max_damping_std = check_scalar("max_damping_std", max_damping_std, low=0.0, high=1.0,
                                   low_open=True)
    yy = yy - yy.mean()
    f_peak = _check_mode(yy, fs, lo, hi)
    sos, yf, z, n_trim, i_pk = _analytic_signal(yy, fs, lo, hi, int(order))
    env = np.abs(z)
    phase = np.unwrap(np.angle(z))
    i0 = i_pk + n_trim
    i1 = n - n_trim
    if window is not None:
        window = check_scalar("window", window, low=0.0, low_open=True)
        nw = int(round(window * fs))
    else:
        nw = int(round(n_periods * fs / f_peak))
    nw = max(nw, 16)
    if i1 - i0 < nw:
        raise ValueError(f"record too short: after trimming {n_trim / fs:.3g} s of filter end "
                         f"effects at each end, {max(i1 - i0, 0) / fs:.3g} s remain, less than "
                         f"one window ({nw / fs:.3g} s); give a longer record or a wider band")
    noise, how = _noise_rms(yf, z, fs, (i0 - n_trim, i0, i1, n_trim, nw), f_peak)
    noise = max(noise, 1e-7 * float(env.max()))
    bw = _noise_bandwidth(sos, fs)
    rows, stop, x_stop = _windows(tt, env, phase, (i0, i1, nw), (noise, snr_min, bw), k_pow,
                                  f_peak, (lo, hi), max_damping_std)
    if not rows:
        raise ValueError(f"no usable window in band ({lo:g}, {hi:g}) Hz after the trimmed start: "
                         f"{stop}; the signal does not rise above {snr_min:g} x the in-band noise "
                         f"({noise:.3g} in units of y) or holds no decaying mode there")
    a = np.array(rows)
    w_ref = 2 * math.pi * float(a[-1, 1])
    floor = snr_min * noise / w_ref ** k_pow
    x_last = float(a[-1, 0])
    warns = _curve_warnings(a, stop, floor)
    notes = (f"band {lo:g}-{hi:g} Hz, Butterworth order {order} zero-phase (sosfiltfilt); "
             f"mode at {f_peak:.4g} Hz; trimmed {n_trim / fs:.4g} s after the envelope peak "
             f"(t = {tt[i0 - n_trim]:.4g} s) and {n_trim / fs:.4g} s before the end; "
             f"{a.shape[0]} windows of up to {nw / fs:.4g} s; in-band noise RMS {noise:.3g} "
             f"({quantity}) from {how}; noise floor {floor:.3g} m ({snr_min:g} x noise); "
             f"last point at {x_last:.3g} m; stopped: {stop}"
             + (f" (at {x_stop:.3g} m)" if x_stop > 0 else ""))
    log.debug("amplitude_curve: %s", notes)
    return AmplitudeCurve(a[:, 0], a[:, 1], a[:, 2], amplitude_std=a[:, 3],
                          frequency_std=a[:, 4], damping_std=a[:, 5], noise_floor=floor,
                          method="hilbert", notes=notes, warnings=tuple(warns))


def _windows(tt, env, phase, span, noise_spec, k_pow, f_peak, band, max_zstd):
    """Window estimates in time order until the signal meets the noise or stops being a mode.

    Returns the rows ``(X, f, zeta, X_std, f_std, zeta_std)``, why the walk stopped and the
    amplitude of the window that stopped it (0 if none).
    """
    i0, i1, nw = span
    noise, snr_min, bw = noise_spec
    thresh = snr_min * noise
    dt = tt[1] - tt[0]
    # blocks of one period, or of the noise correlation time 1/B if longer
    n_block = max(1, int(round(1.0 / (f_peak * dt))), int(round(1.0 / (bw * dt))))
    rows = []
    s = i0
    while s + nw <= i1:
        n_w = nw
        if np.mean(env[s:s + n_w]) < thresh:
            return rows, f"envelope below the noise threshold at t = {tt[s]:.4g} s", 0.0
        for _ in range(2):       # shorten the window where the envelope falls by > e**0.5
            sl = slice(s, s + n_w)
            tc = tt[s] + 0.5 * (n_w - 1) * dt
            (ca, sa), (cp, sp) = _window_fit(tt[sl] - tc, np.log(env[sl]), phase[sl], n_block)
            sigma, wd = -ca[1], cp[1]
            n_short = max(int(0.5 / (abs(sigma) * dt)), 3 * n_block, 16)
            if n_short >= n_w:
                break
            n_w = n_short
        wn = math.hypot(sigma, wd)
        f, zeta = wn / (2 * math.pi), sigma / wn
        if not (band[0] < f < band[1]) or not (0.0 < zeta < 0.5):
            return rows, (f"window at t = {tc:.4g} s gives f = {f:.4g} Hz, zeta = {zeta:.3g} "
                          "(outside the band or not a decaying mode: beating, forcing or "
                          "noise)"), 0.0
        amp = math.exp(ca[0]) / wn ** k_pow
        f_std = math.hypot(sigma * sa[1], wd * sp[1]) / wn / (2 * math.pi)
        T = n_w * dt           # decay-rate error that the noise alone would cause
        sd_noise = math.sqrt(12.0) * noise / math.exp(ca[0]) / (T * math.sqrt(max(bw * T, 3.0)))
        if len(rows) >= 3 and sa[1] > max_zstd * sigma and sd_noise > max_zstd * sigma:
            return rows, (f"damping ratio known to worse than {100 * max_zstd:g} % at "
                          f"t = {tc:.4g} s (noise)"), amp
        rows.append((amp, f, zeta, amp * sa[0], f_std, sa[1] / wn))
        s += n_w
    return rows, "end of the record (after trimming)", 0.0
