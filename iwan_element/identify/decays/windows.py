"""The window estimates of a free decay: Hilbert windows, and peak finding and fitting.

**Hilbert windows.** Windows that follow a free decay, and the Hilbert (envelope and phase)
estimate in each.

Each window spans a bounded decay (``span`` nepers, 0.5: the amplitude changes by at most
``e**0.5`` across it, so that a straight line through ``ln A`` holds and the amplitude at its
centre stands for it), at least ``n_min`` samples (three periods) and at most ``n_max``. The
windows start every ``hop`` nepers of decay (0.15, at least half a period): about seven
points per neper whatever the damping. They overlap (by ``span / hop``, about 3, where the
span rule sets the length): neighbouring points share data and their errors are correlated;
the overlap is stated in the curve's notes.

**Peak finding and fitting.** Frequency and damping of a free decay from its extrema.

A second extraction, independent of the Hilbert transform: it uses only the extrema of the
band-passed decay (the "peak finding and fitting" idea of M. Jin, W. Chen, M. R. W. Brake and
H. Song, "Identification of instantaneous frequency and damping from transient decay data",
J. Vib. Acoust. 142(5):051111, 2020; the implementation here is the project's own, see
``docs/free_decay.md``).

For ``x = A exp(-sigma t) cos(w_d t + phi)`` the extrema fall every half damped period, at
``tan(w_d t + phi) = -sigma / w_d``, with values ``+-A exp(-sigma t_k) w_d / w_n``. So, in a
window holding ``K >= 5`` extrema:

* each extremum's time and value come from the parabola through the three samples around
  it (``scipy.signal.find_peaks`` finds the samples);
* ``w_d = pi / slope`` of the straight line of the extremum times ``t_k`` against their index
  ``k``, ``sigma = -slope`` of ``ln |x_k|`` against ``t_k``, both by least squares with
  their standard errors from the residuals;
* ``w_n = sqrt(sigma**2 + w_d**2)``, ``zeta = sigma / w_n``, and the amplitude at the window
  centre is ``exp(intercept) w_n / w_d``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import signal

from ._filter import _reverse_gain

__all__ = ["WindowPlan", "drift_correct", "extrema", "hilbert_windows", "pff_windows"]


@dataclass(frozen=True)
class WindowPlan:
    """How windows are laid: lengths in samples and the decay per window [neper]."""

    n_min: int
    n_max: int
    n_half: int
    span: float  # decay across a window [neper]
    hop: float  # decay between window starts [neper]
    fixed: bool  # a window length given by the user: fixed, disjoint windows


def _line_fit(tw, yv, n_block):
    """Value and slope at the window centre (``tw`` centred) of ``yv(tw)``, with their standard
    errors: a least-squares parabola, whose curvature takes up a decay rate or frequency that
    changes across the window (on a centred window the linear coefficient is orthogonal to
    it). The errors come from the residuals averaged over blocks of ``n_block`` samples (the
    block means drop the deterministic ripple of harmonics and are nearly independent
    samples of the noise), at least four blocks.
    """
    X = np.column_stack([np.ones_like(tw), tw, tw**2])
    coef, *_ = np.linalg.lstsq(X, yv, rcond=None)
    nb = max(tw.size // n_block, 4)
    edges = np.linspace(0, tw.size, nb + 1).astype(int)
    Xb = np.add.reduceat(X, edges[:-1], axis=0) / np.diff(edges)[:, None]
    res = np.add.reduceat(yv - X @ coef, edges[:-1]) / np.diff(edges)
    s2 = float(res @ res) / (nb - 3)
    return coef[:2], np.sqrt(np.diag(np.linalg.inv(Xb.T @ Xb) * s2))[:2]


def _noise_std(noise, amp, T, bw):
    """Standard errors of intercept and slope of a line through ``ln A`` (or the phase) over
    a window of ``T`` seconds, from in-band noise of RMS ``noise`` on an envelope ``amp``:
    ``noise / amp`` per sample, ``max(B T, 2)`` independent samples.
    """
    n_ind = max(bw * T, 2.0)
    r = noise / amp
    return r / math.sqrt(n_ind), math.sqrt(12.0) * r / (T * math.sqrt(n_ind))


def _fit_window(tt, env, phase, sl, n_block, noise, bw):
    """Line fits of ``ln A`` and phase over ``sl``: (centre, lnA0, sigma, wd, stds)."""
    tc = float(np.mean(tt[sl]))
    tw = tt[sl] - tc
    (ca, sa) = _line_fit(tw, np.log(env[sl]), n_block)
    (cp, sp) = _line_fit(tw, phase[sl], n_block)
    n0, n1 = _noise_std(noise, math.exp(ca[0]), float(tt[sl.stop - 1] - tt[sl.start]), bw)
    sa = np.maximum(sa, [n0, n1])
    sp = np.maximum(sp, [n0, n1])
    return tc, ca[0], -ca[1], cp[1], (sa, sp)


def _window_length(plan, sigma, dt):
    """Window length [samples] for a decay rate ``sigma`` [1/s]."""
    if plan.fixed:
        n = plan.n_max
        if sigma > 0:  # a given window is still shortened where it decays by > e**0.5
            n = min(n, max(int(0.5 / (sigma * dt)), plan.n_min))
        return n
    n = int(plan.span / (sigma * dt)) if sigma > 0 else plan.n_max
    return int(min(max(n, plan.n_min), plan.n_max))


def _hop(plan, sigma, n_w, dt):
    if plan.fixed or sigma <= 0:
        return n_w
    return int(min(n_w, max(plan.hop / (sigma * dt), plan.n_half)))


def hilbert_windows(
    tt, env, phase, span, plan, noise_spec, mode
) -> tuple[list[tuple[float, ...]], list[tuple[int, int]], str, bool]:
    """Window estimates in time order until the signal meets the noise or stops being a mode.

    The windows are laid by their centres, every ``plan.hop`` nepers; near the two ends of
    the usable samples a window is shortened symmetrically about its centre (to no less than
    ``plan.n_min``), so that the curve starts as close to the decay's start as the trim
    allows, with the larger uncertainty of the shorter window (a shortened window keeps at
    least half the full length). A window whose estimate is no decaying mode but within three
    standard errors of one (noise) is skipped. ``span = (i0, i1)`` the
    usable samples; ``noise_spec = (noise, snr_min, bw, n_block)``; ``mode = (k_pow, band,
    sos, fs, route)``. Returns the rows ``(X, f, zeta, X_std, f_std, zeta_std)``, the windows
    ``(start, stop)``, why the walk stopped and, if the stop was not the noise's or the
    record's end, True.
    """
    i0, i1 = span
    noise, snr_min, bw, n_block = noise_spec
    k_pow, band, sos, fs, route = mode
    dt = 1.0 / fs  # the mean step (time stamps may be rounded)
    rows: list[tuple[float, ...]] = []
    wins: list[tuple[int, int]] = []
    # a first decay rate: the time the envelope takes to fall by e from the usable start
    below = np.flatnonzero(env[i0:i1] < env[i0] / math.e)
    sigma = 1.0 / (below[0] * dt) if below.size and below[0] > 0 else 0.0
    # a fixed window (given by the user) is never shortened at the ends: disjoint windows
    # from the trimmed start, as asked
    c = i0 + _window_length(plan, sigma, dt) // (2 if plan.fixed else 4)
    skipped = 0

    def window(sig, c):
        """The window about the centre ``c`` for the decay rate ``sig`` [1/s], or None."""
        n_full = _window_length(plan, sig, dt)
        h = min(n_full // 2, c - i0, i1 - c)
        keep = n_full if plan.fixed else max(plan.n_min, n_full // 2)
        return slice(c - h, c + h) if 2 * h >= keep - 1 else None

    while True:
        sl = window(sigma, c)
        if sl is None:
            if c < i0 + plan.n_max:  # at the start, walk on to a full-enough window
                c += plan.n_half
                if c < i1:
                    continue
            break
        if np.mean(env[sl]) < snr_min * noise:
            return rows, wins, f"envelope below the noise threshold at t = {tt[c]:.4g} s", False
        for _ in range(3):  # the length follows the decay rate found in the window
            tc, ln_a, sigma, wd, (sa, sp) = _fit_window(tt, env, phase, sl, n_block, noise, bw)
            new = window(sigma, c)
            if new is None or abs((new.stop - new.start) - (sl.stop - sl.start)) <= 0.1 * (
                sl.stop - sl.start
            ):
                break
            sl = new
        wn = math.hypot(sigma, wd)
        f, zeta = wn / (2 * math.pi), sigma / wn
        if not (band[0] < f < band[1]) or not (0.0 < zeta < 0.5):
            # within three standard errors of a decaying mode in the band: the noise's doing
            z_sd, f_sd = sa[1] / wn, sp[1] / (2 * math.pi)
            noisy = (zeta + 3 * z_sd > 0) and (band[0] - 3 * f_sd < f < band[1] + 3 * f_sd)
            if noisy:  # no estimate from this one: skip it, counted
                skipped += 1
                sigma = 0.0 if not rows else sigma
                c += plan.n_half if not rows else max(_hop(plan, sigma, sl.stop - sl.start, dt), 1)
                continue
            return (
                rows,
                wins,
                (
                    f"window at t = {tc:.4g} s gives f = {f:.4g} Hz, zeta = "
                    f"{zeta:.3g} (outside the band or not a decaying mode: beating, "
                    "forcing or noise)"
                ),
                True,
            )
        gain = _reverse_gain(sos, fs, sigma, wd, route)
        amp = math.exp(ln_a) / gain / wn**k_pow
        f_std = math.hypot(sigma * sa[1], wd * sp[1]) / wn / (2 * math.pi)
        rows.append((amp, f, zeta, amp * sa[0], f_std, sa[1] / wn))
        wins.append((sl.start, sl.stop))
        n_full = _window_length(plan, sigma, dt)
        if plan.fixed:  # disjoint: the next window starts where this one ends
            c = sl.stop + n_full // 2
        else:
            c += max(_hop(plan, sigma, n_full, dt), 1)
    return (
        rows,
        wins,
        "end of the record (after trimming)"
        + (f"; {skipped} window(s) within the noise of no decay skipped" if skipped else ""),
        False,
    )


def _log_slope(ln_x, ln_w, j, half=1.0):
    """``d ln w / d ln X`` at point ``j``: derivative of the least-squares parabola through the
    points within ``half`` nepers of amplitude of it (a line if fewer than five).
    """
    near = np.flatnonzero(np.abs(ln_x - ln_x[j]) <= half)
    if near.size < 3:
        near = np.arange(max(j - 1, 0), min(j + 2, ln_x.size))
    if near.size < 2 or np.ptp(ln_x[near]) == 0:
        return 0.0
    deg = 2 if near.size >= 5 else 1
    c = np.polyfit(ln_x[near] - ln_x[j], ln_w[near], deg)
    return float(c[-2])


def drift_correct(rows, k_pow, drift_terms) -> list[tuple[float, ...]]:
    """Decay rates corrected for a frequency that drifts with the amplitude.

    Two first-order effects of ``dw/dt = -sigma w (d ln w / d ln X)`` (the curve's own slope,
    from a parabola through the points within a neper): a filter's output for a slowly
    chirping input
    ``a exp(i theta)`` is ``exp(i theta) [a H - i a' H' - (i/2) w' a H'']`` to first order, so
    the envelope of the reversed pass decays at ``sigma (1 + tau_g' w') - g' w'`` with
    ``g' = d ln|H|**2 / dw`` and ``tau_g' = d tau_g / dw`` (``drift_terms(w)`` gives both);
    and velocity or acceleration amplitudes are ``w**k X``, whose logarithm decays at
    ``sigma_X - k w' / w`` and whose phase runs ahead by ``k zeta' = -k sigma d zeta / d ln X``.
    Rows are ``(X, f, zeta,
    X_std, f_std, zeta_std)``; ``None`` rows stay ``None``.
    """
    idx = [i for i, r in enumerate(rows) if r is not None]
    if len(idx) < 2:
        return rows
    r = np.array([rows[i] for i in idx])
    wn = 2 * math.pi * r[:, 1]
    sig = r[:, 2] * wn
    ln_x, ln_w = np.log(r[:, 0]), np.log(wn)
    out = list(rows)
    for j, i in enumerate(idx):
        wd = math.sqrt(max(wn[j] ** 2 - sig[j] ** 2, 0.0))
        w_dot = -sig[j] * wn[j] * _log_slope(ln_x, ln_w, j)
        # the phase of w**k X carries k arg(i w - sigma) = k (pi/2 + zeta): it drifts by k zeta'
        wd += k_pow * sig[j] * _log_slope(ln_x, r[:, 2], j)
        g1, tau1 = drift_terms(wd)
        s_env = (sig[j] + g1 * w_dot) / (1.0 + tau1 * w_dot)
        s_x = s_env + k_pow * w_dot / wn[j]
        w_new = math.hypot(s_x, wd)
        zeta = s_x / w_new
        z_std = rows[i][5] * zeta / max(r[j, 2], 1e-300)
        out[i] = (rows[i][0], w_new / (2 * math.pi), zeta, rows[i][3], rows[i][4], z_std)
    return out


def extrema(yf, i0, i1) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Times (in fractional samples) and values of the extrema of ``yf[i0:i1]``, in order.

    Each is the vertex of the parabola through the three samples around a local maximum of
    ``yf`` or of ``-yf``; only alternating signs are kept (a noise wiggle between two true
    extrema of one sign is dropped in favour of the larger).
    """
    seg = yf[max(i0 - 1, 0) : i1 + 1]
    off = max(i0 - 1, 0)
    idx = np.sort(np.concatenate([signal.find_peaks(seg)[0], signal.find_peaks(-seg)[0]]))
    if idx.size == 0:
        return np.empty(0), np.empty(0)
    ym, y0, yp = seg[idx - 1], seg[idx], seg[idx + 1]
    den = ym - 2.0 * y0 + yp
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(den != 0, 0.5 * (ym - yp) / den, 0.0)
    d = np.clip(d, -0.5, 0.5)
    pos = idx + d + off
    val = y0 - 0.25 * (ym - yp) * d
    keep = [0]
    for j in range(1, pos.size):  # alternate signs: keep the larger of a same-sign run
        if np.sign(val[j]) == np.sign(val[keep[-1]]):
            if abs(val[j]) > abs(val[keep[-1]]):
                keep[-1] = j
        else:
            keep.append(j)
    kept = np.array(keep)
    inside = (pos[kept] >= i0) & (pos[kept] < i1)
    return pos[kept][inside], val[kept][inside]


def _ols(x, y):
    """Straight line ``y = c0 + c1 x``: coefficients and standard errors (residual-based)."""
    X = np.column_stack([np.ones_like(x), x])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    s2 = float(r @ r) / max(x.size - 2, 1)
    return coef, np.sqrt(np.diag(np.linalg.inv(X.T @ X) * s2))


def pff_windows(tt, yf, wins, mode, noise_std) -> list[tuple[float, ...] | None]:
    """Peak-finding-and-fitting estimates in the given windows.

    ``wins`` are ``(start, stop)`` sample ranges, ``mode = (k_pow, sos, fs, route)`` (the
    amplitude is divided by the reversed pass's gain, as the Hilbert estimate's), and
    ``noise_std(amp, T)`` gives the noise-limited standard errors ``(ln A, slope)`` of a
    window, a floor for the residual-based ones. Returns one row ``(X, f, zeta, X_std,
    f_std, zeta_std)`` per window, ``None`` where it holds fewer than five extrema or no
    decaying mode.
    """
    k_pow, sos, fs, route = mode
    dt = 1.0 / fs  # the mean step (time stamps may be rounded)
    pos, val = extrema(yf, wins[0][0], wins[-1][1]) if wins else (np.empty(0), np.empty(0))
    times = tt[0] + pos * dt
    rows: list[tuple[float, ...] | None] = []
    for s, e in wins:
        sel = (pos >= s) & (pos < e)
        if np.count_nonzero(sel) < 5:
            rows.append(None)
            continue
        tk, vk = times[sel], np.abs(val[sel])
        tc = tt[s] + 0.5 * (e - s - 1) * dt
        k = np.arange(tk.size, dtype=float)
        (c_t, s_t) = _ols(k - k.mean(), tk)
        (c_a, s_a) = _ols(tk - tc, np.log(vk))
        wd = math.pi / c_t[1]
        sigma = -c_a[1]
        wn = math.hypot(sigma, wd)
        if not (0.0 < sigma < wn):
            rows.append(None)
            continue
        amp_f = math.exp(c_a[0]) * wn / wd
        n0, n1 = noise_std(amp_f, (e - s) * dt)
        sa0, sa1 = max(s_a[0], n0), max(s_a[1], n1)
        swd = max(wd * s_t[1] / c_t[1], n1)
        amp = amp_f / _reverse_gain(sos, fs, sigma, wd, route) / wn**k_pow
        f_std = math.hypot(sigma * sa1, wd * swd) / wn / (2 * math.pi)
        rows.append((amp, wn / (2 * math.pi), sigma / wn, amp * sa0, f_std, sa1 / wn))
    return rows
