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
4. In the window (channels weighted by their rms, then by their residual noise): the
   stabilisation diagram of multi-channel LS-ESPRIT over model orders 2 ... ``max_order``; the poles
   of the highest
   order that were stable over its last four orders are physical (in the band, damped below
   20 %) or nuisance (stable, outside the band: another mode's leakage through the
   filter's skirts, kept in the fit so that it biases nothing). Then least squares of all
   of them with every complex amplitude
   (:func:`~iwan_element.identify.modal.poles.fit_sinusoids`); a physical pole whose
   amplitude vector is not significant (Wald statistic below ``snr_min**2``) is dropped
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

from ...base.plausibility import QUANTITY_POWER, level_failure, record_failure
from ...base.validation import check_magnitude, check_scalar, check_uniform_time, finite_array
from ..modal.mode_target import ModeTarget
from ..modal.targets import ModalTargets
from ._mode_window import _auto_windows, _band_pass, _linear, _NoWindow, _propagate, _try_window

__all__ = ["free_decay_modes"]

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------- inputs
def _position(name, p):
    if isinstance(p, (tuple, list, np.ndarray)):
        arr = finite_array(f"records[{name!r}] position", p)
        if not 1 <= arr.size <= 3:
            raise ValueError(
                f"records[{name!r}] position must be a number or 1-3 coordinates "
                f"[m], got {arr.size}"
            )
        return float(arr[0]) if arr.size == 1 else tuple(map(float, arr))
    return check_scalar(f"records[{name!r}] position", p)


def _records(t, records, directions, quantity):
    if not isinstance(records, Mapping) or not records:
        raise ValueError(
            "records must be a non-empty mapping {sensor name: (position [m], record)}"
        )
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
            raise ValueError(
                f"records[{name!r}] must be a pair (position [m], {quantity} record)"
            ) from None
        y = check_magnitude(
            f"records[{name!r}]", finite_array(f"records[{name!r}]", y, min_size=64)
        )
        if n is None:
            n = y.size
        elif y.size != n:
            raise ValueError(
                f"records must all have the same length: records[{name!r}] has "
                f"{y.size} samples, the first has {n}"
            )
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
            raise ValueError(
                f"bands[{label!r}] must satisfy 0 < f_lo < f_hi < 0.8 x Nyquist "
                f"({0.8 * nyq:g} Hz), got ({lo:g}, {hi:g})"
            )
        span = float(t[-1] - t[0])
        if span * lo < 5.0:
            raise ValueError(
                f"t spans {span:.3g} s: fewer than 5 periods of bands[{label!r}]'s "
                f"lower edge ({lo:g} Hz); check the unit of t (ms given as s?) "
                "and the band"
            )
        out[str(label)] = (lo, hi)
    return out


def _auto_bands(Y, fs, duration, *, width=0.08, prominence=10.0):
    """One band of +-``width`` per peak of the channels' summed normalised Welch spectrum
    (segments of about an eighth of the record, Hann) that stands ``prominence`` times above
    its surroundings and above the spectrum's median, between 20 periods over the record
    and 0.35 fs; neighbouring bands are cut at the midpoint between their peaks.
    """
    n = Y.shape[1]
    nper = int(min(n, max(256, 2 ** int(round(math.log2(max(n / 8.0, 1.0)))))))
    f, P = signal.welch(Y, fs=fs, nperseg=nper, axis=1)
    S = np.sum(P / np.median(P, axis=1, keepdims=True), axis=0)
    ok = (f >= 20.0 / duration) & (f <= 0.35 * fs)
    ls = np.log(np.maximum(S, 1e-300))
    floor = float(np.median(ls[ok]))
    ls = np.where(ok, ls, floor)
    idx, _ = signal.find_peaks(
        ls, prominence=math.log(prominence), height=floor + math.log(prominence)
    )
    fp = np.sort(f[idx])
    out = {}
    for k, fk in enumerate(fp):
        lo = fk * (1 - width) if k == 0 else max(fk * (1 - width), 0.5 * (fp[k - 1] + fk))
        hi = fk * (1 + width) if k == fp.size - 1 else min(fk * (1 + width), 0.5 * (fp[k + 1] + fk))
        out[f"{fk:.4g} Hz"] = (lo, hi)
    return out


# ---------------------------------------------------------------------------- one band
def _band(t, dt, Y, label, lo, hi, opts):
    """The modes of one band: list of dicts, a note and warnings."""
    y, q, sos, settle, rho = _band_pass(Y, 1.0 / dt, lo, hi, opts["filter_order"])
    td = t[::q]
    env = np.sqrt(np.sum(y * y, axis=0))
    t_first = td[int(np.argmax(env))] + settle
    i0 = int(np.searchsorted(td, t_first))
    head = f"band {label} ({lo:.4g}-{hi:.4g} Hz)"
    warns = []
    if opts["window"] is None:
        try:
            cands = _auto_windows(
                y, td, i0, lo, hi, opts["snr_min"], opts["span"], opts["min_periods"]
            )
        except _NoWindow as exc:
            return [], f"{head}: no usable decay ({exc})", [f"{head}: no usable decay ({exc})"]
    else:
        cands = [(*opts["window"], "window given")]
        if opts["window"][0] < t_first:
            warns.append(
                f"{head}: the given window starts at {opts['window'][0]:g} s, before "
                f"the band-pass has settled after the impact ({t_first:.4g} s)"
            )
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
            return (
                [],
                f"{head}: no mode",
                [
                    f"{head}: no pole was stable and significant in the window {t0:.4g}-"
                    f"{t1:.4g} s" + (" or in earlier ones" if len(cands) > 1 else "") + ": no mode"
                ],
            )
        res, why = first  # none linear: keep the latest
    tw, tau, fit, keep, w, (n_phys, n_nuis, n_orders, dropped), halves, _ = res
    modes = []
    for j, i in enumerate(keep):
        vals, std = _propagate(fit, i, w, sos, dt, opts["power"])
        mode = _mode_dict(vals, std, Y.shape[0], fit.s[i], tw, label, halves, j)
        mode["snr"] = float(
            np.max(
                np.abs(fit.C[i]) * math.exp(fit.s[i].real * tau[-1]) / np.maximum(fit.rms, 1e-300)
            )
        )
        modes.append(mode)
    note = (
        f"{head}, decimated x{q}: window {tw[0]:.4g}-{tw[-1]:.4g} s ({why}); {n_phys} "
        f"physical and {n_nuis} nuisance pole(s) stable over orders 2-{2 * n_orders}"
        + (f"; {dropped} not significant, dropped" if dropped else "")
    )
    if not fit.converged:
        warns.append(f"{head}: the least-squares fit did not converge")
    for md in modes:
        if md["snr"] < opts["snr_min"] / 3:
            warns.append(
                f"{head}: the mode at {md['frequency']:.5g} Hz ends its window at an "
                f"SNR of only {md['snr']:.2g}"
            )
    return modes, note, warns


def _mode_dict(vals, std, m, s, tw, label, halves, j):
    X = vals[2 : 2 + m] + 1j * vals[2 + m : 2 + 2 * m]
    shape = vals[2 + 2 * m : 2 + 3 * m] + 1j * vals[2 + 3 * m :]
    Xa = float(np.max(np.abs(X)))
    d = {
        "label": label,
        "frequency": vals[0],
        "frequency_std": std[0],
        "damping_ratio": vals[1],
        "damping_ratio_std": std[1],
        "amplitude": X,
        "amplitude_std": np.column_stack([std[2 : 2 + m], std[2 + m : 2 + 2 * m]]),
        "shape": shape,
        "shape_std": np.column_stack([std[2 + 2 * m : 2 + 3 * m], std[2 + 3 * m :]]),
        "t_ref": float(tw[0]),
        "window": (float(tw[0]), float(tw[-1])),
        "amplitude_range": (Xa, Xa * math.exp(s.real * (tw[-1] - tw[0]))),
        "complexity": float(np.linalg.norm(shape.imag) / np.linalg.norm(shape)),
        "method": "LS-ESPRIT stabilisation + least squares",
    }
    # (the end-of-window SNR is added by _band and removed before the ModeTarget is made)
    if halves is not None:
        (f1, sf1, z1, sz1), (f2, sf2, z2, sz2) = halves[0][j], halves[1][j]
        d.update(
            frequency_drift=f2 - f1,
            frequency_drift_std=math.hypot(sf1, sf2),
            damping_drift=z2 - z1,
            damping_drift_std=math.hypot(sz1, sz2),
        )
        d["linear"] = _linear(halves[0][j], halves[1][j])
    return d


# ---------------------------------------------------------------------------- driver
def _options(quantity, window, span, snr_min, max_order, min_periods, filter_order, t):
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    if window is not None:
        try:
            t0, t1 = (float(x) for x in window)
        except (TypeError, ValueError):
            raise ValueError(
                f"window must be None or a pair (t0, t1) in s, got {window!r}"
            ) from None
        if not (math.isfinite(t0) and math.isfinite(t1) and t[0] <= t0 < t1 <= t[-1]):
            raise ValueError(
                f"window must satisfy {t[0]:g} <= t0 < t1 <= {t[-1]:g} s (the "
                f"record), got ({t0:g}, {t1:g})"
            )
        window = (t0, t1)
    if (
        isinstance(max_order, bool)
        or not isinstance(max_order, (int, np.integer))
        or not 8 <= max_order <= 80
        or max_order % 2
    ):
        raise ValueError(f"max_order must be an even integer in [8, 80], got {max_order!r}")
    if (
        isinstance(filter_order, bool)
        or not isinstance(filter_order, (int, np.integer))
        or not 2 <= filter_order <= 8
    ):
        raise ValueError(f"filter_order must be an integer in [2, 8], got {filter_order!r}")
    return {
        "power": QUANTITY_POWER[quantity],
        "window": window,
        "span": check_scalar("span", span, low=0.1, high=5.0),
        "snr_min": check_scalar("snr_min", snr_min, low=2.0, high=1e4),
        "max_order": int(max_order),
        "filter_order": int(filter_order),
        "min_periods": check_scalar("min_periods", min_periods, low=5.0, high=1e4),
    }


def _cross_warnings(modes, envelopes):
    """Warn when another band rang well above its own window's level during a mode's window
    (the joint is then loaded by that mode).
    """
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


def free_decay_modes(
    t,
    records,
    *,
    quantity: str = "acceleration",
    directions=None,
    bands=None,
    window=None,
    span: float = 1.0,
    snr_min: float = 10.0,
    max_order: int = 20,
    min_periods: float = 30.0,
    filter_order: int = 4,
) -> ModalTargets:
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
            y, q, _, _, _ = _band_pass(Y, 1.0 / dt, lo, hi, opts["filter_order"])
            best = int(np.argmax(np.abs(found[0]["amplitude"])))
            env = np.abs(signal.hilbert(y[best]))
            envelopes[label] = (tt[::q], env)
    modes.sort(key=lambda d: d["frequency"])
    for a, b, ratio in _cross_warnings(modes, envelopes):
        warns.append(
            f"the window of the mode at {a['frequency']:.5g} Hz "
            f"({a['window'][0]:.3g}-{a['window'][1]:.3g} s) lies where the mode at "
            f"{b['frequency']:.5g} Hz rings at {ratio:.3g} times the level of its "
            "own window: the joint is loaded by that mode then, so this mode is "
            "linear in its own amplitude only"
        )
    for d in modes:
        if d.get("linear") is False:
            warns.append(
                f"the mode at {d['frequency']:.5g} Hz drifts across its window "
                f"({d['window'][0]:.3g}-{d['window'][1]:.3g} s): frequency "
                f"{d['frequency_drift']:+.3g} Hz (+-{d['frequency_drift_std']:.2g}), "
                f"damping {d['damping_drift']:+.3g} (+-{d['damping_drift_std']:.2g}) "
                "between its halves; not yet linear there, its stderr includes the "
                "drift"
            )
    targets = tuple(
        ModeTarget(
            index=i + 1,
            sensors=tuple(names),
            positions=tuple(pos),
            **{k: v for k, v in d.items() if k != "snr"},
        )
        for i, d in enumerate(modes)
    )
    return ModalTargets(
        modes=targets,
        source="free decay",
        notes=f"{quantity} records of {', '.join(names)}; " + "; ".join(notes),
        warnings=tuple(warns),
        failures=_implausible(Y, dt, names, modes, quantity),
    )


def _implausible(Y, dt, names, modes, quantity) -> tuple:
    """The first record (or, failing that, mode) whose levels no jointed structure's
    vibration test reaches (:mod:`iwan_element.base.plausibility`).
    """
    for name, y in zip(names, Y):
        why = record_failure(y, dt, quantity=quantity, name=f"records[{name!r}]")
        if why:
            return (why,)
    for d in modes:
        X = np.abs(np.asarray(d["amplitude"]))
        why = level_failure(X, np.full(X.shape, d["frequency"]), quantity=quantity, name="records")
        if why:
            return (why,)
    return ()
