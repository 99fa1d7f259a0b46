"""Band-pass and analytic signal of a free decay, with the filter's end effects measured.

:func:`_analytic_signal` is the zero-phase route (``scipy.signal.sosfiltfilt`` and a Hilbert
transform, the first and last ``n_trim`` samples spoiled). A zero-phase filter started
abruptly on a ringing record rings itself, at the rate of its least damped pole: when the
mode decays nearly as fast (a few per cent of damping against a band of +-15 %), that
transient never becomes small against the mode and no trim removes it.

:func:`_decay_signal` is the route :func:`~iwan_element.amplitude_curve` uses: the filter
runs causally over the time-reversed record, where the decay is a growing signal starting
in the record's quiet end; see its docstring and ``docs/free_decay.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from .envelope import _filter_extent, _hilbert, _ramp_ends, analytic_signal

_TRIM_LEVEL = 1e-3  # end-effect error allowed, relative to the mode's local envelope
_ZERO_PHASE_RATIO = 0.3  # zero-phase if the mode decays at < 0.3 x the filter's ringing rate


def _noise_bandwidth(sos, fs):
    """Noise bandwidth [Hz] of the zero-phase filter (``sosfiltfilt`` applies ``|H|**2``)."""
    w, H = signal.sosfreqz(sos, worN=8192, fs=fs)
    return float(np.trapezoid(np.abs(H) ** 4, w))


def _lp_fit(seg, p):
    """Least-squares forward predictor ``x[n] = sum_k c_k x[n - k]`` of order ``p`` over
    ``seg`` (the covariance method of linear prediction, S. M. Kay, *Modern Spectral
    Estimation*, 1988; singular values below 1e-7 of the largest dropped).
    """
    m = seg.size
    A = np.column_stack([seg[p - k : m - k] for k in range(1, p + 1)])
    c, *_ = np.linalg.lstsq(A, seg[p:], rcond=1e-7)
    return c


def _lp_extend(seg, c, n_pad, growth=1e3):
    """Continue ``seg`` past its end by at most ``n_pad`` samples with the predictor ``c``
    (``scipy.signal.lfilter`` with zero input and ``lfiltic`` initial conditions), cut where it
    would exceed ``growth`` times the segment's largest value.
    """
    p = c.size
    a_poly = np.concatenate([[1.0], -c])
    zi = signal.lfiltic([1.0], a_poly, seg[::-1][:p])
    ext, _ = signal.lfilter([1.0], a_poly, np.zeros(n_pad), zi=zi)
    big = np.flatnonzero(~(np.abs(ext) < growth * np.max(np.abs(seg))))
    return ext[: big[0]] if big.size else ext


def _taper_far_end(ext):
    """Half-Hann ramp over the far half of a continuation (it starts at the record)."""
    m = ext.size // 2
    out = ext.copy()
    if m:
        out[ext.size - m :] *= 0.5 + 0.5 * np.cos(np.pi * (np.arange(m) + 0.5) / m)
    return out


def _reversed_filter(sos, x):
    """The band-pass run causally twice over the time-reversed record (``|H|**2``, as the
    zero-phase filter), reversed back.
    """
    return signal.sosfilt(np.vstack([sos, sos]), x[::-1])[::-1]


def _group_delay(sos, fs, f):
    """Group delay [s] of ``sos`` applied twice, at ``f`` [Hz]."""
    w, h = signal.sosfreqz(sos, worN=np.array([0.999, 1.001]) * f, fs=fs)
    ph = np.unwrap(2.0 * np.angle(h))
    return float(-(ph[1] - ph[0]) / (2 * math.pi * (w[1] - w[0])))


def _continued_pass(sos, decay, p, m, pads, zero_phase):
    """Continue ``decay`` at both ends (predictor of order ``p`` on ``m`` samples; forwards it
    may not grow, backwards by at most 1e3) and filter it: zero-phase (``sosfiltfilt``) or
    backwards in time. Returns the output, the index of the decay's first sample in it and
    the predictor's one-step residual RMS relative to the RMS of the first ``m`` samples.
    """
    n_head, n_tail = pads
    first = decay[:m][::-1]
    c = _lp_fit(first, p)
    A = np.column_stack([first[p - k : m - k] for k in range(1, p + 1)])
    eps = float(np.sqrt(np.mean((first[p:] - A @ c) ** 2) / max(np.mean(first**2), 1e-300)))
    head = _taper_far_end(_lp_extend(first, c, n_head))
    tail = _taper_far_end(_lp_extend(decay[-m:], _lp_fit(decay[-m:], p), n_tail, growth=1.0))
    x = np.concatenate([head[::-1], decay, tail])
    out = signal.sosfiltfilt(sos, x) if zero_phase else _reversed_filter(sos, x)
    return out, head.size, eps


def _filter_decay_rate(sos, fs):
    """Decay rate [1/s] of the filter's least damped pole (how long it rings)."""
    _, poles, _ = signal.sos2zpk(sos)
    return float(-math.log(np.max(np.abs(poles))) * fs)


