"""The first step of a loop diagnosis: a checked, prepared record.

:func:`check_record` validates the user's arrays and options; :func:`prepare_record` removes
the rig's dynamics (``lowpass``: a zero-phase Butterworth low-pass on both channels), finds
the joint's rest position (mean displacement before the motion starts) and builds the
evaluators of the fitted samples. The result, :class:`PreparedRecord`, is what every later
step (noise, fit, selection, report) reads; none of them goes back to the raw input.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import butter, sosfiltfilt

from ...base.validation import (
    MAGNITUDE_RANGE,
    check_magnitude,
    check_scalar,
    check_time,
    check_varies,
    finite_array,
    same_length,
)
from ...core.history import REVERSAL_TOL, unit_params
from ...effects import EFFECTS
from ...effects.engine.evaluate import Evaluator
from ...identify.loops.cycles import Cycle, find_reversals, split_cycles
from .noise import noise_estimate

__all__ = [
    "PreparedRecord",
    "check_record",
    "prepare_record",
    "fitted_samples",
    "effect_scales",
    "dissipation_scale",
    "drive_structure",
    "untestable",
    "record_cycles",
    "SLOW_FIT_SAMPLES",
]

#: Samples fitted for stacks without a vectorised form (run element by element).
SLOW_FIT_SAMPLES = 300


@dataclass(frozen=True, eq=False)
class PreparedRecord:
    """A record as the diagnosis fits it.

    Attributes
    ----------
    t : ndarray or None
        Time [s] (None: no time given).
    u : ndarray
        Displacement [m] as measured, low-passed if asked.
    F_raw, F : ndarray
        Force [N] as measured, and as fitted (low-passed if asked).
    n : int
        Samples.
    lowpass : float or None
        Low-pass cut-off [Hz].
    u_offset : float
        The joint's rest position [m] (mean displacement before the motion starts).
    uj, v : ndarray
        Displacement from the rest position [m] and its velocity [m/s] (zero without ``t``).
    keep, sub : ndarray of int
        Fitted samples of the fast and of the element-by-element stacks.
    ev, ev_slow : Evaluator
        Their unit-force evaluators.
    """

    t: np.ndarray | None
    u: np.ndarray
    F_raw: np.ndarray
    F: np.ndarray
    n: int
    lowpass: float | None
    u_offset: float
    uj: np.ndarray
    v: np.ndarray
    keep: np.ndarray
    sub: np.ndarray
    ev: Evaluator
    ev_slow: Evaluator

    @property
    def scales(self) -> dict:
        """Reference sizes of the effect variables (:func:`effect_scales`; ``D_ref`` 1 until
        a plain fit gives it, :func:`dissipation_scale`).
        """
        return effect_scales(self.uj, self.v)


def effect_scales(uj, v, d_ref: float = 1.0) -> dict:
    """Reference sizes of the effect variables (``ParamSpec.ref``) of a record: largest |u|
    [m], RMS velocity [m/s], the plain unit-``Fs`` fit's dissipation over the record ``d_ref``
    [J per N of Fs] and 1.
    """
    return {
        "u_max": float(np.abs(uj).max()),
        "1": 1.0,
        "v_rms": float(np.sqrt(np.mean(v**2))) or 1.0,
        "D_ref": d_ref,
    }


def dissipation_scale(ev: Evaluator, shape) -> float:
    """Energy the plain unit-``Fs`` joint of ``shape = (phi_max, chi, beta)`` dissipates over
    the record of ``ev`` (the energy-dependent effects' scale, ``D_ref``), 1 if none.
    """
    return float(ev.unit_dissipation(unit_params(*shape))[-1]) or 1.0


def drive_structure(uj) -> tuple[NDArray[np.intp], float]:
    """``(reversal indices, absolute reversal tolerance [m])`` of a record's displacement from
    its rest position, as every evaluator of it uses them.
    """
    rev = find_reversals(uj) if uj.size > 2 else np.zeros(0, np.intp)
    return rev, REVERSAL_TOL * float(np.abs(uj).max())


def check_record(
    t, u, F, noise, lowpass
) -> tuple[
    NDArray[np.float64] | None, NDArray[np.float64], NDArray[np.float64], int, Any, float | None
]:
    """Checked ``(t, u, F, n, noise, lowpass)``; ``ValueError`` naming the bad argument."""
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=40), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=40), unit="N")
    n = same_length(u=uu, F=FF)
    tt = None if t is None else check_time(t, n)
    check_varies("u", uu, unit="m", what="a displacement-driven test is needed")
    check_varies(
        "F",
        FF,
        unit="N",
        what="the joint force does not follow the displacement; check the force channel",
    )
    scale_F = max(float(np.max(np.abs(FF))), 1e-300)
    if noise is not None:
        noise = check_scalar("noise", noise, low=MAGNITUDE_RANGE[0], high=MAGNITUDE_RANGE[1])
        if noise < 1e-9 * scale_F:
            raise ValueError(
                f"noise = {noise:g} N is below the floating-point resolution of the "
                f"force record (1e-9 x max|F| = {1e-9 * scale_F:.3g} N); give a "
                "realistic noise level or leave noise=None to estimate it"
            )
    lp = None
    if lowpass is not None:
        if tt is None:
            raise ValueError("lowpass needs the time vector t")
        fs = 1.0 / float(np.median(np.diff(tt)))
        lp = check_scalar("lowpass", lowpass, low=0.0, high=0.5 * fs, low_open=True, high_open=True)
    return tt, uu, FF, n, noise, lp


def _rate_missing(t, v) -> str:
    """Why a record cannot test a rate-dependent force, or "" (the ``"rate"`` need)."""
    if t is None:
        return (
            "no time vector was given, so the velocity is unknown; a rate effect cannot be tested"
        )
    s = np.abs(v)
    moving = s > 0.05 * s.max()
    med = float(np.median(s[moving])) if moving.any() else 0.0
    if moving.sum() > 10 and np.mean(np.abs(s[moving] - med) <= 0.05 * med) >= 0.9:
        return (
            "the record is loaded at a single constant rate (|v| within 5 % of one value "
            "on 90 % of the samples), so a rate-dependent force cannot be told from a "
            "rate-independent friction offset; test at several rates or with sinusoidal "
            "loading"
        )
    return ""


def untestable(rec: PreparedRecord, candidates) -> dict:
    """``{effect: why}`` for each of ``candidates`` whose declared data needs
    (``needs`` of its class in :data:`~iwan_element.EFFECTS`) the record ``rec`` lacks.
    """
    missing = {"rate": _rate_missing(rec.t, rec.v)}
    out = {}
    for c in candidates:
        why = [missing[n] for n in EFFECTS[c].needs if missing[n]]
        if why:
            out[c] = "; ".join(why)
    return out


def record_cycles(rec: PreparedRecord) -> Sequence[Cycle]:
    """The record's load cycles (:func:`~iwan_element.identify.loops.cycles.split_cycles`; the
    sample index stands for the time when there is none), or [] when it has none.
    """
    t = np.arange(rec.uj.size, dtype=float) if rec.t is None else rec.t
    try:
        return split_cycles(t, rec.uj, rec.F)
    except ValueError:
        return []


def lowpass_filter(t, x, cutoff):
    """Zero-phase 4th-order Butterworth low-pass of ``x`` at ``cutoff`` [Hz]."""
    fs = 1.0 / float(np.median(np.diff(t)))
    return sosfiltfilt(butter(4, cutoff, fs=fs, output="sos"), x)


def _rest_index(u, noise_u):
    """Samples before the motion starts (at least 1)."""
    thr = max(1e-6 * float(np.ptp(u)), 5.0 * noise_u)
    moved = np.flatnonzero(np.abs(u - u[0]) > thr)
    return max(int(moved[0]) if moved.size else 1, 1)


def fitted_samples(n: int, max_samples: int) -> np.ndarray:
    """Indices of the samples a diagnosis fits: at most ``max_samples``, evenly spaced over
    the ``n`` samples of the record (the first and last included).
    """
    return np.unique(np.round(np.linspace(0, n - 1, min(n, max_samples))).astype(np.intp))


def _evaluators(uj, v, max_samples):
    n = uj.size
    rev, tol = drive_structure(uj)
    keep = fitted_samples(n, max_samples)
    ev = Evaluator(uj, v, keep, rev, tol=tol)
    sub = keep[
        np.unique(
            np.round(np.linspace(0, keep.size - 1, min(keep.size, SLOW_FIT_SAMPLES))).astype(
                np.intp
            )
        )
    ]
    ev_slow = Evaluator(uj, v, sub, rev, tol=tol)
    return ev, ev_slow, keep, sub


def prepare_record(t, u, F, n, lowpass, max_samples) -> PreparedRecord:
    """The record as fitted (checked input from :func:`check_record`).

    Both channels are low-passed, as the rig's dynamics and the sensor noise are in both: the
    joint is driven by the displacement without them. Raw displacement noise makes turning
    points by the hundred (154 on a 1 Hz damper record at the fitted samples, 26 after a
    20 Hz low-pass), and every one re-sticks the sliders of a break-away model. The force
    offset is not removed here: it is fitted with every model (linear, with ``Fs``), the rest
    samples being part of the fitted data (a mean over a few rest samples would leave its
    error in the residual as a constant misfit, a false "effect").
    """
    FF, uu = F, u
    if lowpass is not None:
        FF, uu = lowpass_filter(t, F, lowpass), lowpass_filter(t, u, lowpass)
    i_rest = _rest_index(uu, noise_estimate(t, uu)[0])
    u_off = float(np.mean(uu[:i_rest]))
    uj = uu - u_off
    v = np.zeros(n) if t is None else np.gradient(uj, t)
    ev, ev_slow, keep, sub = _evaluators(uj, v, max_samples)
    return PreparedRecord(
        t=t,
        u=uu,
        F_raw=F,
        F=FF,
        n=n,
        lowpass=lowpass,
        u_offset=u_off,
        uj=uj,
        v=v,
        keep=keep,
        sub=sub,
        ev=ev,
        ev_slow=ev_slow,
    )
