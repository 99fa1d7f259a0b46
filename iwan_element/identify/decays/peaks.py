"""Peak finding and fitting: frequency and damping of a free decay from its extrema.

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

import numpy as np
from scipy import signal

from ._filter import _reverse_gain

__all__ = ["extrema", "pff_windows"]


def extrema(yf, i0, i1):
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
    keep = np.array(keep)
    inside = (pos[keep] >= i0) & (pos[keep] < i1)
    return pos[keep][inside], val[keep][inside]


def _ols(x, y):
    """Straight line ``y = c0 + c1 x``: coefficients and standard errors (residual-based)."""
    X = np.column_stack([np.ones_like(x), x])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    s2 = float(r @ r) / max(x.size - 2, 1)
    return coef, np.sqrt(np.diag(np.linalg.inv(X.T @ X) * s2))


def pff_windows(tt, yf, wins, mode, noise_std):
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
    rows = []
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
