"""Assembly of a free-decay amplitude curve: uncertainties for overlapping windows, the
comparison of the two extractions, and the warnings (too few points, too little precision,
points dropped, an early stop); see :mod:`iwan_element.identify.decays.curve`.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..modal.curves import AmplitudeCurve

log = logging.getLogger("iwan_element.identify.decays.curve")

_MIN_POINTS = 10  # fewer points than this (in the decay's first decade) draw a warning
_F_TARGET, _Z_TARGET = 1e-4, 0.03  # precision below which the curve draws a warning


def _overlap(wins):
    """Per point: its window's length over the spacing of the window centres (>= 1), the
    number of points that share each sample of data.
    """
    if len(wins) < 2:
        return np.ones(len(wins))
    c = np.array([0.5 * (s + e) for s, e in wins])
    step = np.diff(c)
    step = np.concatenate([step, step[-1:]])
    n = np.array([e - s for s, e in wins], dtype=float)
    return np.maximum(n / np.maximum(step, 1.0), 1.0)


def _cut_uncertain(rows, max_zstd):
    """Rows up to the first (from the fourth on) whose damping is known to worse than
    ``max_zstd`` (relative); and how many were dropped.
    """
    for i, r in enumerate(rows):
        if i >= 3 and r[5] > max_zstd * r[2]:
            return rows[:i], len(rows) - i
    return rows, 0


def _few_points_warning(n_pts, stop, usable, trim_np, noise_stop, x_start, hop):
    """Why the curve has fewer than ``_MIN_POINTS`` points in the first decade of the decay,
    and what to change.
    """
    x0, x1 = usable
    nep = math.log(x0 / x1) if x1 > 0 else 0.0
    msg = (
        f"only {n_pts} curve point(s) (fewer than {_MIN_POINTS}) in the first decade of the "
        f"decay (from about {x_start:.3g} m): they run from {x0:.3g} m to {x1:.3g} m "
        f"({nep:.2g} nepers, about {1 / hop:.2g} points per neper)"
    )
    if noise_stop:
        msg += (
            "; it reaches the noise floor there: less noise or a larger initial amplitude "
            "gives more points"
        )
    elif stop.startswith("end"):
        msg += "; the record ends while the mode still rings above the noise: record longer"
    if trim_np > 0.3:
        msg += (
            f"; the filter's end effects cost {trim_np:.2g} nepers at the start: a wider "
            "band or a lower order needs less"
        )
    return msg


def _precision_warning(a):
    """A warning when the stated uncertainty reaches 1e-4 in frequency or 3 % in damping (the
    precision a joint identification needs) over less than a decade of amplitude from the
    curve's first point.
    """
    x = a[:, 0]
    parts = []
    for col, target, name in ((4, _F_TARGET, "frequency"), (5, _Z_TARGET, "damping")):
        rel = a[:, col] / np.abs(a[:, col - 3])
        bad = np.flatnonzero(rel > target)
        x_ok = x[bad[0] - 1] if bad.size and bad[0] > 0 else (None if bad.size else x[-1])
        if x_ok is None or x_ok > 0.1 * x[0]:
            where = (
                "at no point"
                if x_ok is None
                else f"only down to {x_ok:.3g} m ({x_ok / x[0]:.2g} of the first point)"
            )
            parts.append(f"{name} to {target:g} (relative) {where}")
    if not parts:
        return None
    return (
        f"the data (noise, other content in the band) allow {' and '.join(parts)}, less "
        "than a decade of amplitude: less noise, a larger initial amplitude, or longer "
        "windows (n_periods) at the cost of amplitude resolution would help"
    )


def _compare(rows_a, rows_b, names):
    """Points where two extractions differ by more than 3 combined standard uncertainties."""
    bad, n = [], 0
    for ra, rb in zip(rows_a, rows_b):
        if ra is None or rb is None:
            continue
        n += 1
        df = abs(ra[1] - rb[1]) / max(math.hypot(ra[4], rb[4]), 1e-300)
        dz = abs(ra[2] - rb[2]) / max(math.hypot(ra[5], rb[5]), 1e-300)
        if df > 3 or dz > 3:
            bad.append((ra[0], df, dz))
    if not bad:
        return (
            f"{names[1]} check: agrees with {names[0]} within 3 standard uncertainties at "
            f"all {n} points"
        ), None
    where = ", ".join(f"{x:.3g} m (f {df:.1f}, zeta {dz:.1f} sigma)" for x, df, dz in bad[:8])
    more = f" and {len(bad) - 8} more" if len(bad) > 8 else ""
    return (
        f"{names[1]} check: differs at {len(bad)} of {n} points",
        f"the {names[0]} and {names[1]} extractions differ by more than 3 combined standard "
        f"uncertainties at {len(bad)} of {n} points: {where}{more}",
    )


def _kept_rows(main, names, max_zstd):
    """The windows with an estimate, without those too uncertain, and their warnings."""
    keep = [i for i, r in enumerate(main) if r is not None]
    warns = []
    if len(keep) < len(main):
        warns.append(
            f"{len(main) - len(keep)} of {len(main)} windows gave no {names[0]} "
            "estimate (fewer than five extrema or no decaying mode) and were left out"
        )
    if not keep:
        raise ValueError(f"no window gave a {names[0]} estimate; try method='hilbert'")
    rows = [main[i] for i in keep]
    n_drop = 0
    if max_zstd is not None:
        rows, n_drop = _cut_uncertain(rows, max_zstd)
        if n_drop:
            warns.append(
                f"max_damping_ratio_std={max_zstd:g}: {n_drop} point(s) above the noise floor "
                f"were dropped after {rows[-1][0]:.3g} m, their damping known to worse "
                f"than {100 * max_zstd:g} %; leave max_damping_ratio_std unset to keep them "
                "with their uncertainty"
            )
    return keep, rows, warns


def _start_amplitude(a, wins, keep, tt, i_pk, fs, f_peak, env_start, k_pow):
    """The displacement amplitude at the decay's start [m]."""
    # the amplitude at the decay's start, from the first point and its decay rate
    s0, e0 = wins[keep[0]]
    t_c0 = 0.5 * (tt[s0] + tt[e0 - 1])
    x_start = float(a[0, 0] * math.exp(2 * math.pi * a[0, 1] * a[0, 2] * (t_c0 - tt[i_pk])))
    per = int(round(fs / f_peak))  # or the (spoiled) envelope in the first period
    x_start = max(x_start, float(np.max(env_start[:per])) / (2 * math.pi * a[0, 1]) ** k_pow)
    return x_start


