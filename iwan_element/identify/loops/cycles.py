"""Load cycles of a quasi-static joint test: turning points and cycles with their loops.

* :func:`find_reversals` finds the turning points of the displacement with a dead band
  (a turning point counts only once the signal has come back from it by more than
  ``hysteresis``), so sensor noise does not create spurious reversals;
* :func:`split_cycles`: each cycle runs from one displacement maximum to the next. Its peaks
  are refined by local least-squares fits (a parabola in time for the displacement; for the
  force a parabola on each side of the displacement peak, since the tangent stiffness jumps
  at a reversal), its dissipated energy is the loop area ``D = closed integral F du``
  (trapezoids, closed by the chord between the end points) and it is flagged when it does
  not close or when its centre drifts.

All arrays are in SI units: time [s], displacement [m], force [N], energy [J].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...base.validation import check_magnitude, check_scalar, check_time, finite_array, same_length
from .noise import difference_sigma, estimate_noise

__all__ = ["Cycle", "find_reversals", "split_cycles", "check_varies", "default_hysteresis"]


@dataclass(frozen=True)
class Cycle:
    """One load cycle, from a displacement maximum to the next one (SI units).

    Attributes
    ----------
    index : int
        Position of the cycle in the record (0 = first cycle).
    start, stop : int
        Sample slice of the cycle, ``u[start:stop]`` (``stop - 1`` is the closing maximum).
    t_start : float
        Time of the first sample [s].
    u0 : float
        Displacement amplitude [m]: half the range from the opening maximum to the minimum.
    F0 : float
        Force amplitude [N]: half the force range between the same two reversals.
    D : float
        Dissipated energy of the loop [J] (its area, ``closed integral F du``).
    k_sec : float
        Secant stiffness ``F0/u0`` [N/m] (paper eq. 24).
    u_center, F_center : float
        Centre of the loop [m], [N] (mean of the maximum and the minimum).
    closure : float
        Mismatch of the end point with the start point, as the larger of ``|du|/(2 u0)`` and
        ``|dF|/(2 F0)`` [-].
    closed : bool
        ``closure <= close_tol``.
    drifting : bool
        The centre lies further than ``drift_tol`` times the amplitude from the median centre
        of all cycles (in displacement or in force).
    """

    index: int
    start: int
    stop: int
    t_start: float
    u0: float
    F0: float
    D: float
    k_sec: float
    u_center: float
    F_center: float
    closure: float
    closed: bool
    drifting: bool

    @property
    def usable(self) -> bool:
        """True if the loop closes and does not drift (fit for a dissipation table)."""
        return self.closed and not self.drifting

    @property
    def flags(self) -> tuple[str, ...]:
        """Reasons why the cycle is not usable (empty if it is)."""
        out = []
        if not self.closed:
            out.append(f"does not close (end point off by {100 * self.closure:.1f} % of the range)")
        if self.drifting:
            out.append("centre drifts")
        return tuple(out)


def _noise_sigma(u: np.ndarray) -> float:
    """Robust noise standard deviation of a slowly varying signal.

    :func:`~iwan_element.identify.loops.noise.estimate_noise` (Savitzky-Golay residual, per sample);
    below 32 samples the MAD of the second differences. The second differences alone mistook
    the curvature of a clean, coarsely sampled record for noise.
    """
    if u.size < 5:
        return 0.0
    if u.size >= 32:
        return estimate_noise(np.arange(u.size, dtype=float), u).sigma
    return difference_sigma(u)


def check_varies(u: np.ndarray) -> None:
    """Raise a ValueError if the displacement ``u`` [m] is constant; return None."""
    if u.size and np.ptp(u) == 0.0:
        raise ValueError(
            f"u (displacement) does not vary: it is {u[0]:g} m everywhere; cycles "
            "need a displacement that goes up and down (check the column and its unit)"
        )


def default_hysteresis(u: np.ndarray) -> float:
    """Default reversal hysteresis [m]: the larger of 10 noise sigmas and 1 % of the half range."""
    half_range = 0.5 * float(u.max() - u.min())
    return max(10.0 * _noise_sigma(u), 0.01 * half_range)


def find_reversals(u, *, hysteresis: float | None = None) -> np.ndarray:
    """Indices of the turning points of a noisy displacement record.

    A maximum is confirmed once the signal has fallen more than ``hysteresis`` below it (and a
    minimum likewise), so noise smaller than the dead band creates no reversal. Consecutive
    turning points alternate between maxima and minima.

    Parameters
    ----------
    u : array_like, shape (n,)
        Displacement [m].
    hysteresis : float, optional, keyword-only
        Dead band [m], ``> 0``. Default: ``max(10 sigma, 0.01 (max u - min u)/2)`` with
        ``sigma`` the noise level estimated from the second differences of ``u``. Cycles with
        a peak-to-peak range below it are not resolved.

    Returns
    -------
    ndarray of int
        Sample indices of the confirmed turning points, in time order. The last extremum of the
        record counts only if the record comes back from it by more than the dead band.
    """
    x = check_magnitude("u", finite_array("u", u, ndim=1, min_size=2), unit="m")
    check_varies(x)
    h = (
        default_hysteresis(x)
        if hysteresis is None
        else check_scalar("hysteresis", hysteresis, low=0.0, low_open=True)
    )
    vals = x.tolist()
    out = []
    i_max = i_min = 0
    direction = 0  # +1 rising (looking for a max), -1 falling, 0 unknown
    for i, v in enumerate(vals):
        if v > vals[i_max]:
            i_max = i
        if v < vals[i_min]:
            i_min = i
        if direction >= 0 and vals[i_max] - v > h:
            # at the start, an extremum counts only if it is an excursion from the first sample
            if direction == 1 or vals[i_max] - vals[0] > h:
                out.append(i_max)
            direction = -1
            i_min = i
        elif direction <= 0 and v - vals[i_min] > h:
            if direction == -1 or vals[0] - vals[i_min] > h:
                out.append(i_min)
            direction = 1
            i_max = i
    return np.array(out, dtype=np.intp)


def _window(u: np.ndarray, i: int, lo: int, hi: int, band: float, sign: float) -> tuple[int, int]:
    """Contiguous samples around the extremum ``i`` (within ``[lo, hi]``) whose value stays
    within ``band`` of the extremum.
    """
    a = i
    while a > lo and sign * (u[i] - u[a - 1]) <= band:
        a -= 1
    b = i
    while b < hi and sign * (u[i] - u[b + 1]) <= band:
        b += 1
    return a, b


def _refine_peak(
    tau: np.ndarray,
    u: np.ndarray,
    F: np.ndarray,
    i: int,
    lo: int,
    hi: int,
    band: float,
    sign: float,
) -> tuple[float, float]:
    """Displacement and force at the turning point ``i`` from local least-squares fits.

    The displacement is a parabola in time around its extremum; the force has a parabola on
    each side sharing the apex at the displacement's extremum time (the tangent stiffness
    jumps at a reversal). Falls back to the raw samples when the window is too short.
    """
    a, b = _window(u, i, lo, hi, band, sign)
    if b - a < 6:
        return float(u[i]), float(F[i])
    s = tau[a : b + 1] - tau[i]
    scale = max(abs(s[0]), abs(s[-1]))
    s = s / scale
    c2, c1, c0 = np.polyfit(s, u[a : b + 1], 2)
    if sign * c2 >= 0.0:
        return float(u[i]), float(F[i])
    s_star = -c1 / (2.0 * c2)
    if not s[0] < s_star < s[-1]:
        return float(u[i]), float(F[i])
    u_pk = c0 + c1 * s_star + c2 * s_star**2
    q = (s - s_star) ** 2
    left = s < s_star
    A = np.column_stack([np.ones_like(s), np.where(left, q, 0.0), np.where(left, 0.0, q)])
    if left.sum() < 2 or (~left).sum() < 2:
        return float(u_pk), float(F[i])
    coef = np.linalg.lstsq(A, F[a : b + 1], rcond=None)[0]
    return float(u_pk), float(coef[0])


def _loop_area(u: np.ndarray, F: np.ndarray) -> float:
    """``closed integral F du`` [J] by trapezoids, closed by the chord from last to first point."""
    uu = np.append(u, u[0])
    FF = np.append(F, F[0])
    return float(0.5 * np.sum((FF[1:] + FF[:-1]) * np.diff(uu)))


def _reversal_peaks(tt, uu, FF, rev):
    """The refined ``(u, F)`` at every reversal."""
    sigma = _noise_sigma(uu)
    # refined (u, F) at every reversal; the window may reach halfway to the neighbours
    peaks = []
    bounds = np.concatenate([[0], rev, [uu.size - 1]])
    for k, i in enumerate(rev):
        lo = (bounds[k] + i) // 2
        hi = (i + bounds[k + 2]) // 2
        sign = 1.0 if uu[i] >= uu[bounds[k + 2]] else -1.0
        rng_local = (
            abs(uu[i] - uu[bounds[k + 2]]) if k + 1 < rev.size else abs(uu[i] - uu[bounds[k]])
        )
        band = max(0.02 * rng_local, 3.0 * sigma)
        peaks.append(_refine_peak(tt, uu, FF, int(i), int(lo), int(hi), band, sign))
    return peaks


def _raw_cycles(tt, uu, FF, rev, peaks):
    """Each cycle from a maximum to the next: span, amplitudes, area, centre and closure."""
    first_max = 0 if rev.size < 2 or uu[rev[0]] > uu[rev[1]] else 1
    raw = []
    for k in range(first_max, rev.size - 2, 2):
        i0, i2 = rev[k], rev[k + 2]
        (u_a, F_a), (u_b, F_b), (u_c, F_c) = peaks[k], peaks[k + 1], peaks[k + 2]
        u0 = 0.5 * (u_a - u_b)
        F0 = 0.5 * (F_a - F_b)
        D = _loop_area(uu[i0 : i2 + 1], FF[i0 : i2 + 1])
        closure = max(
            abs(u_c - u_a) / (2.0 * u0) if u0 > 0 else math.inf,
            abs(F_c - F_a) / (2.0 * abs(F0)) if F0 != 0 else math.inf,
        )
        raw.append(
            (
                int(i0),
                int(i2) + 1,
                float(tt[i0]),
                u0,
                F0,
                D,
                0.5 * (u_a + u_b),
                0.5 * (F_a + F_b),
                closure,
            )
        )
    return raw


def split_cycles(
    t, u, F, *, hysteresis: float | None = None, close_tol: float = 0.02, drift_tol: float = 0.05
) -> tuple[Cycle, ...]:
    """Split a displacement-driven record into cycles (maximum to next maximum).

    Parameters
    ----------
    t : array_like of shape (n,), or None
        Time [s], strictly increasing; ``None`` uses the sample index. Used for the peak fits.
    u, F : array_like, shape (n,)
        Displacement [m] and force [N]. Not modified.
    hysteresis : float, optional, keyword-only
        Dead band for reversals [m] (see :func:`find_reversals`).
    close_tol : float, keyword-only
        Largest end-point mismatch, relative to the peak-to-peak range, of a closed loop,
        in ``(0, 1)``. Default 0.02.
    drift_tol : float, keyword-only
        Largest offset of a loop's centre from the median centre, relative to its amplitude,
        in ``(0, 1)``. Default 0.05.

    Returns
    -------
    tuple of Cycle
        Possibly empty; the first loading from rest and a trailing half cycle are no cycles.
    """
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=2), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=2), unit="N")
    same_length(u=uu, F=FF)
    check_varies(uu)
    tt = np.arange(uu.size, dtype=float) if t is None else check_time(t, uu.size)
    close_tol = check_scalar(
        "close_tol", close_tol, low=0.0, high=1.0, low_open=True, high_open=True
    )
    drift_tol = check_scalar(
        "drift_tol", drift_tol, low=0.0, high=1.0, low_open=True, high_open=True
    )
    h = (
        default_hysteresis(uu)
        if hysteresis is None
        else check_scalar("hysteresis", hysteresis, low=0.0, low_open=True)
    )
    rev = find_reversals(uu, hysteresis=h)
    if rev.size == 0:
        return ()
    peaks = _reversal_peaks(tt, uu, FF, rev)
    raw = _raw_cycles(tt, uu, FF, rev, peaks)
    if not raw:
        return ()
    uc_med = float(np.median([r[6] for r in raw]))
    Fc_med = float(np.median([r[7] for r in raw]))
    cycles = []
    for n, (start, stop, t0, u0, F0, D, uc, Fc, closure) in enumerate(raw):
        drifting = (abs(uc - uc_med) > drift_tol * u0) or (abs(Fc - Fc_med) > drift_tol * abs(F0))
        cycles.append(
            Cycle(
                index=n,
                start=start,
                stop=stop,
                t_start=t0,
                u0=u0,
                F0=F0,
                D=D,
                k_sec=F0 / u0 if u0 > 0 else math.nan,
                u_center=uc,
                F_center=Fc,
                closure=float(closure),
                closed=bool(closure <= close_tol),
                drifting=bool(drifting),
            )
        )
    return tuple(cycles)


# --------------------------------------------------------------------------- test record
