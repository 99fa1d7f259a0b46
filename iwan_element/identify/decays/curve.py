"""From a measured free decay to frequency and damping against amplitude.

:func:`amplitude_curve` turns a ring-down record (hammer impact, release test, a simulated
free decay) into an :class:`~iwan_element.identify.modal.curves.AmplitudeCurve`, from about 0.02 %
to 5 % of damping with its defaults. The equations and their sources are in
``docs/free_decay.md``.

1. Band-pass, backwards in time. A Butterworth band-pass (``scipy.signal.butter``, second-order
   sections) is run causally, twice, over the time-reversed decay (``scipy.signal.sosfilt``):
   there the decay is a growing signal that starts in the noise of the record's end, so the
   filter's start-up transient is at the noise level and dies against the mode at the sum of
   the two decay rates, however heavily the mode is damped; a zero-phase filter would ring
   at the decay's abrupt start for as long as a mode damped at a few per cent lasts. The
   output is moved back by the filter's group delay; the record is continued past both ends
   by a least-squares linear predictor before filtering. A linear mode keeps its decay rate
   and frequency through any linear filter; its amplitude is divided by the pass's gain
   ``|H(exp((sigma + i w_d) dt))|**2 exp(sigma tau)`` (1 to first order in the damping).
2. Analytic signal ``z = A exp(i theta)`` (``scipy.signal.hilbert``, zero-padded, of the
   filtered decay continued at both ends by a short predictor: a decay that starts at full
   amplitude is a step, which the transform's ``1/t`` kernel would spread).
3. Trims, measured: at the start, the samples whose output draws on the backward
   continuation (the share of the pass's impulse response that reaches before the decay,
   times the predictor's relative residual) by more than 1e-3; at the end, if the mode still
   rings there, where two continuations (predictors fitted on ten and on six periods) give
   outputs differing by more than 1e-3 of the envelope; at least one period each.
4. Windows that follow the decay (:mod:`._windows`): each spans at most ``span``
   (0.15) nepers of decay and at least three periods (at most ``n_max``, 200 periods); they
   step by the same decay, overlapping where three periods decay by more (heavy damping), so
   the curve has about seven points per neper of decay whatever the damping. ``n_periods``
   or ``window`` fix the length instead (disjoint windows, shortened where they would decay
   by more than ``e**0.5``). In each, straight lines through ``ln A`` and ``theta``: slopes
   ``-sigma`` and ``w_d``; ``w_n = sqrt(sigma**2 + w_d**2)`` (``frequency``), ``zeta = sigma /
   w_n`` and the displacement amplitude at the window centre ``A / w_n**k`` (k = 2, 1, 0 for
   acceleration, velocity, displacement).
5. Per-point uncertainty: the regression standard errors, from the residuals averaged over
   blocks of one period (or of the noise correlation time ``1 / B`` if longer), and never
   below what the in-band noise alone causes: ``(s_n / A) / sqrt(B T)`` for ``ln A`` and
   ``sqrt(12) (s_n / A) / (T sqrt(B T))`` for the slopes (``B T`` independent samples).
6. Noise, from the in-band signal itself (no pre-trigger needed, not fooled by other modes
   outside the band). In consecutive windows after the trimmed start the analytic signal is
   compared with its local free-decay model ``exp(a + b t + i (c + d t))``; ``rms|z -
   model| / sqrt(2)`` bounds the in-band noise RMS ``s`` from above, and where the mode has
   decayed into the noise (residual above 0.3 of ``rms|z|``) the whole in-band content
   ``rms|z| / sqrt(2)`` is the bound. The estimate is the median of the lower half of the
   windows' bounds. When the record has a pre-trigger of at least three periods clear of
   the filter's end effects, the RMS of the band-passed pre-trigger is a direct estimate, and
   the smaller of the two is used. The out-of-band spectral level is not used: on an impact
   test it holds the tails of the other modes.
7. Stop and noise floor: ``noise_floor`` is the displacement amplitude at which the envelope
   would be ``snr_min`` times the in-band noise RMS. The curve runs to the first window
   whose envelope is below that, or to the end of the record; a window that is not a
   decaying mode in the band (beating, forcing) also stops it, with a warning. No point
   above the noise floor is dropped for its uncertainty unless ``max_damping_ratio_std`` is given;
   then the points after the first one (from the fourth on) whose damping is known to worse
   than that are dropped, with a warning that counts them.
8. Warnings when the curve has fewer than 10 points, saying why (record too short, noise,
   the trim) and what to change.
9. A second, independent extraction, ``method="pff"`` (:mod:`.peaks`, peak finding and
   fitting after Jin et al., J. Vib. Acoust. 142(5):051111, 2020) uses only the extrema of
   the filtered decay in the same windows. With ``compare=True`` (the default) the other
   method is run too and the points where the two differ by more than three combined
   standard uncertainties (in frequency or damping) are listed in a warning.

The band must hold one clear mode: a Welch spectrum peak inside it, not at its edges, at
least 10 times the band's median level (or 3 times, if the band-passed envelope decays
tenfold: a heavily damped mode fills a narrow band), with no second peak above a tenth of it.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from scipy import signal

from ...base.plausibility import QUANTITY_POWER, level_failure, record_failure
from ...base.validation import check_magnitude, check_scalar, check_uniform_time, finite_array
from ..modal.curves import DECAY_METHODS
from ._filter import _decay_signal, _drift_terms, _noise_bandwidth
from ._report import _finish
from .saturation import cut_clipping, cut_flattened_peaks
from .windows import WindowPlan, _noise_std, drift_correct, hilbert_windows, pff_windows

if TYPE_CHECKING:
    from ..modal.curves import AmplitudeCurve

__all__ = ["amplitude_curve"]

log = logging.getLogger(__name__)


def _check_band(band, fs):
    try:
        lo, hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"band must be a pair (f_lo, f_hi) in Hz, got {band!r}") from None
    nyq = 0.5 * fs
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi < nyq):
        raise ValueError(
            f"band must satisfy 0 < f_lo < f_hi < Nyquist ({nyq:g} Hz), got ({lo:g}, {hi:g}) Hz"
        )
    return lo, hi


def _decays_in_band(y, fs, lo, hi):
    """Whether the band-passed record's envelope falls tenfold from its peak to the mean of
    its last fifth: a heavily damped mode fills a narrow band, so that its spectral peak is
    only a few times the band's median, but it decays; noise does not.
    """
    sos = signal.butter(2, [lo, hi], btype="bandpass", fs=fs, output="sos")
    env = np.abs(signal.hilbert(signal.sosfiltfilt(sos, y)))
    return bool(env.max() > 10.0 * np.mean(env[-max(env.size // 5, 1) :]))


class _TwoModes(ValueError):
    """The band holds a second peak (retried once on the unwindowed periodogram)."""


def _check_mode(y, fs, lo, hi):
    """Welch spectrum of the record: the frequency of the one clear mode in the band.

    A band that seems to hold two modes is looked at again in one unwindowed periodogram of
    the whole record: a free decay is its own window, while Welch's taper suppresses its
    start, where a heavily damped decay lives, and the tapered remnant can split into
    several peaks (a 10 % damped mode at 80 Hz was refused as "81 and 67 Hz").
    """
    # (zero padding at most 16 times the record: a nonsensical time axis cannot blow it up)
    nfft = int(
        2 ** min(math.ceil(math.log2(fs / ((hi - lo) / 64.0))), math.ceil(math.log2(16 * y.size)))
    )
    nper = int(min(y.size, nfft))
    if (hi - lo) * y.size / fs < 4.0:
        raise ValueError(
            f"band ({lo:g}, {hi:g}) Hz is too narrow for the record length "
            f"({y.size / fs:.3g} s): it is less than 4 / T wide; widen it"
        )
    # a short record (a heavily damped decay) is zero-padded to the same line spacing
    try:
        return _mode_peak(*signal.welch(y, fs=fs, nperseg=nper, nfft=nfft), y, fs, lo, hi)
    except _TwoModes as first:
        try:
            return _mode_peak(
                *signal.periodogram(y, fs=fs, window="boxcar", nfft=max(nfft, y.size)),
                y,
                fs,
                lo,
                hi,
            )
        except _TwoModes:
            raise first from None


def _mode_peak(f, P, y, fs, lo, hi):
    """The one clear spectral peak of ``P`` in the band, or a ValueError saying why not."""
    inb = np.flatnonzero((f >= lo) & (f <= hi))
    if inb.size < 8:
        raise ValueError(
            f"band ({lo:g}, {hi:g}) Hz is too narrow for the record length "
            f"({y.size / fs:.3g} s): it is less than 4 / T wide; widen it"
        )
    Pb = P[inb]
    k = int(np.argmax(Pb))
    med = float(np.median(Pb))
    where = f"in band ({lo:g}, {hi:g}) Hz"
    if k < 2 or k > inb.size - 3:
        raise ValueError(
            f"no clear mode {where}: the strongest content is at its edge "
            f"({f[inb[k]]:.4g} Hz); move or widen the band around one mode"
        )
    if Pb[k] < 10.0 * med and not (Pb[k] > 3.0 * med and _decays_in_band(y, fs, lo, hi)):
        raise ValueError(
            f"no clear mode {where}: the spectral peak at {f[inb[k]]:.4g} Hz is "
            f"only {Pb[k] / max(med, 1e-300):.3g} times the band's median level "
            "(needs 10, or 3 with an envelope that decays tenfold); a heavily "
            "damped mode fills a narrow band (its half-power width is 2 zeta f): "
            "widen the band"
        )
    peaks, _ = signal.find_peaks(Pb, prominence=0.05 * Pb[k])
    others = [int(j) for j in peaks if abs(int(j) - k) > 3 and Pb[j] > 0.1 * Pb[k]]
    if others:
        raise _TwoModes(
            f"band ({lo:g}, {hi:g}) Hz holds more than one mode (peaks at "
            f"{f[inb[k]]:.4g} Hz and {f[inb[others[0]]]:.4g} Hz); narrow it to one"
        )
    return float(f[inb[k]])


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
        zw = z[s : s + nw]
        mag = np.abs(zw)
        ca = np.polyfit(tw, np.log(np.maximum(mag, 1e-300)), 1)
        cp = np.polyfit(tw, np.unwrap(np.angle(zw)), 1)
        model = np.exp(np.polyval(ca, tw) + 1j * np.polyval(cp, tw))
        res = float(np.sqrt(np.mean(np.abs(zw - model) ** 2)))
        total = float(np.sqrt(np.mean(mag**2)))
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
        low = np.sort(bounds)[: (bounds.size + 1) // 2]
        noise = float(np.median(low))
        how.append(
            f"residual of the analytic signal about its local decaying-sinusoid model "
            f"(median of the lower half of {bounds.size} windows): {noise:.3g}"
        )
    pre = yf[n_trim : max(n_trim, i_pk - n_trim)]
    if pre.size >= max(64, 3.0 * fs / f_peak):
        quiet = float(np.sqrt(np.mean(pre**2)))
        how.append(f"pre-trigger ({pre.size / fs:.3g} s): {quiet:.3g}")
        noise = min(noise, quiet)
    return noise, "; ".join(how)


_SPAN = 0.5  # decay across a window [neper]
_HOP = 0.15  # decay between window starts [neper]


def _plan(fs, f_peak, n_periods, window):
    """Window plan: adaptive (default) or a fixed length from ``n_periods`` or ``window``."""
    per = fs / f_peak
    n_min = max(int(round(3 * per)), 16)
    if window is not None:
        n_max, fixed = max(int(round(window * fs)), 16), True
    elif n_periods is not None:
        n_max, fixed = max(int(round(n_periods * per)), 16), True
    else:
        n_max, fixed = max(int(round(200 * per)), n_min), False
    return WindowPlan(
        n_min=min(n_min, n_max),
        n_max=n_max,
        n_half=max(int(round(per / 2)), 1),
        span=_SPAN,
        hop=_HOP,
        fixed=fixed,
    )


def _check_options(quantity, order, n_periods, window, snr_min, max_damping_ratio_std, method):
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 10:
        raise ValueError(f"order must be an integer in [1, 10], got {order!r}")
    if method not in DECAY_METHODS:
        raise ValueError(f"method must be one of {DECAY_METHODS}, got {method!r}")
    if n_periods is not None:
        n_periods = check_scalar("n_periods", n_periods, low=3.0, high=1000.0)
    if window is not None:
        window = check_scalar("window", window, low=0.0, low_open=True)
    snr_min = check_scalar("snr_min", snr_min, low=2.0, high=1e6)
    if max_damping_ratio_std is not None:
        max_damping_ratio_std = check_scalar(
            "max_damping_ratio_std", max_damping_ratio_std, low=0.0, high=1.0, low_open=True
        )
    return n_periods, window, snr_min, max_damping_ratio_std


def _check_length(i0, i1, n_start, n_end, plan, fs):
    """Refuse a record whose trimmed span is shorter than one window."""
    if i1 - i0 < (plan.n_max if plan.fixed else plan.n_min):
        raise ValueError(
            f"record too short: after trimming {n_start / fs:.3g} s of filter end "
            f"effects at the start and {n_end / fs:.3g} s at the end, "
            f"{max(i1 - i0, 0) / fs:.3g} s remain, less than one window "
            f"({(plan.n_max if plan.fixed else plan.n_min) / fs:.3g} s); give a "
            "longer record, a wider band or a shorter window"
        )


def _noise(yf, z, env, sos, fs, f_peak, plan, i_pk, i0, i1, n_start):
    """The in-band noise RMS and how it was found, and the filter's noise bandwidth."""
    # noise windows of 20 periods (at least 10 / B): each bound rests on enough independent
    # samples for the median of the lower half not to undershoot; at least three windows
    bw = _noise_bandwidth(sos, fs)
    nw_noise = int(max(min(max(20 * fs / f_peak, 10 * fs / bw), (i1 - i0) / 3), plan.n_min))
    noise, how = _noise_rms(yf, z, fs, (i_pk, i0, i1, n_start, nw_noise), f_peak)
    noise = max(noise, 1e-7 * float(env[i0:i1].max()))
    return bw, noise, how