def _decay_points(a, x_start, n_start, fs, stop, noise_stop, plan, warns):
    """A warning when the decay's first decade holds fewer than ``_MIN_POINTS`` points."""
    n_dec = int(np.count_nonzero(a[:, 0] >= 0.1 * x_start))
    if n_dec < _MIN_POINTS:
        trim_np = float(n_start / fs * 2 * math.pi * a[0, 1] * a[0, 2])
        warns.append(
            _few_points_warning(
                n_dec,
                stop,
                (a[0, 0], a[n_dec - 1, 0]),
                trim_np,
                noise_stop and n_dec == a.shape[0],
                x_start,
                plan.hop,
            )
        )


def _filter_text(route, fs):
    """How the band-pass ran: zero-phase, or twice backwards in time."""
    return (
        "zero-phase (sosfiltfilt)"
        if route[0]
        else "run twice backwards in time (sosfilt "
        f"on the reversed record, moved back by the group delay, {route[1] / fs:.4g} s)"
    )


def _finish(tt, fits, stops, info, opts):
    """The curve, its notes and its warnings from the window estimates."""
    main, other, wins, names = fits
    stop, odd_stop = stops
    lo, hi, order, f_peak, fs, n_start, n_end, i_pk, noise, how, snr_min, k_pow, route = info[:13]
    env_start = info[13]
    max_zstd, compare, plan = opts
    keep, rows, warns = _kept_rows(main, names, max_zstd)
    a = np.array(rows)
    w_ref = 2 * math.pi * float(a[-1, 1])
    floor = snr_min * noise / w_ref**k_pow
    noise_stop = stop.startswith("envelope") or "of the noise" in stop
    if odd_stop:
        warns.append(
            f"the curve stopped early at {a[-1, 0]:.3g} m ({a[-1, 0] / floor:.3g} x the "
            f"noise floor), not because of noise: {stop}"
        )
    prec = _precision_warning(a)
    if prec:
        warns.append(prec)
    x_start = _start_amplitude(a, wins, keep, tt, i_pk, fs, f_peak, env_start, k_pow)
    _decay_points(a, x_start, n_start, fs, stop, noise_stop, plan, warns)
    share = _overlap([wins[i] for i in keep][: len(rows)])
    overlap = float(np.mean(share))
    cmp_note = ""
    if compare and other is not None:
        cmp_note, cmp_warn = _compare(
            [main[i] for i in keep][: len(rows)], [other[i] for i in keep][: len(rows)], names
        )
        if cmp_warn:
            warns.append(cmp_warn)
    how_f = _filter_text(route, fs)
    notes = (
        f"band {lo:g}-{hi:g} Hz, Butterworth order {order} {how_f}, on the record "
        f"continued past its ends by linear prediction; mode at "
        f"{f_peak:.4g} Hz; decay from t = {tt[i_pk]:.4g} s, trimmed {n_start / fs:.4g} s "
        f"at its start and {n_end / fs:.4g} s before the end (measured end effects); "
        f"{a.shape[0]} windows ({'fixed' if plan.fixed else 'following the decay'}, "
        f"{plan.span:g} nepers each, starting every {plan.hop:g} nepers, "
        f"{plan.n_min / fs:.4g}-{plan.n_max / fs:.4g} s), "
        f"overlap {overlap:.2g} (neighbouring points share data when > 1); method "
        f"{names[0]}; in-band noise RMS {noise:.3g} {('m', 'm/s', 'm/s^2')[k_pow]} from {how}; "
        f"noise floor {floor:.3g} m "
        f"({snr_min:g} x noise); last point at {a[-1, 0]:.3g} m; stopped: {stop}"
        + (f"; {cmp_note}" if cmp_note else "")
    )
    if overlap > 1.05:
        notes += (
            f"; the uncertainties include the factor sqrt(overlap) (mean {overlap:.2g}), so "
            "that a fit treating the points as independent states its own uncertainty "
            "right: one point alone is known better by that factor"
        )
    a[:, 3:6] *= np.sqrt(share)[:, None]
    log.debug("amplitude_curve: %s", notes)
    return AmplitudeCurve(
        a[:, 0],
        a[:, 1],
        a[:, 2],
        amplitude_std=a[:, 3],
        frequency_std=a[:, 4],
        damping_ratio_std=a[:, 5],
        noise_floor=floor,
        method=names[0],
        notes=notes,
        warnings=tuple(warns),
    )
