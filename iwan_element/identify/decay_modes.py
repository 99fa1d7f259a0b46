"""Linear modal targets from a multi-sensor free decay (hammer ring-down, no force).

:func:`free_decay_modes` gives, for every mode that rings in the record, its natural
frequency, damping ratio and complex displacement amplitude at every sensor, each with a
standard error, from the part of the decay where that mode is linear: its latest window with
enough signal (``docs/modal_targets.md``).

Per frequency band (given, or one per spectral peak):

1. Causal Butterworth band-pass (``scipy.signal.sosfilt``) of every channel and decimation
   to about eight samples per period of the band's upper edge. A linear filter keeps a
   damped sinusoid ``C exp(s t)`` a damped sinusoid of the same pole, with the complex gain
   ``H(exp(s dt))`` (exact once the filter's start-up transient has died; the window starts
   eight of the filter's slowest time constants after the band's envelope peak); the gain is
   divided out of every amplitude, the same for all sensors, so shapes keep their phases.
2. The band's envelope in blocks (rms per channel); a channel's noise floor is the median of
   its last quarter of blocks when their decay has stopped (else the decay never reaches it).
3. The window: it ends where the best channel's SNR over its floor first falls below
   ``snr_min`` (or at the record's end) and spans ``span`` nepers of the band's local decay
   before that (at least ``min_periods`` periods): the lowest amplitudes that still carry
   enough signal, where a joint's amplitude dependence is weakest. If a mode in it is not
   linear (step 5), the next window, one window length earlier, is tried (up to six) and the
   latest linear one is kept; else the latest, flagged. ``window=(t0, t1)`` overrides it.
4. In the window (channels weighted by their rms, then by their residual noise): the stabilisation diagram of
   multi-channel LS-ESPRIT over model orders 2 ... ``max_order``; the poles of the highest
   order that were stable over its last four orders are physical (in the band, damped below
   20 %) or nuisance (stable, outside the band: another mode's leakage through the
   filter's skirts, kept in the fit so that it biases nothing). Then least squares of all
   of them with every complex amplitude (:func:`._poles.fit_sinusoids`); a physical pole
   whose amplitude vector is not significant (Wald statistic below ``snr_min**2``) is dropped
   with a note.
5. Linearity check: the same fit on each half of the window; the drift of frequency and
   damping between the halves, with its standard error, is reported, and a drift beyond
   three standard errors marks the mode as not linear in its window (its targets'
   ``*_stderr`` then include the drift).
6. Uncertainties: the covariance of the least-squares parameters for the band-passed noise's
   known correlation (the filter's own autocorrelation at the decimated lags), carried to
   frequency, damping, amplitudes and the normalised shape by the delta method (central
   differences). Checked against Monte-Carlo scatter on synthetic decays (tests).

Why not a library: sdypy-EMA (MIT, on the package index) identifies poles from FRFs (LSCF,
LSCE on impulse responses, RFP) and needs the force; it gives no standard errors, picks
poles interactively or nearest to a guess, and has no notion of an amplitude window. SDynPy
(GPL-3.0) cannot be an extra of a BSD package. The free-decay route, its window rule and its
uncertainties are written here.
"""
from __future__ import annotations

import logging
import math
from collections.abc import Mapping

import numpy as np
from scipy import signal

from ..base.validation import check_magnitude, check_scalar, check_uniform_time, finite_array
from ._poles import amplitudes, basis, fit_sinusoids, stable_poles, subspace_poles
from .modal_targets import ModalTargets, ModeTarget

__all__ = ["free_decay_modes"]

log = logging.getLogger(__name__)

_POWER = {"displacement": 0, "velocity": 1, "acceleration": 2}
#: Samples per period of a band's upper edge after decimation.
_OVERSAMPLE = 8.0
#: A drift between the window's halves beyond this many standard errors is not linear.
_DRIFT_Z = 3.0


