"""The record prepared for :func:`iwan_element.identify.decays.fit.fit_decay`.

The checks of the record and the options, the start of the free decay, the local
decaying-sinusoid fits in consecutive windows (the data summary of the result and the start
values of the fit), the start values of the modal Iwan curves from those window
estimates (:func:`iwan_element.fit_modal_iwan`; Segalman 2005, J. Appl. Mech. 72:752-760)
and those of the out-of-band modes that leak into the band (:func:`_neighbours`).
The equations are in the project's ``docs/decay_fit.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from ...base.plausibility import QUANTITY_POWER
from ...base.validation import check_magnitude, check_scalar, check_uniform_time, finite_array
from ..modal.fit import fit_modal_iwan
from ._fit_model import _polar, _Problem
from .curve import _check_band
from .saturation import cut_clipping, cut_flattened_peaks


def _windows(prob, i_a, i_b, nw):
    """Local decaying-sinusoid fits in consecutive windows of ``nw`` samples.

    Returns rows ``(i_centre, envelope, sigma, w_d, phase, rms|z - local model|, rms|z|)``
    at the window centres (start values, noise and the data summary of the result; the fit
    itself does not use them).
    """
    rows = []
    tw = (np.arange(nw) - 0.5 * (nw - 1)) / prob.fs
    for s in range(i_a, i_b - nw + 1, nw):
        zw = prob.z[s : s + nw]
        lnA, ph = _polar(zw)
        ca = np.polyfit(tw, lnA, 1)
        cp = np.polyfit(tw, ph, 1)
        res = np.abs(zw - np.exp(np.polyval(ca, tw) + 1j * np.polyval(cp, tw)))
        rows.append(
            (
                s + 0.5 * (nw - 1),
                math.exp(ca[1]),
                -ca[0],
                cp[0],
                cp[1],
                float(np.sqrt(np.mean(res**2))),
                float(np.sqrt(np.mean(np.abs(zw) ** 2))),
            )
        )
    return np.array(rows).reshape(-1, 7)


def _summary(prob, rows):
    """Window estimates as a curve: displacement amplitude [m], frequency [Hz], zeta."""
    wn = np.hypot(rows[:, 2], rows[:, 3])
    ok = (rows[:, 2] > 0) & (wn > 2 * math.pi * prob.band[0]) & (wn < 2 * math.pi * prob.band[1])
    return rows[ok, 1] / wn[ok] ** prob.k, wn[ok] / (2 * math.pi), rows[ok, 2] / wn[ok]


def _starts(X, f, zeta, conv):
    """Curve start values from the modal Iwan fit of the window estimates (microslip ones,
    and the full vector when that fit leaves microslip) and a near-linear mode.
    """
    starts, full = [], None
    if X.size >= 4 and np.unique(np.round(np.log(X), 6)).size >= 3:
        try:
            fit = fit_modal_iwan(
                X,
                f,
                np.maximum(zeta, 1e-7),
                stiffness=conv["stiffness"],
                floor=conv["floor"],
                x_ref=conv["x_ref"],
                damping_form="decay",
            )
            p = fit.parameters
            if fit.regime == "microslip":
                starts.append(np.array(fit.values, dtype=float))
            elif fit.regime == "macroslip":
                full = np.array(fit.values, dtype=float)
                delta = (
                    p["kappa"]
                    * (conv["x_ref"] / p["phi_max"]) ** (p["chi"] + 1)
                    / ((p["chi"] + 2) * (1 + p["beta"]))
                )
                starts.append(np.array([p["f0"], p["zeta0"], p["chi"], min(delta, 0.5)]))
        except ValueError:
            pass
    zmin = float(np.min(zeta)) if zeta.size else 1e-3
    for x in starts:  # keep chi off the corner chi -> -1 where f0 and delta trade
        x[2] = min(max(x[2], -0.8), 0.8)
    starts.append(
        np.array(
            [
                float(np.max(f)) * 1.00001,
                0.8 * max(zmin, 1e-6),
                -0.5,
                max(1.0 - (np.median(f) / np.max(f)) ** 2, 1e-6),
            ]
        )
    )
    return starts, full


def _decay_start(prob, t_start, t0):
    """Working-rate index of the start of the free decay: given, else the first sample above
    0.3 of the record's largest magnitude (an impact or a release), taken as the record's
    start when it is within the first period (a release, or a record cropped in the decay,
    whose first samples may be near a zero crossing).
    """
    if t_start is not None:
        t_end = t0 + (prob.n - 1) / prob.fs
        t_start = check_scalar("t_start", t_start, low=t0, high=t_end)
        return int(round((t_start - t0) * prob.fs))
    mag = np.abs(prob.y)
    i_on = int(np.argmax(mag > 0.3 * mag.max()))
    period = prob.fs / math.sqrt(prob.band[0] * prob.band[1])
    return 0 if i_on <= period else i_on


def _check_options(quantity, order, stiffness, floor):
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or not 1 <= order <= 10:
        raise ValueError(f"order must be an integer in [1, 10], got {order!r}")
    if stiffness not in ("harmonic", "secant"):
        raise ValueError(f"stiffness must be 'harmonic' or 'secant', got {stiffness!r}")
    if floor not in ("dashpot", "constant"):
        raise ValueError(f"floor must be 'dashpot' or 'constant', got {floor!r}")


def _prepare(t, y, quantity, band, order, stiffness, floor, x_ref, t_start):
    """Checks, analytic signal, start of the decay, first span and start values."""
    yy = check_magnitude("y", finite_array("y", y))
    if yy.size < 64:
        raise ValueError(f"y must have at least 64 samples, got {yy.size}")
    tt, dt = check_uniform_time(t, yy.size)
    check_magnitude("t", tt, unit="s")
    tt, yy, clip_note = cut_clipping(tt, yy)
    _check_options(quantity, order, stiffness, floor)
    lo, hi = _check_band(band, 1.0 / dt)
    if hi * dt < 1e-5:
        raise ValueError(
            f"band ({lo:g}, {hi:g}) Hz is below 1e-5 of the sampling rate "
            f"{1.0 / dt:.3g} Hz (from t): check the unit of t"
        )
    tt, yy, flat_note = cut_flattened_peaks(tt, yy, (lo, hi))
    clip_note = " ".join(x for x in (clip_note, flat_note) if x)
    conv = dict(
        stiffness=stiffness,
        floor=floor,
        x_ref=None,
        damping_form="decay",
        method="direct signal fit",
        quantity=quantity,
        band=[lo, hi],
        order=int(order),
    )
    prob = _Problem(yy - yy.mean(), 1.0 / dt, (lo, hi), int(order), QUANTITY_POWER[quantity], conv)
    fs = prob.fs
    i_s = prob.i_s = _decay_start(prob, t_start, float(tt[0]))
    nw = max(16, int(round(2.0 * fs / math.sqrt(lo * hi))))  # two periods
    env = np.convolve(np.abs(prob.z), np.ones(nw) / nw, mode="same")
    i_top = i_s + int(np.argmax(env[i_s:]))  # the filter spreads the start
    low = np.flatnonzero(env[i_top:] < 0.05 * env[i_top])
    i_a = prob.n if low.size == 0 else i_top + int(low[0])
    X, f, zeta, rows = _window_curve(prob, i_s, i_a, nw)
    if X.size == 0 or i_a - i_s < nw:
        raise ValueError(
            f"no decaying mode in band ({lo:g}, {hi:g}) Hz after "
            f"t = {tt[0] + i_s / fs:.4g} s (record too short or no clear mode)"
        )
    conv["x_ref"] = (
        float(np.exp(np.mean(np.log(X))))
        if x_ref is None
        else check_scalar("x_ref", x_ref, low=0.0, low_open=True)
    )
    m = prob.n_trim
    first = rows[0] if rows[0, 0] > m or i_s >= m else rows[int(np.argmax(rows[:, 1]))]
    wn = math.hypot(first[2], first[3])
    tc = (first[0] - i_s) / fs
    nuis = [
        math.log(first[1] / wn**prob.k) + max(first[2], 0.0) * tc,
        first[4] - first[3] * tc - prob.k * math.asin(min(max(first[2] / wn, 0.0), 0.5)),
    ]
    prob.nb_starts = _neighbours(prob, i_s)
    prob.nb = len(prob.nb_starts)
    nuis = [v for nb in prob.nb_starts for v in nb] + nuis
    return (
        prob,
        conv,
        dict(
            clip_note=clip_note,
            t0=float(tt[0]),
            i_s=i_s,
            i_top=i_top,
            i_a=i_a,
            env=env,
            nw=nw,
            nuis=nuis,
            data=(X, f, zeta),
        ),
    )


def _window_curve(prob, i_s, i_b, nw):
    """Window estimates over ``[i_s, i_b)``, clear of the filter's end effects
    where possible (the fit itself models it): start values and the plot's data.
    """
    m = prob.n_trim
    a, b = (
        (max(i_s, m), min(i_b, prob.n - m))
        if min(i_b, prob.n - m) - max(i_s, m) >= 2 * nw
        else (i_s, i_b)
    )
    rows = _windows(prob, a, b, max(nw, (b - a) // 16))  # at most 16 windows
    return (*_summary(prob, rows), rows)


def _neighbours(prob, i_s, max_modes=2):
    """Out-of-band modes that leak into the band: start values ``[f, sigma, c, s]`` of each.

    Peaks of the record's amplitude spectrum (from the start of the decay) outside the band,
    at least 10 times the median out-of-band level (the noise), the one with the strongest
    steady leak (spectrum times ``|H|**2``) on each side, if that leak is above 1e-3 of the
    noise level: a mode that starts abruptly with the decay leaks far more through the
    band-pass at the start than its steady ``|H|**2`` says (a 16 % neighbour with a steady
    leak below the noise biased the joint parameters by 30 standard errors). Each is a linear
    decaying sinusoid: frequency and decay rate from straight lines through the phase and
    log-envelope of its own narrow band's analytic signal (clear of
    that filter's end effects), amplitudes by linear least squares on the record.
    """
    lo, hi = prob.band
    seg = prob.y[i_s:]
    n = seg.size
    if n < 64:
        return []
    nfft = int(2 ** math.ceil(math.log2(4 * n)))
    f = np.fft.rfftfreq(nfft, 1.0 / prob.fs)
    Y = np.abs(np.fft.rfft(seg * signal.windows.hann(n), nfft))
    _, H = signal.sosfreqz(prob.sos, worN=f, fs=prob.fs)
    H2 = np.abs(H) ** 2
    out_band = ((f < lo) | (f > hi)) & (f > 0.25 * lo) & (f < 0.45 * prob.fs)
    if not np.any(out_band):
        return []
    floor = float(np.median(Y[out_band]))
    pk, _ = signal.find_peaks(Y)
    pk = pk[out_band[pk] & (Y[pk] > 10.0 * floor) & (Y[pk] * H2[pk] > 1e-3 * floor)]
    starts = []
    t = np.arange(n) / prob.fs
    for side in (pk[f[pk] < lo], pk[f[pk] > hi]):
        if side.size == 0:
            continue
        j = side[np.argmax(Y[side] * H2[side])]
        est = _neighbour_start(prob, seg, t, float(f[j]))
        if est is not None:
            starts.append(est)
    return starts[:max_modes]


def _neighbour_start(prob, seg, t, f2):
    """Frequency, decay rate and amplitudes of a linear mode near ``f2`` [Hz] in ``seg``."""
    lo, hi = prob.band
    gap = (lo - f2) if f2 < lo else (f2 - hi)
    d = min(0.5 * gap, 0.1 * f2)
    if d <= 0.0 or f2 + d >= 0.5 * prob.fs:
        return None
    sos = signal.butter(2, [f2 - d, f2 + d], btype="bandpass", fs=prob.fs, output="sos")
    z = signal.hilbert(signal.sosfiltfilt(sos, seg), N=int(2 ** math.ceil(math.log2(2 * seg.size))))
    z = z[: seg.size]
    m = int(math.ceil(3.0 * prob.fs / d))  # a few of its filter's time constants
    if seg.size - 2 * m < 16:
        m = seg.size // 4
    sl = slice(m, seg.size - m)
    lnA, ph = _polar(z[sl])
    w = np.abs(z[sl]) ** 2
    cs = np.polyfit(t[sl], lnA, 1, w=np.sqrt(w))
    cp = np.polyfit(t[sl], ph, 1, w=np.sqrt(w))
    fr, sig = cp[0] / (2.0 * math.pi), max(-cs[0], 0.0)
    if not (f2 - d < fr < f2 + d):
        return None
    env = np.exp(-sig * t)
    A = np.column_stack([env * np.cos(2 * math.pi * fr * t), env * np.sin(2 * math.pi * fr * t)])
    coef, *_ = np.linalg.lstsq(A, seg, rcond=None)
    return np.array([fr, sig, coef[0] / prob.scale, coef[1] / prob.scale])
