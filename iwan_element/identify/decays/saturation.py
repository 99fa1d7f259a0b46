"""Saturation (clipping) of a measured record: flat tops at its extremes.

A sensor or acquisition channel driven past its range holds its output at the range's limit:
the record then has runs of samples at exactly its largest (or smallest) value, on several
cycles. An unclipped record, sampled or quantised, reaches its extreme at one peak. Every
amplitude above the clip level is lost and the band-passed envelope there is wrong (the
clipped peaks are flattened), so the decay routes (:func:`~iwan_element.amplitude_curve`,
:func:`~iwan_element.fit_decay`) use the record only after its last clipped sample
(:func:`cut_clipping`; both treat the cut as the start of the record, with its filter end
effects) and say so in a warning (docs/guards.md).

Clipping with noise added after it (an amplifier driven past its range ahead of a noisy
stage) has no exactly flat tops. :func:`cut_flattened_peaks` finds it by what it does to the
mode in the analysed band: the record's peaks fall short of the band's own oscillation
(``Re z``, the band-passed analytic signal of :func:`.envelope.analytic_signal`). Per cycle
of ``z`` the deficit ``d = (Re z - y) sign(cos phase)`` is averaged over the samples near
the peaks (``|cos phase| >= 0.975``); for an unclipped record it is the out-of-band content
(other modes) and the noise there, of either sign from cycle to cycle; a clipped cycle falls short
systematically. A cycle
counts as flattened when its mean deficit exceeds 1 % of the envelope and the mean over the
five cycles around it exceeds five of its standard errors (their scatter) and 1 % of the
envelope; the record is cut after the longest
run of cycles from the decay's start in which at least 80 % are flattened (at least two).
A nonlinear joint's own harmonics at the peaks stay far below 1 % of the fundamental in
microslip.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .envelope import analytic_signal

__all__ = ["Clipping", "cut_clipping", "find_clipping", "cut_flattened_peaks"]

#: Relative tolerance [of the record's range] of a sample "at" an extreme value.
TOL = 1e-9
#: Fewest samples at one extreme, in at least two separate runs, that count as clipping.
MIN_SAMPLES = 4


@dataclass(frozen=True)
class Clipping:
    """Where a record is clipped.

    Attributes
    ----------
    n : int
        Samples at a clipped extreme.
    last : int
        Index of the last of them.
    levels : tuple of float
        The clipped extreme value(s), in units of the record.
    """

    n: int
    last: int
    levels: tuple

    def text(self, t) -> str:
        """What a warning says: how many samples, at which level(s), until when (``t`` [s])."""
        lv = " and ".join(f"{v:.4g}" for v in self.levels)
        return (
            f"the record is clipped (saturated): {self.n} samples sit at its extreme "
            f"value(s) {lv} (flat tops) until t = {float(t[self.last]):.4g} s"
        )


def find_clipping(y) -> Clipping | None:
    """The clipping of ``y`` (1-D, finite), or None when it has none: at least
    :data:`MIN_SAMPLES` samples within ``TOL`` of the range of its maximum (or minimum), in at
    least two separate runs.
    """
    y = np.asarray(y, dtype=float)
    span = float(np.ptp(y)) if y.size else 0.0
    if span == 0.0:
        return None
    hits, levels = np.zeros(y.size, bool), []
    for level in (float(y.max()), float(y.min())):
        at = np.abs(y - level) <= TOL * span
        runs = int(np.count_nonzero(np.diff(np.concatenate([[0], at.view(np.int8)])) == 1))
        if at.sum() >= MIN_SAMPLES and runs >= 2:
            hits |= at
            levels.append(level)
    if not levels:
        return None
    idx = np.flatnonzero(hits)
    return Clipping(n=int(idx.size), last=int(idx[-1]), levels=tuple(levels))


def cut_clipping(
    t, y, *, min_samples: int = 64
) -> tuple[NDArray[np.float64], NDArray[np.float64], str]:
    """``(t, y, note)``: the record after its last clipped sample and the warning saying so,
    or the record unchanged and ``""``. ValueError naming ``y`` when fewer than
    ``min_samples`` samples follow the clipping.
    """
    clip = find_clipping(y)
    if clip is None:
        return t, y, ""
    rest = y.size - clip.last - 1
    if rest < min_samples:
        raise ValueError(
            f"y: {clip.text(t)}, and only {rest} samples follow it (at least "
            f"{min_samples} needed); every amplitude measured would be wrong. "
            "Record again with a larger input range (or a softer excitation)"
        )
    note = (
        f"{clip.text(t)}: the record was used from the next sample on, so the results "
        "start below the clip level; record again with a larger input range to measure "
        "the amplitudes above it"
    )
    return t[clip.last + 1 :], y[clip.last + 1 :], note


def _flattened_cycles(y, fs, band):
    """``(flattened, end index, envelope)`` per cycle of the band's oscillation in ``y``
    (module docstring), cycles within three periods of the band's low edge of either end
    of the record left out.
    """
    _, _, z = analytic_signal(y, fs, band)
    phase = np.unwrap(np.angle(z))
    edge = int(3 * fs / band[0])
    if y.size <= 2 * edge + 8:
        return np.zeros(0, bool), np.zeros(0, int), np.zeros(0)
    inner = slice(edge, y.size - edge)
    c = np.cos(phase[inner])
    kk = np.floor((phase[inner] - phase[edge]) / (2 * np.pi)).astype(int)
    near = np.abs(c) >= 0.975
    d = (z.real[inner] - y[inner]) * np.sign(c)
    env = np.abs(z[inner])
    kk -= kk.min()
    idx = np.arange(kk.size)
    cnt = np.bincount(kk[near], minlength=kk.max() + 1)
    dsum = np.bincount(kk[near], weights=d[near], minlength=cnt.size)
    esum = np.bincount(kk, weights=env, minlength=cnt.size)
    nall = np.bincount(kk, minlength=cnt.size)
    last = np.full(cnt.size, -1)
    np.maximum.at(last, kk, idx)
    ok = cnt >= 2
    dm = dsum[ok] / cnt[ok]
    envs = esum[ok] / nall[ok]
    ends = last[ok] + edge
    flat = np.zeros(dm.size, bool)
    for j in range(dm.size):  # five cycles around each: a consistent shortfall
        b = dm[max(0, j - 2) : j + 3]
        se = b.std(ddof=1) / np.sqrt(b.size) if b.size > 2 else np.inf
        flat[j] = b.mean() > max(5 * se, 0.01 * envs[j]) and dm[j] > 0.01 * envs[j]
    return flat, np.array(ends, int), envs


def cut_flattened_peaks(
    t, y, band, *, min_samples: int = 64
) -> tuple[NDArray[np.float64], NDArray[np.float64], str]:
    """``(t, y, note)``: the record after its last clipped cycle when its peaks are
    flattened below the mode in ``band`` [Hz] (clipping under noise, module docstring) and
    the warning saying so, or the record unchanged and ``""``. ValueError naming ``y`` when
    fewer than ``min_samples`` samples follow.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    fs = (t.size - 1) / (t[-1] - t[0])
    flat, ends, envs = _flattened_cycles(y - y.mean(), fs, band)
    if flat.sum() < 2:
        return t, y, ""
    start = int(np.argmax(envs))  # the decay starts at the largest cycle
    share = np.cumsum(flat[start:]) / np.arange(1, flat.size - start + 1)
    run = np.flatnonzero((share >= 0.8) & flat[start:])
    if run.size == 0 or flat[start : start + run[-1] + 1].sum() < 2:
        return t, y, ""
    cut = int(ends[start + run[-1]])
    n_flat = int(flat[start : start + run[-1] + 1].sum())
    rest = y.size - cut - 1
    text = (
        f"the record's peaks are flattened below its {band[0]:g}-{band[1]:g} Hz mode on "
        f"{n_flat} cycles until t = {t[cut]:.4g} s (clipping under noise: the band's "
        "oscillation overshoots the record at its peaks)"
    )
    if rest < min_samples:
        raise ValueError(
            f"y: {text}, and only {rest} samples follow (at least {min_samples} "
            "needed); every amplitude measured would be wrong. Record again with a "
            "larger input range (or a softer excitation)"
        )
    note = (
        f"{text}: the record was used from the next sample on, so the results start "
        "below the clip level; record again with a larger input range to measure the "
        "amplitudes above it"
    )
    return t[cut + 1 :], y[cut + 1 :], note