def _check_windows(rows, stop, i0, i1, n_start, n_end, fs, band, snr_min, noise):
    """Refuse a record without one usable window, saying why (too short, or no signal)."""
    lo, hi = band
    if not rows and stop.startswith("end"):
        raise ValueError(
            f"record too short: after trimming {n_start / fs:.3g} s of filter end "
            f"effects at the start and {n_end / fs:.3g} s at the end, "
            f"{(i1 - i0) / fs:.3g} s remain, not enough for one window that follows "
            f"the decay (0.5 nepers of it, at least 3 periods, at least half of it "
            "inside the record); give a longer record or a fixed, shorter window "
            "(n_periods)"
        )
    if not rows:
        raise ValueError(
            f"no usable window in band ({lo:g}, {hi:g}) Hz after the trimmed start: "
            f"{stop}; the signal does not rise above {snr_min:g} x the in-band noise "
            f"({noise:.3g} in units of y) or holds no decaying mode there"
        )


def _drift_corrected(tt, yf, rows, wins, method, compare, k_pow, sos, fs, route, noise, bw):
    """The peak-fit windows when asked for, and both estimates corrected for drift."""
    pff = (
        pff_windows(
            tt, yf, wins, (k_pow, sos, fs, route), lambda amp, T: _noise_std(noise, amp, T, bw)
        )
        if (method == "pff" or compare)
        else None
    )

    def terms(w):
        return _drift_terms(sos, fs, w, route[0])

    rows = drift_correct(rows, k_pow, terms)
    if pff is not None:
        pff = drift_correct(pff, k_pow, terms)
    return rows, pff