# ---------------------------------------------------------------------------- inputs
def _position(name, p):
    if isinstance(p, (tuple, list, np.ndarray)):
        arr = finite_array(f"records[{name!r}] position", p)
        if not 1 <= arr.size <= 3:
            raise ValueError(f"records[{name!r}] position must be a number or 1-3 coordinates "
                             f"[m], got {arr.size}")
        return float(arr[0]) if arr.size == 1 else tuple(map(float, arr))
    return check_scalar(f"records[{name!r}] position", p)


def _records(t, records, directions, quantity):
    if not isinstance(records, Mapping) or not records:
        raise ValueError("records must be a non-empty mapping {sensor name: (position [m], "
                         "record)}")
    if directions is not None and not isinstance(directions, Mapping):
        raise ValueError("directions must be a mapping {sensor name: +1 or -1} or None")
    directions = dict(directions or {})
    unknown = set(directions) - set(records)
    if unknown:
        raise ValueError(f"directions names sensors not in records: {sorted(unknown)}")
    names, pos, rows = [], [], []
    n = None
    for name, val in records.items():
        try:
            p, y = val
        except (TypeError, ValueError):
            raise ValueError(f"records[{name!r}] must be a pair (position [m], {quantity} "
                             "record)") from None
        y = check_magnitude(f"records[{name!r}]", finite_array(f"records[{name!r}]", y,
                                                                min_size=64))
        if n is None:
            n = y.size
        elif y.size != n:
            raise ValueError(f"records must all have the same length: records[{name!r}] has "
                             f"{y.size} samples, the first has {n}")
        if float(np.ptp(y)) == 0.0:
            raise ValueError(f"records[{name!r}] is constant: no decay to identify")
        d = directions.get(name, 1)
        if d not in (1, -1):
            raise ValueError(f"directions[{name!r}] must be +1 or -1, got {d!r}")
        names.append(str(name))
        pos.append(_position(name, p))
        rows.append(d * y)
    if len(set(pos)) != len(pos):
        raise ValueError(f"records must be at distinct positions, got {pos}")
    tt, dt = check_uniform_time(t, n, "t", "records")
    return tt, dt, names, pos, np.vstack(rows)


def _bands(bands, fs, Y, t):
    nyq = 0.5 * fs
    if bands is None:
        return _auto_bands(Y, fs, t[-1] - t[0])
    if not isinstance(bands, Mapping) or not bands:
        raise ValueError("bands must be a non-empty mapping {label: (f_lo, f_hi) [Hz]} or None")
    out = {}
    for label, b in bands.items():
        try:
            lo, hi = (float(x) for x in b)
        except (TypeError, ValueError):
            raise ValueError(f"bands[{label!r}] must be a pair (f_lo, f_hi) in Hz") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi < 0.8 * nyq):
            raise ValueError(f"bands[{label!r}] must satisfy 0 < f_lo < f_hi < 0.8 x Nyquist "
                             f"({0.8 * nyq:g} Hz), got ({lo:g}, {hi:g})")
        span = float(t[-1] - t[0])
        if span * lo < 5.0:
            raise ValueError(f"t spans {span:.3g} s: fewer than 5 periods of bands[{label!r}]'s "
                             f"lower edge ({lo:g} Hz); check the unit of t (ms given as s?) "
                             "and the band")
        out[str(label)] = (lo, hi)
    return out


def _auto_bands(Y, fs, duration, *, width=0.08, prominence=10.0):
    """One band of +-``width`` per peak of the channels' summed normalised Welch spectrum
    (segments of about an eighth of the record, Hann) that stands ``prominence`` times above
    its surroundings and above the spectrum's median, between 20 periods over the record
    and 0.35 fs; neighbouring bands are cut at the midpoint between their peaks."""
    n = Y.shape[1]
    nper = int(min(n, max(256, 2 ** int(round(math.log2(max(n / 8.0, 1.0)))))))
    f, P = signal.welch(Y, fs=fs, nperseg=nper, axis=1)
    S = np.sum(P / np.median(P, axis=1, keepdims=True), axis=0)
    ok = (f >= 20.0 / duration) & (f <= 0.35 * fs)
    ls = np.log(np.maximum(S, 1e-300))
    floor = float(np.median(ls[ok]))
    ls = np.where(ok, ls, floor)
    idx, _ = signal.find_peaks(ls, prominence=math.log(prominence),
                               height=floor + math.log(prominence))
    fp = np.sort(f[idx])
    out = {}
    for k, fk in enumerate(fp):
        lo = fk * (1 - width) if k == 0 else max(fk * (1 - width), 0.5 * (fp[k - 1] + fk))
        hi = fk * (1 + width) if k == fp.size - 1 else min(fk * (1 + width),
                                                             0.5 * (fp[k + 1] + fk))
        out[f"{fk:.4g} Hz"] = (lo, hi)
    return out


