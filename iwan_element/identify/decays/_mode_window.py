"""One band of :func:`~iwan_element.free_decay_modes` in one window: the causal band-pass
and decimation with the filter's gain and noise correlation, the automatic window (the
latest stretch with enough signal over each channel's noise floor, steps 2 and 3 of
:mod:`.modes`), the stabilised LS-ESPRIT poles and least-squares amplitudes in it
(:mod:`iwan_element.identify.modal.poles`), the Wald test of each mode, the drift between
the window's halves (the linearity check) and the delta-method uncertainties of frequency,
damping and amplitudes.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from ..modal.poles import fit_sinusoids, stable_poles, subspace_poles

#: Samples per period of a band's upper edge after decimation.
_OVERSAMPLE = 8.0
#: A drift between the window's halves beyond this many standard errors is not linear.
_DRIFT_Z = 3.0


def _band_pass(Y, fs, lo, hi, order):
    """Band-passed, decimated channels; the filter, its decimation and the noise's
    autocorrelation at the decimated lags.
    """
    sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    q = max(1, int(fs // (_OVERSAMPLE * hi)))
    yf = signal.sosfilt(sos, Y, axis=1)
    z = signal.sos2zpk(sos)[1]
    rate = float(np.min(-np.log(np.abs(z)))) * fs  # slowest filter decay [1/s]
    n_h = int(min(max(12.0 / rate * fs, 64), 20 * fs))
    imp = np.zeros(n_h)
    imp[0] = 1.0
    h = signal.sosfilt(sos, imp)
    full = np.correlate(h, h, "full")[n_h - 1 :]
    rho = full[::q] / full[0]
    big = np.flatnonzero(np.abs(rho) > 1e-3)
    rho = rho[: big[-1] + 1] if big.size else rho[:1]
    return yf[:, ::q], q, sos, 8.0 / rate, rho


def _gain(sos, z):
    """Complex gain of the sos filter at the points ``z`` (off the unit circle too)."""
    g = np.ones_like(z, dtype=complex)
    zi = 1.0 / z
    for b0, b1, b2, a0, a1, a2 in sos:
        g *= (b0 + b1 * zi + b2 * zi * zi) / (a0 + a1 * zi + a2 * zi * zi)
    return g


def _fz(s):
    w = np.abs(s)
    return w / (2 * math.pi), -s.real / w


def _block_rms(y, td, i0, n_block):
    """Block centres [s] and rms per channel of consecutive blocks after sample ``i0``."""
    starts = np.arange(i0, y.shape[1] - n_block + 1, n_block)
    E = np.array([np.sqrt(np.mean(y[:, a : a + n_block] ** 2, axis=1)) for a in starts])
    return td[starts] + 0.5 * n_block * (td[1] - td[0]), E.reshape(len(starts), y.shape[0])


def _slope(x, y):
    """Least-squares slope of y on x and its standard error."""
    A = np.column_stack([np.ones_like(x), x - x.mean()])
    coef, res, *_ = np.linalg.lstsq(A, y, rcond=None)
    dof = max(x.size - 2, 1)
    s2 = float(np.sum((y - A @ coef) ** 2)) / dof
    return float(coef[1]), math.sqrt(s2 / max(float(np.sum((x - x.mean()) ** 2)), 1e-300))


def _floors(tc, E):
    """Noise floor of each channel's block rms (NaN where the decay has not reached it): the
    median of the last quarter of the blocks when their log-rms no longer falls at more than
    0.3 times the early rate (or not significantly, 3 standard errors).
    """
    nb = len(tc)
    q = max(nb // 4, 3)
    out = np.full(E.shape[1], np.nan)
    for j in range(E.shape[1]):
        le = np.log(np.maximum(E[:, j], 1e-300))
        r0, _ = _slope(tc[:q], le[:q])
        rt, st = _slope(tc[-q:], le[-q:])
        if not (rt < 0.3 * min(r0, 0.0) and rt < -3.0 * st):
            out[j] = float(np.median(E[-q:, j]))
    return out


def _local_rates(tc, e):
    """Decay rate [1/s] of ``e`` at each block: the slope of ``ln e`` over the last
    ``max(6, b / 4)`` blocks up to block ``b``; NaN where it is not positive by three
    standard errors (no clear decay there).
    """
    le = np.log(np.maximum(e, 1e-300))
    out = np.full(tc.size, np.nan)
    for b in range(tc.size):
        k = max(6, (b + 1) // 4)
        a = max(b + 1 - k, 0)
        if b + 1 - a >= 3:
            r, sr = _slope(tc[a : b + 1], le[a : b + 1])
            if -r > 3.0 * sr:
                out[b] = -r
    return out


def _auto_windows(y, td, i0, lo, hi, snr_min, span, min_periods, n_max=6):
    """Candidate windows ``[(t0, t1, note), ...]``, latest first, by the window rule of the
    module docstring: the band's envelope in blocks; the first ends where the best channel's
    SNR over its noise floor first falls below ``snr_min`` (the record's end if no channel
    reaches its floor), each spans ``span`` nepers of the band's local decay before its end
    (at least ``min_periods`` periods), and each next one ends half a window earlier.
    """
    fc = 0.5 * (lo + hi)
    dt = td[1] - td[0]
    n_block = int(max(5.0 / fc, 1.0 / (hi - lo)) / dt) + 1
    tc, E = _block_rms(y, td, i0, n_block)
    if len(tc) < 6:
        raise _NoWindow(
            f"the decay after the impact holds only {len(tc)} blocks of "
            f"{n_block * dt:.3g} s (6 needed)"
        )
    F = _floors(tc, E)
    with np.errstate(invalid="ignore", divide="ignore"):
        snr = np.sqrt(np.maximum(E**2 / F**2 - 1.0, 0.0))
    snr = np.where(np.isnan(F)[None, :], np.inf, snr)
    best = np.max(snr, axis=1)
    if best[0] < snr_min:
        raise _NoWindow(
            f"the band's SNR is only {best[0]:.3g} (< snr_min = {snr_min:g}) right after the impact"
        )
    bad = np.flatnonzero(best < snr_min)
    last = int(bad[0]) - 1 if bad.size else len(tc) - 1
    if last < 2:
        raise _NoWindow("the band falls into the noise within three blocks of the impact")
    jb = int(np.argmax(np.where(np.isfinite(snr[last]), snr[last], 1e300)))
    sig = np.sqrt(np.maximum(E[:, jb] ** 2 - np.nan_to_num(F[jb]) ** 2, 1e-300))
    rates = _local_rates(tc, sig)
    out = []
    t1 = float(min(tc[last] + 0.5 * n_block * dt, td[-1]))
    why = "end of record" if not bad.size else f"SNR below {snr_min:g} after it"
    while len(out) < n_max and t1 - td[i0] >= min_periods / fc:
        b = min(int(np.searchsorted(tc, t1)), last)
        rate = float(rates[b])
        T = span / rate if rate > 0 else min_periods / fc
        T = min(max(T, min_periods / fc), t1 - td[i0])
        out.append((t1 - T, t1, f"{why}; band decay {rate:.3g} 1/s at its end"))
        t1 -= T
        why = "a later window was not linear"
    if not out:
        raise _NoWindow(f"the decay above the noise is shorter than {min_periods:g} periods")
    return out


class _NoWindow(Exception):
    """A band with no usable decay."""


def _physical(Yw, dtd, lo, hi, max_order, m):
    """Stable poles of the window: (physical in band, nuisance out of band), stable depth."""
    orders = list(range(2, max_order + 1, 2))
    rows = max(int(math.ceil(3 * (max_order + m) / m)), 4)
    if Yw.shape[1] < 3 * rows:
        rows = max(Yw.shape[1] // 3, 2)
        orders = [o for o in orders if o <= rows * m - m] or [2]
    poles = subspace_poles(Yw, dtd, orders, rows=rows)
    stable, _ = stable_poles(poles)
    f, z = _fz(stable) if stable.size else (np.zeros(0), np.zeros(0))
    phys = stable[(f >= lo) & (f <= hi) & (z > 0) & (z < 0.2)]
    nuis = stable[((f < lo) | (f > hi)) & (z > 0) & (z < 0.5)]
    return phys, nuis, len(orders)


def _outputs(s, C, scale, sos, dt, k):
    """f, zeta, Re X, Im X, Re shape, Im shape of one pole (C: weighted amplitudes)."""
    X = C * scale / (_gain(sos, np.array([np.exp(s * dt)]))[0] * s**k)
    th = 0.5 * np.angle(np.sum(X * X))
    v = X * np.exp(-1j * th)
    if v.real[int(np.argmax(np.abs(v.real)))] < 0:
        v = -v
    f, z = _fz(np.array([s]))
    return np.concatenate([[f[0], z[0]], X.real, X.imag, v.real, v.imag])


def _propagate(fit, i, scale, sos, dt, k):
    """Outputs of pole i and their covariance by central differences (delta method)."""
    p, m = fit.C.shape
    idx = np.concatenate(
        [[i, p + i], 2 * p + i * m + np.arange(m), 2 * p + p * m + i * m + np.arange(m)]
    )
    x = fit.params()[idx]
    cov = fit.cov[np.ix_(idx, idx)]

    def g(v):
        return _outputs(v[0] + 1j * v[1], v[2 : 2 + m] + 1j * v[2 + m :], scale, sos, dt, k)

    y0 = g(x)
    h = np.sqrt(np.maximum(np.diag(cov), 0.0)) * 1e-3
    h = np.where(h > 0, h, 1e-9 * np.maximum(np.abs(x), 1e-300))
    Jg = np.empty((y0.size, x.size))
    for j in range(x.size):
        e = np.zeros_like(x)
        e[j] = h[j]
        Jg[:, j] = (g(x + e) - g(x - e)) / (2 * h[j])
    return y0, np.sqrt(np.maximum(np.diag(Jg @ cov @ Jg.T), 0.0))


def _wald(fit, i):
    p, m = fit.C.shape
    idx = np.concatenate([2 * p + i * m + np.arange(m), 2 * p + p * m + i * m + np.arange(m)])
    c = np.concatenate([fit.C[i].real, fit.C[i].imag])
    cov = fit.cov[np.ix_(idx, idx)]
    return float(c @ np.linalg.pinv(cov) @ c)


def _half_drift(tau, Yw, fit, phys_idx, rho):
    """Frequency and damping (with std) of each physical pole on each half of the window."""
    n = tau.size // 2
    out = []
    for sl in (slice(0, n), slice(n, None)):
        tt = tau[sl] - tau[sl][0]
        if tt.size < 8 * fit.s.size + 8:
            return None
        h = fit_sinusoids(tt, Yw[:, sl], fit.s, rho=rho)
        fz = []
        for i in phys_idx:
            f, z = _fz(h.s[i : i + 1])
            p = h.s.size
            cov = h.cov[np.ix_([i, p + i], [i, p + i])]
            w = abs(h.s[i])
            # d f = (sigma dsigma + omega domega) / (2 pi w); d zeta = -(omega^2 dsigma -
            # sigma omega domega) / w^3
            gf = np.array([h.s[i].real, h.s[i].imag]) / (2 * math.pi * w)
            gz = -np.array([h.s[i].imag ** 2, -h.s[i].real * h.s[i].imag]) / w**3
            vf, vz = float(gf @ cov @ gf), float(gz @ cov @ gz)
            if not (h.converged and vf >= 0 and vz >= 0 and math.isfinite(vf + vz)):
                return None  # a half that cannot be fitted: not measured
            fz.append((f[0], math.sqrt(vf), z[0], math.sqrt(vz)))
        out.append(fz)
    return out


def _fit_window(tau, yw, dtd, lo, hi, opts, rho):
    """Stabilisation, least squares, significance: (fit, physical indices, weights, info)."""
    m = yw.shape[0]
    w = np.sqrt(np.mean(yw**2, axis=1))  # first weights: channel rms
    phys, nuis, n_orders = _physical(yw / w[:, None], dtd, lo, hi, opts["max_order"], m)
    if phys.size == 0:
        return None, [], w, (0, 0, n_orders, 0)
    s0 = np.concatenate([phys, nuis])
    fit = fit_sinusoids(tau, yw / w[:, None], s0, rho=rho)
    w = w * np.maximum(fit.rms, 1e-12 * np.max(fit.rms))  # refit weighted by the noise
    fit = fit_sinusoids(tau, yw / w[:, None], fit.s, rho=rho)
    keep = [
        i
        for i in range(phys.size)
        if lo <= _fz(fit.s[i : i + 1])[0][0] <= hi
        and fit.s[i].real < 0
        and _wald(fit, i) >= opts["snr_min"] ** 2
    ]
    dropped = phys.size - len(keep)
    if keep and dropped:  # refit without the spurious poles
        s1 = np.concatenate([fit.s[keep], fit.s[phys.size :]])
        fit = fit_sinusoids(tau, yw / w[:, None], s1, rho=rho)
        keep = list(range(len(keep)))
    return fit, keep, w, (phys.size, nuis.size, n_orders, dropped)


def _try_window(y, td, t0, t1, dtd, lo, hi, opts, rho):
    """The fit of one window, or None when it holds no mode: (times, tau, fit, physical
    indices, weights, counts, halves, linear flag per mode).
    """
    sel = (td >= t0) & (td <= t1)
    if sel.sum() < 32:
        return None
    tw = td[sel]
    tau = tw - tw[0]
    fit, keep, w, counts = _fit_window(tau, y[:, sel], dtd, lo, hi, opts, rho)
    if not keep:
        return None
    halves = _half_drift(tau, y[:, sel] / w[:, None], fit, keep, rho)
    lin = [
        None if halves is None else _linear(halves[0][j], halves[1][j]) for j in range(len(keep))
    ]
    return tw, tau, fit, keep, w, counts, halves, lin


def _linear(a, b):
    """Whether frequency and damping of the two halves agree within _DRIFT_Z std."""
    (f1, sf1, z1, sz1), (f2, sf2, z2, sz2) = a, b
    return bool(
        abs(f2 - f1) <= _DRIFT_Z * math.hypot(sf1, sf2)
        and abs(z2 - z1) <= _DRIFT_Z * math.hypot(sz1, sz2)
    )
