"""Saturation (clipping) of a measured record: flat tops at its extremes.

A sensor or acquisition channel driven past its range holds its output at the range's limit:
the record then has runs of samples at exactly its largest (or smallest) value, on several
cycles. An unclipped record, sampled or quantised, reaches its extreme at one peak. Every
amplitude above the clip level is lost and the band-passed envelope there is wrong (the
clipped peaks are flattened), so the decay routes (:func:`~iwan_element.amplitude_curve`,
:func:`~iwan_element.fit_decay`) use the record only after its last clipped sample
(:func:`cut_clipping`; both treat the cut as the start of the record, with its filter end
effects) and say so in a warning (docs/guards.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Clipping", "cut_clipping", "find_clipping"]

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
        return (f"the record is clipped (saturated): {self.n} samples sit at its extreme "
                f"value(s) {lv} (flat tops) until t = {float(t[self.last]):.4g} s")


def find_clipping(y) -> Clipping | None:
    """The clipping of ``y`` (1-D, finite), or None when it has none: at least
    :data:`MIN_SAMPLES` samples within ``TOL`` of the range of its maximum (or minimum), in at
    least two separate runs."""
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


def cut_clipping(t, y, *, min_samples: int = 64):
    """``(t, y, note)``: the record after its last clipped sample and the warning saying so,
    or the record unchanged and ``""``. ValueError naming ``y`` when fewer than
    ``min_samples`` samples follow the clipping."""
    clip = find_clipping(y)
    if clip is None:
        return t, y, ""
    rest = y.size - clip.last - 1
    if rest < min_samples:
        raise ValueError(f"y: {clip.text(t)}, and only {rest} samples follow it (at least "
                         f"{min_samples} needed); every amplitude measured would be wrong. "
                         "Record again with a larger input range (or a softer excitation)")
    note = (f"{clip.text(t)}: the record was used from the next sample on, so the results "
            "start below the clip level; record again with a larger input range to measure "
            "the amplitudes above it")
    return t[clip.last + 1:], y[clip.last + 1:], note