def _envelope_decay_rate(yz, fs):
    """Rough decay rate [1/s] of a band-passed decay: one over the time its envelope takes
    to fall by e from its peak (0 if it never does).
    """
    env = np.abs(_hilbert(yz))
    j = int(np.argmax(env))
    below = np.flatnonzero(env[j:] < env[j] / math.e)
    return fs / below[0] if below.size else 0.0


def _head_weight(sos, n):
    """Share of the reversed pass's impulse response (``|h|``, ``sos`` twice) beyond each lag:
    ``W[u] = sum_{v < u} |h[v]| / sum |h|``.
    """
    imp = np.zeros(n)
    imp[0] = 1.0
    h = np.abs(signal.sosfilt(np.vstack([sos, sos]), imp))
    return np.concatenate([[0.0], np.cumsum(h)[:-1]]) / h.sum()


def _decay_signal(yy, fs, lo, hi, order):
    """Band-passed decay and its analytic signal, on the record continued past its ends.

    The decay (from ``i_pk``) is continued past both ends by least-squares linear
    prediction, the continuations tapered at their far ends, so that the filter meets no step
    at the decay's start or at the record's end. Two routes:

    * zero-phase (``scipy.signal.sosfiltfilt``), allowed where the filter's ringing dies well
      within the mode's decay (its least damped pole decays more than ``1 / 0.3`` times faster
      than the mode's envelope), and taken if it spoils the start no more than the other
      route: then what remains of the end effects is the continuation's error;
    * otherwise backwards in time: run causally over the reversed record (twice: ``|H|**2``,
      as the zero-phase filter), the filter meets the decay as a growing signal that starts
      in the quiet end of the record: its start-up transient is at the noise level and dies
      against the growing mode at the sum of the two decay rates, however heavily the mode
      is damped. A mode ``Re(c exp(s t))`` comes out as ``Re(c G exp(s t))`` with a constant
      complex gain: decay rate and frequency are kept, ``|G| = exp(-sigma tau_g)`` to first
      order, the envelope a group delay ``tau_g`` later; the output is moved back by
      ``tau_g`` (at the band's centre).

    Returns ``(sos, yf, z, (n_start, n_end), i_pk, (zero_phase, shift))``: as
    :func:`_analytic_signal`, with the trims at the decay's start and at the record's end
    apart (at least one period each), the route and the shift [samples]. Zero-phase, a trim
    is where two continuations (predictors fitted on ten and on six periods) give outputs
    differing by more than 1e-3 of the envelope. Backwards, at the start the output at
    sample ``j`` draws the share ``W[shift - j]`` of its input from the backward
    continuation (:func:`_head_weight`), good to the predictor's relative one-step residual
    ``eps``: the start trim keeps ``eps W`` below 1e-3; the end trim is the two-continuation
    one. The end is trimmed only if the mode still rings there.
    """
    sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    ay = np.abs(yy)
    yz = signal.sosfiltfilt(sos, yy)
    i_pk = int(min(np.argmax(np.abs(yz)), np.argmax(ay >= 0.5 * ay.max())))
    n_ext = _filter_extent(sos, fs, lo, hi)
    f_c = math.sqrt(lo * hi)
    # zero-phase allowed where the filter's ringing dies well within the mode's decay; then
    # the route whose start is spoiled less (zero-phase on a tie: it has no delay to undo)
    back = _route(yy, yz, sos, (fs, f_c, n_ext, i_pk), False)
    if _envelope_decay_rate(yz[i_pk:], fs) < _ZERO_PHASE_RATIO * _filter_decay_rate(sos, fs):
        zero = _route(yy, yz, sos, (fs, f_c, n_ext, i_pk), True)
        if zero[2][0] <= back[2][0]:
            return (sos,) + zero[:3] + (i_pk,) + zero[3:]
    return (sos,) + back[:3] + (i_pk,) + back[3:]