# ---------------------------------------------------------------------------- one band
def _filter(Y, fs, lo, hi, order):
    """Band-passed, decimated channels; the filter, its decimation and the noise's
    autocorrelation at the decimated lags."""
    sos = signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
    q = max(1, int(fs // (_OVERSAMPLE * hi)))
    yf = signal.sosfilt(sos, Y, axis=1)
    z = signal.sos2zpk(sos)[1]
    rate = float(np.min(-np.log(np.abs(z)))) * fs              # slowest filter decay [1/s]
    n_h = int(min(max(12.0 / rate * fs, 64), 20 * fs))
    imp = np.zeros(n_h)
    imp[0] = 1.0
    h = signal.sosfilt(sos, imp)
    full = np.correlate(h, h, "full")[n_h - 1:]
    rho = full[::q] / full[0]
    big = np.flatnonzero(np.abs(rho) > 1e-3)
    rho = rho[:big[-1] + 1] if big.size else rho[:1]
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
    E = np.array([np.sqrt(np.mean(y[:, a:a + n_block] ** 2, axis=1)) for a in starts])
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
    0.3 times the early rate (or not significantly, 3 standard errors)."""
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
    standard errors (no clear decay there)."""
    le = np.log(np.maximum(e, 1e-300))
    out = np.full(tc.size, np.nan)
    for b in range(tc.size):
        k = max(6, (b + 1) // 4)
        a = max(b + 1 - k, 0)
        if b + 1 - a >= 3:
            r, sr = _slope(tc[a:b + 1], le[a:b + 1])
            if -r > 3.0 * sr:
                out[b] = -r
    return out


def _auto_windows(y, td, i0, lo, hi, snr_min, span, min_periods, n_max=6):
    """Candidate windows ``[(t0, t1, note), ...]``, latest first, by the window rule of the
    module docstring: the band's envelope in blocks; the first ends where the best channel's
    SNR over its noise floor first falls below ``snr_min`` (the record's end if no channel
    reaches its floor), each spans ``span`` nepers of the band's local decay before its end
    (at least ``min_periods`` periods), and each next one ends half a window earlier."""
    fc = 0.5 * (lo + hi)
    dt = td[1] - td[0]
    n_block = int(max(5.0 / fc, 1.0 / (hi - lo)) / dt) + 1
    tc, E = _block_rms(y, td, i0, n_block)
    if len(tc) < 6:
        raise _NoWindow(f"the decay after the impact holds only {len(tc)} blocks of "
                        f"{n_block * dt:.3g} s (6 needed)")
    F = _floors(tc, E)
    with np.errstate(invalid="ignore", divide="ignore"):
        snr = np.sqrt(np.maximum(E ** 2 / F ** 2 - 1.0, 0.0))
    snr = np.where(np.isnan(F)[None, :], np.inf, snr)
    best = np.max(snr, axis=1)
    if best[0] < snr_min:
        raise _NoWindow(f"the band's SNR is only {best[0]:.3g} (< snr_min = {snr_min:g}) "
                        "right after the impact")
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
    X = C * scale / (_gain(sos, np.array([np.exp(s * dt)]))[0] * s ** k)
    th = 0.5 * np.angle(np.sum(X * X))
    v = X * np.exp(-1j * th)
    if v.real[int(np.argmax(np.abs(v.real)))] < 0:
        v = -v
    f, z = _fz(np.array([s]))
    return np.concatenate([[f[0], z[0]], X.real, X.imag, v.real, v.imag])


def _propagate(fit, i, scale, sos, dt, k):
    """Outputs of pole i and their covariance by central differences (delta method)."""
    p, m = fit.C.shape
    idx = np.concatenate([[i, p + i], 2 * p + i * m + np.arange(m),
                          2 * p + p * m + i * m + np.arange(m)])
    x = fit.params()[idx]
    cov = fit.cov[np.ix_(idx, idx)]

    def g(v):
        return _outputs(v[0] + 1j * v[1], v[2:2 + m] + 1j * v[2 + m:], scale, sos, dt, k)

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
            f, z = _fz(h.s[i:i + 1])
            p = h.s.size
            cov = h.cov[np.ix_([i, p + i], [i, p + i])]
            w = abs(h.s[i])
            # d f = (sigma dsigma + omega domega) / (2 pi w); d zeta = -(omega^2 dsigma -
            # sigma omega domega) / w^3
            gf = np.array([h.s[i].real, h.s[i].imag]) / (2 * math.pi * w)
            gz = -np.array([h.s[i].imag ** 2, -h.s[i].real * h.s[i].imag]) / w ** 3
            vf, vz = float(gf @ cov @ gf), float(gz @ cov @ gz)
            if not (h.converged and vf >= 0 and vz >= 0 and math.isfinite(vf + vz)):
                return None                     # a half that cannot be fitted: not measured
            fz.append((f[0], math.sqrt(vf), z[0], math.sqrt(vz)))
        out.append(fz)
    return out


def _fit_window(tau, yw, dtd, lo, hi, opts, rho):
    """Stabilisation, least squares, significance: (fit, physical indices, weights, info)."""
    m = yw.shape[0]
    w = np.sqrt(np.mean(yw ** 2, axis=1))               # first weights: channel rms
    phys, nuis, n_orders = _physical(yw / w[:, None], dtd, lo, hi, opts["max_order"], m)
    if phys.size == 0:
        return None, [], w, (0, 0, n_orders, 0)
    s0 = np.concatenate([phys, nuis])
    fit = fit_sinusoids(tau, yw / w[:, None], s0, rho=rho)
    w = w * np.maximum(fit.rms, 1e-12 * np.max(fit.rms))     # refit weighted by the noise
    fit = fit_sinusoids(tau, yw / w[:, None], fit.s, rho=rho)
    keep = [i for i in range(phys.size) if lo <= _fz(fit.s[i:i + 1])[0][0] <= hi
            and fit.s[i].real < 0 and _wald(fit, i) >= opts["snr_min"] ** 2]
    dropped = phys.size - len(keep)
    if keep and dropped:                                # refit without the spurious poles
        s1 = np.concatenate([fit.s[keep], fit.s[phys.size:]])
        fit = fit_sinusoids(tau, yw / w[:, None], s1, rho=rho)
        keep = list(range(len(keep)))
    return fit, keep, w, (phys.size, nuis.size, n_orders, dropped)


def _try_window(y, td, t0, t1, dtd, lo, hi, opts, rho):
    """The fit of one window, or None when it holds no mode: (times, tau, fit, physical
    indices, weights, counts, halves, linear flag per mode)."""
    sel = (td >= t0) & (td <= t1)
    if sel.sum() < 32:
        return None
    tw = td[sel]
    tau = tw - tw[0]
    fit, keep, w, counts = _fit_window(tau, y[:, sel], dtd, lo, hi, opts, rho)
    if not keep:
        return None
    halves = _half_drift(tau, y[:, sel] / w[:, None], fit, keep, rho)
    lin = [None if halves is None else _linear(halves[0][j], halves[1][j])
           for j in range(len(keep))]
    return tw, tau, fit, keep, w, counts, halves, lin


def _linear(a, b):
    """Whether frequency and damping of the two halves agree within _DRIFT_Z std."""
    (f1, sf1, z1, sz1), (f2, sf2, z2, sz2) = a, b
    return bool(abs(f2 - f1) <= _DRIFT_Z * math.hypot(sf1, sf2)
                and abs(z2 - z1) <= _DRIFT_Z * math.hypot(sz1, sz2))


def _band(t, dt, Y, label, lo, hi, opts):
    """The modes of one band: list of dicts, a note and warnings."""
    y, q, sos, settle, rho = _filter(Y, 1.0 / dt, lo, hi, opts["filter_order"])
    td = t[::q]
    env = np.sqrt(np.sum(y * y, axis=0))
    t_first = td[int(np.argmax(env))] + settle
    i0 = int(np.searchsorted(td, t_first))
    head = f"band {label} ({lo:.4g}-{hi:.4g} Hz)"
    warns = []
    if opts["window"] is None:
        try:
            cands = _auto_windows(y, td, i0, lo, hi, opts["snr_min"], opts["span"],
                                  opts["min_periods"])
        except _NoWindow as exc:
            return [], f"{head}: no usable decay ({exc})", [f"{head}: no usable decay ({exc})"]
    else:
        cands = [(*opts["window"], "window given")]
        if opts["window"][0] < t_first:
            warns.append(f"{head}: the given window starts at {opts['window'][0]:g} s, before "
                         f"the band-pass has settled after the impact ({t_first:.4g} s)")
    first = None
    for t0, t1, why in cands:
        res = _try_window(y, td, t0, t1, q * dt, lo, hi, opts, rho)
        if res is None:
            continue
        first = first or (res, why)
        if all(h is not None and h for h in res[-1]):
            break
    else:
        if first is None:
            t0, t1 = cands[0][:2]
            return [], f"{head}: no mode", [
                f"{head}: no pole was stable and significant in the window {t0:.4g}-"
                f"{t1:.4g} s" + (" or in earlier ones" if len(cands) > 1 else "")
                + ": no mode"]
        res, why = first                         # none linear: keep the latest
    tw, tau, fit, keep, w, (n_phys, n_nuis, n_orders, dropped), halves, _ = res
    modes = []
    for j, i in enumerate(keep):
        vals, std = _propagate(fit, i, w, sos, dt, opts["power"])
        mode = _mode_dict(vals, std, Y.shape[0], fit.s[i], tw, label, halves, j)
        mode["snr"] = float(np.max(np.abs(fit.C[i]) * math.exp(fit.s[i].real * tau[-1])
                                   / np.maximum(fit.rms, 1e-300)))
        modes.append(mode)
    note = (f"{head}, decimated x{q}: window {tw[0]:.4g}-{tw[-1]:.4g} s ({why}); {n_phys} "
            f"physical and {n_nuis} nuisance pole(s) stable over orders 2-{2 * n_orders}"
            + (f"; {dropped} not significant, dropped" if dropped else ""))
    if not fit.converged:
        warns.append(f"{head}: the least-squares fit did not converge")
    for md in modes:
        if md["snr"] < opts["snr_min"] / 3:
            warns.append(f"{head}: the mode at {md['frequency']:.5g} Hz ends its window at an "
                         f"SNR of only {md['snr']:.2g}")
    return modes, note, warns


def _mode_dict(vals, std, m, s, tw, label, halves, j):
    X = vals[2:2 + m] + 1j * vals[2 + m:2 + 2 * m]
    shape = vals[2 + 2 * m:2 + 3 * m] + 1j * vals[2 + 3 * m:]
    Xa = float(np.max(np.abs(X)))
    d = {"label": label, "frequency": vals[0], "frequency_std": std[0],
         "damping_ratio": vals[1], "damping_ratio_std": std[1], "amplitude": X,
         "amplitude_std": np.column_stack([std[2:2 + m], std[2 + m:2 + 2 * m]]),
         "shape": shape, "shape_std": np.column_stack([std[2 + 2 * m:2 + 3 * m],
                                                       std[2 + 3 * m:]]),
         "t_ref": float(tw[0]), "window": (float(tw[0]), float(tw[-1])),
         "amplitude_range": (Xa, Xa * math.exp(s.real * (tw[-1] - tw[0]))),
         "complexity": float(np.linalg.norm(shape.imag) / np.linalg.norm(shape)),
         "method": "LS-ESPRIT stabilisation + least squares"}
    # (the end-of-window SNR is added by _band and removed before the ModeTarget is made)
    if halves is not None:
        (f1, sf1, z1, sz1), (f2, sf2, z2, sz2) = halves[0][j], halves[1][j]
        d.update(frequency_drift=f2 - f1, frequency_drift_std=math.hypot(sf1, sf2),
                 damping_drift=z2 - z1, damping_drift_std=math.hypot(sz1, sz2))
        d["linear"] = _linear(halves[0][j], halves[1][j])
    return d


# ---------------------------------------------------------------------------- driver
def _options(quantity, window, span, snr_min, max_order, min_periods, filter_order, t):
    if quantity not in _POWER:
        raise ValueError(f"quantity must be one of {sorted(_POWER)}, got {quantity!r}")
    if window is not None:
        try:
            t0, t1 = (float(x) for x in window)
        except (TypeError, ValueError):
            raise ValueError(f"window must be None or a pair (t0, t1) in s, got "
                             f"{window!r}") from None
        if not (math.isfinite(t0) and math.isfinite(t1) and t[0] <= t0 < t1 <= t[-1]):
            raise ValueError(f"window must satisfy {t[0]:g} <= t0 < t1 <= {t[-1]:g} s (the "
                             f"record), got ({t0:g}, {t1:g})")
        window = (t0, t1)
    if isinstance(max_order, bool) or not isinstance(max_order, (int, np.integer)) \
            or not 8 <= max_order <= 80 or max_order % 2:
        raise ValueError(f"max_order must be an even integer in [8, 80], got {max_order!r}")
    if isinstance(filter_order, bool) or not isinstance(filter_order, (int, np.integer)) \
            or not 2 <= filter_order <= 8:
        raise ValueError(f"filter_order must be an integer in [2, 8], got {filter_order!r}")
    return {"power": _POWER[quantity], "window": window,
            "span": check_scalar("span", span, low=0.1, high=5.0),
            "snr_min": check_scalar("snr_min", snr_min, low=2.0, high=1e4),
            "max_order": int(max_order), "filter_order": int(filter_order),
            "min_periods": check_scalar("min_periods", min_periods, low=5.0, high=1e4)}


def _cross_warnings(modes, envelopes):
    """Warn when another band rang well above its own window's level during a mode's window
    (the joint is then loaded by that mode)."""
    warns = []
    for a in modes:
        tc = 0.5 * (a["window"][0] + a["window"][1])
        worst = None
        for b in modes:
            if b["label"] == a["label"]:
                continue
            td, env = envelopes[b["label"]]
            own = np.interp(0.5 * (b["window"][0] + b["window"][1]), td, env)
            ratio = float(np.interp(tc, td, env) / max(own, 1e-300))
            if worst is None or ratio > worst[0]:
                worst = (ratio, b)
        if worst is not None and worst[0] > 3.0:
            warns.append((a, worst[1], worst[0]))
    return warns


def free_decay_modes(t, records, *, quantity: str = "acceleration", directions=None,
                     bands=None, window=None, span: float = 1.0, snr_min: float = 10.0,
                     max_order: int = 20, min_periods: float = 30.0,
                     filter_order: int = 4) -> ModalTargets:
    """Natural frequencies, damping ratios and shapes from a multi-sensor free decay.

    The linear targets of a ring-down without measured force (a hammer impact), each from
    the latest window of its band with enough signal (module docstring;
    ``docs/modal_targets.md``).

    Parameters
    ----------
    t : array_like, shape (n,)
        Time [s], uniformly sampled; the record may start before the impact.
    records : mapping
        ``{sensor name: (position, record)}``: position [m] along the structure (a number,
        or up to three coordinates), record the sensor's signal, shape (n,), in SI units of
        ``quantity``. At least 64 samples; positions distinct.
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
        What the records are; amplitudes are returned as displacement (``X = C / s**k``).
    directions : mapping, optional, keyword-only
        ``{sensor name: +1 or -1}``: -1 for a sensor whose measuring axis points against the
        common axis of the shapes (an accelerometer on the opposite face); default +1.
    bands : mapping, optional, keyword-only
        ``{label: (f_lo, f_hi)}`` [Hz], each with one or a few modes; default one band of
        +-8 % around each peak of the channels' summed, normalised Welch spectrum standing
        ten times above its surroundings.
    window : (t0, t1), optional, keyword-only
        The window [s] for every band; default the window rule (module docstring).
    span : float, keyword-only
        Decay across the automatic window [neper], default 1 (amplitude falls by e);
        range [0.1, 5].
    snr_min : float, keyword-only
        Smallest block SNR (rms in-band signal over in-band noise, best channel) that ends
        the automatic window; a mode's amplitude must also have a Wald statistic of at
        least ``snr_min**2``. Default 10, range [2, 1e4].
    max_order : int, keyword-only
        Highest model order of the stabilisation diagram (even, 8-80, default 20).
    min_periods : float, keyword-only
        Shortest automatic window [periods of the band centre], default 30.
    filter_order : int, keyword-only
        Butterworth band-pass order, 2-8 (default 4).

    Returns
    -------
    ModalTargets
        ``source="free decay"``; per mode frequency, damping, complex displacement
        amplitude at every sensor at the window's start ``t_ref`` with a common phase, the
        shape turned to be nearly real, the window, the amplitude range and the drift
        between the window's halves; modes indexed by ascending frequency.

    Raises
    ------
    ValueError
        Malformed ``t``, ``records``, ``directions``, ``bands``, ``window`` or options; the
        message names the argument.
    """
    tt, dt, names, pos, Y = _records(t, records, directions, quantity)
    opts = _options(quantity, window, span, snr_min, max_order, min_periods, filter_order, tt)
    band_map = _bands(bands, 1.0 / dt, Y, tt)
    modes, notes, warns, envelopes = [], [], [], {}
    for label, (lo, hi) in band_map.items():
        found, note, w = _band(tt, dt, Y, label, lo, hi, opts)
        log.debug("%s", note)
        modes += found
        notes.append(note)
        warns += w
        if found:
            y, q, _, _, _ = _filter(Y, 1.0 / dt, lo, hi, opts["filter_order"])
            best = int(np.argmax(np.abs(found[0]["amplitude"])))
            env = np.abs(signal.hilbert(y[best]))
            envelopes[label] = (tt[::q], env)
    modes.sort(key=lambda d: d["frequency"])
    for a, b, ratio in _cross_warnings(modes, envelopes):
        warns.append(f"the window of the mode at {a['frequency']:.5g} Hz "
                     f"({a['window'][0]:.3g}-{a['window'][1]:.3g} s) lies where the mode at "
                     f"{b['frequency']:.5g} Hz rings at {ratio:.3g} times the level of its "
                     "own window: the joint is loaded by that mode then, so this mode is "
                     "linear in its own amplitude only")
    for d in modes:
        if d.get("linear") is False:
            warns.append(f"the mode at {d['frequency']:.5g} Hz drifts across its window "
                         f"({d['window'][0]:.3g}-{d['window'][1]:.3g} s): frequency "
                         f"{d['frequency_drift']:+.3g} Hz (+-{d['frequency_drift_std']:.2g}), "
                         f"damping {d['damping_drift']:+.3g} (+-{d['damping_drift_std']:.2g}) "
                         "between its halves; not yet linear there, its stderr includes the "
                         "drift")
    targets = tuple(ModeTarget(index=i + 1, sensors=tuple(names), positions=tuple(pos),
                               **{k: v for k, v in d.items() if k != "snr"})
                    for i, d in enumerate(modes))
    return ModalTargets(modes=targets, source="free decay",
                        notes=f"{quantity} records of {', '.join(names)}; " + "; ".join(notes),
                        warnings=tuple(warns))