def amplitude_curve(
    t,
    y,
    *,
    quantity: str = "acceleration",
    band,
    n_periods: float | None = None,
    window: float | None = None,
    order: int = 4,
    snr_min: float = 10.0,
    max_damping_ratio_std: float | None = None,
    method: str = "hilbert",
    compare: bool = True,
) -> AmplitudeCurve:
    """Frequency and damping ratio against amplitude from a free-decay record of one mode.

    Band-pass run backwards in time, Hilbert transform, straight-line fits of log-envelope
    and phase in windows that follow the decay (or peak finding and fitting in the same
    windows); see the module docstring for every step and ``docs/free_decay.md`` for the
    equations.

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
    n_periods : float, optional
        Fixed window length in periods of the mode (range [3, 1000]); by default (None) the
        windows follow the decay: 0.15 nepers of decay each, 3 to 200 periods.
    window : float, optional
        Fixed window length [s]; overrides ``n_periods``.
    order : int, keyword-only
        Butterworth order (default 4, range 1..10); applied twice.
    snr_min : float, keyword-only
        The curve stops where the envelope is below ``snr_min`` times the in-band noise RMS
        (default 10, range [2, 1e6]).
    max_damping_ratio_std : float, optional
        If given (range (0, 1]), the curve also stops at the first point from the fourth on
        whose damping ratio has a relative standard uncertainty above this; the points dropped
        are counted in a warning. By default every point above the noise floor is kept with
        its stated uncertainty.
    method : {"hilbert", "pff"}, keyword-only
        Envelope and phase of the analytic signal (default), or peak finding and fitting on
        the extrema of the filtered decay (:mod:`iwan_element.identify.decays.windows`).
    compare : bool, keyword-only
        Also run the other method in the same windows and warn where the two differ by more
        than three combined standard uncertainties (default True).

    Returns
    -------
    AmplitudeCurve
        ``amplitude`` [m] (displacement at the sensor), ``frequency`` [Hz] (undamped natural
        frequency ``sqrt(sigma**2 + w_d**2) / 2 pi``), ``damping_ratio`` [-], their standard
        uncertainties, ``noise_floor`` [m] (the displacement amplitude at which the signal
        would be ``snr_min`` times the in-band noise), ``method``; ``notes`` state the
        filter, the trims, the windows and their overlap, the noise estimate, the comparison
        and where and why the curve stopped; ``warnings`` what the data could not support.
        Points are in time order (decreasing amplitude). Where windows overlap, neighbouring
        points share data and their errors are correlated.

    Raises
    ------
    ValueError
        Bad input (NaN, non-uniform or non-increasing ``t``, too short a record, a band
        outside the Nyquist range, an unknown option), a band holding no clear mode or more
        than one, or a signal that never rises above ``snr_min`` times the noise.
    """
    yy = check_magnitude("y", finite_array("y", y))
    n = yy.size
    if n < 64:
        raise ValueError(f"y must have at least 64 samples, got {n}")
    tt, dt = check_uniform_time(t, n)
    tt, yy, clip_note = cut_clipping(tt, yy)
    n = yy.size
    fs = 1.0 / dt
    n_periods, window, snr_min, max_damping_ratio_std = _check_options(
        quantity, order, n_periods, window, snr_min, max_damping_ratio_std, method
    )
    k_pow = QUANTITY_POWER[quantity]
    lo, hi = _check_band(band, fs)
    tt, yy, flat_note = cut_flattened_peaks(tt, yy, (lo, hi))
    notes = tuple(x for x in (clip_note, flat_note) if x)
    n = yy.size
    yy = yy - yy.mean()
    f_peak = _check_mode(yy, fs, lo, hi)
    sos, yf, z, (n_start, n_end), i_pk, route = _decay_signal(yy, fs, lo, hi, int(order))
    plan = _plan(fs, f_peak, n_periods, window)
    i0, i1 = i_pk + n_start, n - n_end
    _check_length(i0, i1, n_start, n_end, plan, fs)
    env = np.abs(z)
    phase = np.unwrap(np.angle(z))
    bw, noise, how = _noise(yf, z, env, sos, fs, f_peak, plan, i_pk, i0, i1, n_start)
    n_block = max(1, int(round(fs / f_peak)), int(round(fs / bw)))
    rows, wins, stop, odd_stop = hilbert_windows(
        tt,
        env,
        phase,
        (i0, i1),
        plan,
        (noise, snr_min, bw, n_block),
        (k_pow, (lo, hi), sos, fs, route),
    )
    _check_windows(rows, stop, i0, i1, n_start, n_end, fs, (lo, hi), snr_min, noise)
    rows, pff = _drift_corrected(
        tt, yf, rows, wins, method, compare, k_pow, sos, fs, route, noise, bw
    )
    names = (method, "pff" if method == "hilbert" else "hilbert")
    main, other = (rows, pff) if method == "hilbert" else (pff, rows)
    curve = _finish(
        tt,
        (main, other, wins, names),
        (stop, odd_stop),
        (
            lo,
            hi,
            order,
            f_peak,
            fs,
            n_start,
            n_end,
            i_pk,
            noise,
            how,
            snr_min,
            k_pow,
            route,
            env[i_pk : i_pk + n_start + 1],
        ),
        (max_damping_ratio_std, compare, plan),
    )
    failures = _implausible(yy, dt, curve, quantity) + curve.failures
    return replace(curve, warnings=notes + curve.warnings, failures=failures)


def _implausible(yy, dt, curve, quantity) -> tuple:
    """The record's plausibility (:mod:`iwan_element.base.plausibility`): its own
    derivatives, then the curve's velocity and acceleration; the first failure or ().
    """
    why = record_failure(yy, dt, quantity=quantity, name="y") or level_failure(
        curve.amplitude, curve.frequency, quantity=quantity, name="y"
    )
    return (why,) if why else ()