def _route(yy, yz, sos, spec, zero_phase):
    """One filtering route of :func:`_decay_signal`: ``(yf, z, (n_start, n_end), (zero_phase,
    shift))``.
    """
    fs, f_c, n_ext, i_pk = spec
    n = yy.size
    per = fs / f_c
    sh = 0 if zero_phase else int(round(_group_delay(sos, fs, f_c) * fs))
    decay = yy[i_pk:]
    nd = decay.size
    yf = yz.copy()
    z = np.empty(n, dtype=complex)
    if i_pk > 0:
        z[:i_pk] = _hilbert(yz[:i_pk])
    p = int(min(max(round(0.8 * per), 12), 64, max(nd // 8, 2)))
    m = int(min(nd // 2, max(10 * p, round(10 * per))))
    pads = (sh + n_ext, n_ext)
    outs = []
    n_l = int(round(5 * per))  # output kept (and tapered) beyond the decay's ends
    for mm in (m, max(int(0.6 * m), 4 * p)):
        out, h, eps = _continued_pass(sos, decay, p, mm, pads, zero_phase)
        j0 = h - sh  # output index of the decay's first sample
        a, b = max(j0 - n_l, 0), min(j0 + nd + n_l, out.size)
        zz = _hilbert(_ramp_ends(out[a:b], n_l, b - (j0 + nd)))
        got = zz[j0 - a : j0 - a + nd] if j0 >= 0 else zz[: nd + j0]
        outs.append(np.concatenate([np.full(nd - got.size, np.nan + 0j), got]))
        if len(outs) == 1:
            eps_a, short = eps, j0 < n_l
    za, zb = outs
    yf[i_pk:] = np.nan_to_num(za.real)  # (NaN: before a cut continuation, trimmed)
    z[i_pk:] = np.nan_to_num(za)
    # start: the output at sample j draws the share W[sh - j] of its input from before the
    # decay (the backward continuation); with the continuation good to the predictor's
    # residual, the error is about eps W[sh - j]
    env = np.abs(za)
    rel = np.abs(za - zb) / np.maximum(env, 1e-300)
    k = min(n_ext + sh, nd // 2)
    if zero_phase:  # both ends draw on the continuations: where two of them differ
        bad = np.flatnonzero(~(rel[:k] <= _TRIM_LEVEL))
    else:
        W = _head_weight(sos, sh + 1)
        j = np.arange(min(sh + 1, nd))
        bad = np.flatnonzero(max(eps_a, 1e-4) * W[sh - j] > _TRIM_LEVEL)
    n_trim = int(bad[-1]) + 1 if bad.size else 0
    if short:  # the continuation was cut (it grew by 1e3): no output before it
        n_trim = max(n_trim, n_l - j0)
    # end: where two continuations (ten and six periods of fit) differ, if it still rings
    n_end = 0
    if np.nanmean(env[-min(n_ext, k) :]) > 0.01 * np.nanmax(env):
        above = np.flatnonzero(~(rel[nd - k :][::-1] <= _TRIM_LEVEL))
        n_end = int(above[-1]) + 1 if above.size else 0
    one = int(round(per))
    return yf, z, (max(n_trim, one), max(n_end, one)), (zero_phase, sh)


def _sos_response(sos, zz):
    """``H(z)`` of second-order sections at a complex ``z``."""
    g = 1.0 + 0j
    for b0, b1, b2, a0, a1, a2 in sos:
        g *= (b0 + b1 / zz + b2 / zz**2) / (a0 + a1 / zz + a2 / zz**2)
    return g


def _reverse_gain(sos, fs, sigma, wd, route):
    """Envelope gain of the filtering for a mode decaying at ``sigma`` [1/s] with damped
    angular frequency ``wd`` [rad/s], divided out of the amplitude (1 to first order in
    ``sigma``). ``route = (zero_phase, shift)``. Backwards: ``|H(z)|**2 exp(sigma shift dt)``
    at ``z = exp((sigma + i wd) dt)`` (the reversed record grows at ``sigma``); zero-phase:
    ``|H(z) H(1/z)|`` at ``z = exp((-sigma + i wd) dt)``.
    """
    zero_phase, shift = route
    if zero_phase:
        zz = complex(
            math.exp(-sigma / fs) * math.cos(wd / fs), math.exp(-sigma / fs) * math.sin(wd / fs)
        )
        return abs(_sos_response(sos, zz) * _sos_response(sos, 1.0 / zz))
    zz = complex(math.exp(sigma / fs) * math.cos(wd / fs), math.exp(sigma / fs) * math.sin(wd / fs))
    return abs(_sos_response(sos, zz)) ** 2 * math.exp(sigma * shift / fs)


def _analytic_signal(yy, fs, lo, hi, order):
    """Zero-phase band-passed signal and its analytic signal
    (:func:`.envelope.analytic_signal`, the ends tapered over the filter's end effects and
    the transform zero-padded).

    Returns ``(sos, yf, z, n_trim, i_pk)``: the filter, the filtered signal, its Hilbert
    transform, the number of samples spoiled by the filter's end effects at each end and the
    index of the largest filtered sample.
    """
    # zero padding to >= 2n: the FFT-based transform is circular, and without padding the
    # large start of a ring-down would leak into its quiet end. The first and last n_trim
    # samples (cut anyway) are tapered: a record cropped at the impact starts abruptly, and
    # the Hilbert kernel's slow 1/t decay would spread that step over the whole record.
    sos, yf, z = analytic_signal(yy, fs, (lo, hi), order=order, taper_ends=True, pad=True)
    n_trim = _filter_extent(sos, fs, lo, hi)
    i_pk = int(np.argmax(np.abs(yf)))
    return sos, yf, z, n_trim, i_pk


def _drift_terms(sos, fs, w, zero_phase=False):
    """``(g', tau')`` of ``sos`` applied twice at ``w`` [rad/s]: the slopes of the log-gain
    ``ln|H|**2`` [s] and of the group delay [s**2] against angular frequency (0 for the
    zero-phase route, which has no delay).
    """
    f = w / (2 * math.pi)
    h = 1e-3 * f
    _, H = signal.sosfreqz(sos, worN=np.array([f - h, f, f + h]), fs=fs)
    ph = np.unwrap(2.0 * np.angle(H))
    lg = 2.0 * np.log(np.abs(H))
    dw = 2 * math.pi * h
    tau1 = 0.0 if zero_phase else float(-(ph[2] - 2 * ph[1] + ph[0]) / dw**2)
    return float((lg[2] - lg[0]) / (2 * dw)), tau1
