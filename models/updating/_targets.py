"""The targets of :func:`~iwan_element.models.updating.linear_update` (its step 1): natural
frequencies, scale-free mode shapes at sensors and drive-point modal constants, checked,
each with its relative standard error (the measurement's and the model-form error added in
quadrature), and the measured value behind each residual's label.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np


def _pair(v):
    """``(value, stderr)`` of a target given as a number or a pair."""
    if isinstance(v, (tuple, list)):
        if len(v) != 2:
            raise ValueError(f"a target must be a number or (value, stderr), got {v!r}")
        return float(v[0]), float(v[1])
    return float(v), 0.0


def _real_shape(values: dict) -> tuple:
    """Positions, real signed amplitudes and stderr of a measured shape ``{position [m]:
    amplitude or (amplitude, stderr)}`` (complex amplitudes rotated to the real axis by their
    mean phase).
    """
    items = sorted(((float(p), v) for p, v in values.items()), key=lambda pv: pv[0])
    pos = np.array([p for p, _ in items])
    vals = [v if isinstance(v, (tuple, list)) else (v, 0.0) for _, v in items]
    amp = np.array([complex(v[0]) for v in vals])
    amp = np.real(amp * np.exp(-0.5j * np.angle(np.sum(amp * amp))))
    se = np.array([float(v[1]) for v in vals])
    return pos, amp, se


@dataclass(frozen=True)
class _Targets:
    freq: dict  # mode -> (Hz, relative stderr)
    shapes: dict  # mode -> (positions, unit shape, stderr per entry)
    consts: dict  # mode -> (1/kg, relative stderr)
    labels: tuple

    @classmethod
    def build(cls, frequencies, shapes, modal_constants, err):
        freq, sh, cc, labels = {}, {}, {}, []
        for name, v in (
            ("frequencies", frequencies),
            ("shapes", shapes),
            ("modal_constants", modal_constants),
        ):
            if v is None and name != "frequencies":
                continue
            if not isinstance(v, Mapping) or any(
                isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1 for k in v
            ):
                raise ValueError(
                    f"{name} must map elastic mode numbers (integers >= 1) to targets, got {v!r}"
                )
        for r, v in sorted(dict(frequencies).items()):
            f, se = _pair(v)
            if not (math.isfinite(f) and f > 0 and se >= 0):
                raise ValueError(
                    f"frequencies[{r}] must be a frequency > 0 [Hz] (and a stderr >= 0), got {v!r}"
                )
            freq[int(r)] = (f, math.hypot(se / f, err["frequency"]))
            labels.append(f"f{r}")
        for r, vals in sorted(dict(shapes or {}).items()):
            pos, amp, se = _real_shape(vals)
            if pos.size < 2 or not np.all(np.isfinite(amp)) or np.linalg.norm(amp) == 0:
                raise ValueError(
                    f"shapes[{r}] must give a finite, non-zero amplitude at 2 or "
                    f"more positions, got {vals!r}"
                )
            n = np.linalg.norm(amp)
            sh[int(r)] = (pos, amp / n, np.hypot(se / n, err["shape"]))
            labels += [f"shape{r}@{p:.4g}" for p in pos]
        for r, v in sorted(dict(modal_constants or {}).items()):
            c, se = _pair(v)
            if not (math.isfinite(c) and c != 0 and se >= 0):
                raise ValueError(
                    f"modal_constants[{r}] must be a non-zero modal constant [1/kg], got {v!r}"
                )
            cc[int(r)] = (c, math.hypot(se / c, err["modal_constant"]))
            labels.append(f"c{r}")
        if not freq and not sh and not cc:
            raise ValueError("give at least one target (frequencies, shapes, modal_constants)")
        return cls(freq, sh, cc, tuple(labels))

    @property
    def modes(self) -> tuple:
        return tuple(sorted(set(self.freq) | set(self.shapes) | set(self.consts)))

    @property
    def positions(self) -> tuple:
        return tuple(sorted({float(p) for pos, _, _ in self.shapes.values() for p in pos}))


def _measured(t: _Targets, label: str) -> float:
    if label.startswith("f"):
        return t.freq[int(label[1:])][0]
    if label.startswith("c"):
        return t.consts[int(label[1:])][0]
    r, p = label[5:].split("@")
    pos, unit, _ = t.shapes[int(r)]
    return float(unit[int(np.argmin(np.abs(pos - float(p))))])
