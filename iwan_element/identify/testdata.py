"""Measured test data in, clean cycles out.

A quasi-static joint test (the seed paper's section 3.2: imposed ``u(t) = u0 sin(w t)``, force
measured) is read from a CSV file by :func:`load_test`, converted to SI units at the boundary
and split into cycles by :func:`split_cycles`:

* :func:`find_reversals` finds the turning points of the displacement with a dead band
  (a turning point counts only once the signal has come back from it by more than
  ``hysteresis``), so sensor noise does not create spurious reversals;
* each cycle runs from one displacement maximum to the next. Its peaks are refined by local
  least-squares fits (a parabola in time for the displacement; for the force a parabola on
  each side of the displacement peak, since the tangent stiffness jumps at a reversal), its
  dissipated energy is the loop area ``D = closed integral F du`` (trapezoids, closed by the
  chord between the end points) and it is flagged when it does not close or when its centre
  drifts.

All arrays are in SI units: time [s], displacement [m], force [N], energy [J].
"""
from __future__ import annotations

import html
import math
from dataclasses import dataclass, field

import numpy as np

from ..core.validation import (check_int, check_time, check_magnitude, check_scalar, finite_array,
                                same_length)
from ..core.joint import IwanJoint
from ..core.result_shape import html_table, table_lines
from ..core.serialize import json_safe
from ..core.parameters import IwanParameters
from .noise import difference_sigma, estimate_noise

__all__ = [
    "Cycle",
    "TestData",
    "find_reversals",
    "split_cycles",
    "simulate_test",
]

# --------------------------------------------------------------------------- cycles
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

    :func:`~iwan_element.identify.noise.estimate_noise` (Savitzky-Golay residual, per sample);
    below 32 samples the MAD of the second differences. The second differences alone mistook
    the curvature of a clean, coarsely sampled record for noise."""
    if u.size < 5:
        return 0.0
    if u.size >= 32:
        return estimate_noise(np.arange(u.size, dtype=float), u).sigma
    return difference_sigma(u)


def _check_varies(u: np.ndarray) -> None:
    if u.size and np.ptp(u) == 0.0:
        raise ValueError(f"u (displacement) does not vary: it is {u[0]:g} m everywhere; cycles "
                         "need a displacement that goes up and down (check the column and its unit)")


def _default_hysteresis(u: np.ndarray) -> float:
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
    _check_varies(x)
    h = _default_hysteresis(x) if hysteresis is None else check_scalar(
        "hysteresis", hysteresis, low=0.0, low_open=True)
    vals = x.tolist()
    out = []
    i_max = i_min = 0
    direction = 0                       # +1 rising (looking for a max), -1 falling, 0 unknown
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
    within ``band`` of the extremum."""
    a = i
    while a > lo and sign * (u[i] - u[a - 1]) <= band:
        a -= 1
    b = i
    while b < hi and sign * (u[i] - u[b + 1]) <= band:
        b += 1
    return a, b


def _refine_peak(tau: np.ndarray, u: np.ndarray, F: np.ndarray, i: int, lo: int, hi: int,
                 band: float, sign: float) -> tuple[float, float]:
    """Displacement and force at the turning point ``i`` from local least-squares fits.

    The displacement is a parabola in time around its extremum; the force has a parabola on
    each side sharing the apex at the displacement's extremum time (the tangent stiffness
    jumps at a reversal). Falls back to the raw samples when the window is too short.
    """
    a, b = _window(u, i, lo, hi, band, sign)
    if b - a < 6:
        return float(u[i]), float(F[i])
    s = tau[a:b + 1] - tau[i]
    scale = max(abs(s[0]), abs(s[-1]))
    s = s / scale
    c2, c1, c0 = np.polyfit(s, u[a:b + 1], 2)
    if sign * c2 >= 0.0:
        return float(u[i]), float(F[i])
    s_star = -c1 / (2.0 * c2)
    if not s[0] < s_star < s[-1]:
        return float(u[i]), float(F[i])
    u_pk = c0 + c1 * s_star + c2 * s_star ** 2
    q = (s - s_star) ** 2
    left = s < s_star
    A = np.column_stack([np.ones_like(s), np.where(left, q, 0.0), np.where(left, 0.0, q)])
    if left.sum() < 2 or (~left).sum() < 2:
        return float(u_pk), float(F[i])
    coef = np.linalg.lstsq(A, F[a:b + 1], rcond=None)[0]
    return float(u_pk), float(coef[0])


def _loop_area(u: np.ndarray, F: np.ndarray) -> float:
    """``closed integral F du`` by trapezoids, closed by the chord from the last to the first point."""
    uu = np.append(u, u[0])
    FF = np.append(F, F[0])
    return float(0.5 * np.sum((FF[1:] + FF[:-1]) * np.diff(uu)))


def split_cycles(t, u, F, *, hysteresis: float | None = None, close_tol: float = 0.02,
                 drift_tol: float = 0.05) -> tuple[Cycle, ...]:
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
    _check_varies(uu)
    tt = np.arange(uu.size, dtype=float) if t is None else check_time(t, uu.size)
    close_tol = check_scalar("close_tol", close_tol, low=0.0, high=1.0, low_open=True, high_open=True)
    drift_tol = check_scalar("drift_tol", drift_tol, low=0.0, high=1.0, low_open=True, high_open=True)
    h = _default_hysteresis(uu) if hysteresis is None else check_scalar(
        "hysteresis", hysteresis, low=0.0, low_open=True)
    rev = find_reversals(uu, hysteresis=h)
    if rev.size == 0:
        return ()
    sigma = _noise_sigma(uu)
    # refined (u, F) at every reversal; the window may reach halfway to the neighbours
    peaks = []
    bounds = np.concatenate([[0], rev, [uu.size - 1]])
    for k, i in enumerate(rev):
        lo = (bounds[k] + i) // 2
        hi = (i + bounds[k + 2]) // 2
        sign = 1.0 if uu[i] >= uu[bounds[k + 2]] else -1.0
        rng_local = abs(uu[i] - uu[bounds[k + 2]]) if k + 1 < rev.size else abs(uu[i] - uu[bounds[k]])
        band = max(0.02 * rng_local, 3.0 * sigma)
        peaks.append(_refine_peak(tt, uu, FF, int(i), int(lo), int(hi), band, sign))
    first_max = 0 if rev.size < 2 or uu[rev[0]] > uu[rev[1]] else 1
    raw = []
    for k in range(first_max, rev.size - 2, 2):
        i0, i1, i2 = rev[k], rev[k + 1], rev[k + 2]
        (u_a, F_a), (u_b, F_b), (u_c, F_c) = peaks[k], peaks[k + 1], peaks[k + 2]
        u0 = 0.5 * (u_a - u_b)
        F0 = 0.5 * (F_a - F_b)
        D = _loop_area(uu[i0:i2 + 1], FF[i0:i2 + 1])
        closure = max(abs(u_c - u_a) / (2.0 * u0) if u0 > 0 else math.inf,
                      abs(F_c - F_a) / (2.0 * abs(F0)) if F0 != 0 else math.inf)
        raw.append((int(i0), int(i2) + 1, float(tt[i0]), u0, F0, D, 0.5 * (u_a + u_b),
                    0.5 * (F_a + F_b), closure))
    if not raw:
        return ()
    uc_med = float(np.median([r[6] for r in raw]))
    Fc_med = float(np.median([r[7] for r in raw]))
    cycles = []
    for n, (start, stop, t0, u0, F0, D, uc, Fc, closure) in enumerate(raw):
        drifting = (abs(uc - uc_med) > drift_tol * u0) or (abs(Fc - Fc_med) > drift_tol * abs(F0))
        cycles.append(Cycle(index=n, start=start, stop=stop, t_start=t0, u0=u0, F0=F0, D=D,
                            k_sec=F0 / u0 if u0 > 0 else math.nan, u_center=uc, F_center=Fc,
                            closure=float(closure), closed=bool(closure <= close_tol),
                            drifting=bool(drifting)))
    return tuple(cycles)


# --------------------------------------------------------------------------- test record
def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class TestData:
    """A quasi-static joint test in SI units, split into cycles.

    Build it with :func:`load_test` (from a CSV file) or :meth:`from_arrays`.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s], strictly increasing (read-only).
    u : ndarray, shape (n,)
        Joint displacement [m] (read-only).
    F : ndarray, shape (n,)
        Joint force [N] (read-only).
    cycles : tuple of Cycle
        All complete cycles, usable or flagged.
    units : dict
        Units of the source (``{"time": "s", "displacement": "mm", "force": "kN"}``); the
        arrays here are always SI.
    source : str or None
        Where the data came from (file path), for reports.
    hysteresis : float
        Dead band used to find the reversals [m].
    """

    __test__ = False                    # not a pytest test class despite its name

    t: np.ndarray
    u: np.ndarray
    F: np.ndarray
    cycles: tuple
    units: dict = field(default_factory=dict)
    source: str | None = None
    hysteresis: float = 0.0

    def __post_init__(self):
        # the same checks as from_arrays, on read-only copies (the caller's arrays stay as given)
        uu = finite_array("u (displacement)", self.u, ndim=1, min_size=4).copy()
        FF = finite_array("F (force)", self.F, ndim=1, min_size=4).copy()
        same_length(t=np.asarray(self.t).ravel(), u=uu, F=FF)
        tt = np.array(check_time(self.t, uu.size), dtype=float)
        _check_varies(uu)
        for name, arr in (("t", tt), ("u", uu), ("F", FF)):
            object.__setattr__(self, name, _readonly(arr))

    @classmethod
    def from_arrays(cls, t, u, F, *, units: dict | None = None, source: str | None = None,
                    hysteresis: float | None = None, close_tol: float = 0.02,
                    drift_tol: float = 0.05) -> "TestData":
        """Validate SI arrays and split them into cycles.

        Parameters
        ----------
        t, u, F : array_like, shape (n,)
            Time [s] (strictly increasing), displacement [m], force [N]. Copied, not modified.
        units : dict, optional, keyword-only
            Source units to record (default: SI).
        source : str, optional, keyword-only
            Description of the origin.
        hysteresis, close_tol, drift_tol : keyword-only
            See :func:`split_cycles`.

        Raises
        ------
        ValueError
            On NaN/inf, unequal lengths, non-increasing time, a constant displacement, an
            all-zero force or fewer than two complete cycles.
        """
        uu = finite_array("u (displacement)", u, ndim=1, min_size=4)
        FF = finite_array("F (force)", F, ndim=1, min_size=4)
        same_length(t=np.asarray(t).ravel(), u=uu, F=FF)
        tt = check_time(t, uu.size)
        if not np.any(FF != 0.0):
            raise ValueError("F (force) is all zero: check the force column and its unit")
        _check_varies(uu)
        h = _default_hysteresis(uu) if hysteresis is None else check_scalar(
            "hysteresis", hysteresis, low=0.0, low_open=True)
        cycles = split_cycles(tt, uu, FF, hysteresis=h, close_tol=close_tol, drift_tol=drift_tol)
        if len(cycles) < 2:
            raise ValueError(f"found {len(cycles)} complete cycle(s) (maximum to maximum of the "
                             f"displacement, dead band {h:.3g} m); at least 2 are needed")
        return cls(t=_readonly(tt), u=_readonly(uu), F=_readonly(FF), cycles=tuple(cycles),
                   units=dict(units or {"time": "s", "displacement": "m", "force": "N"}),
                   source=source, hysteresis=float(h))

    def usable_cycles(self) -> tuple[Cycle, ...]:
        """Cycles that close and do not drift."""
        return tuple(c for c in self.cycles if c.usable)

    def amplitude_table(self, *, min_cycles: int = 2) -> dict[str, np.ndarray]:
        """Per-cycle amplitudes of the usable cycles (the paper's Fig. 7 data).

        Parameters
        ----------
        min_cycles : int, keyword-only
            Fewest usable cycles accepted (``>= 1``).

        Returns
        -------
        dict
            ``u0`` [m], ``F0`` [N], ``D`` [J], ``k_sec`` [N/m]: new arrays, shape (m,).

        Raises
        ------
        ValueError
            If fewer than ``min_cycles`` cycles close without drifting; the message lists why
            the others were rejected.
        """
        check_int("min_cycles", min_cycles, 1)
        good = self.usable_cycles()
        if len(good) < min_cycles:
            bad = [f"cycle {c.index}: {', '.join(c.flags)}" for c in self.cycles if not c.usable]
            raise ValueError(f"only {len(good)} of {len(self.cycles)} cycles close without drift "
                             f"(at least {min_cycles} needed); " + "; ".join(bad[:5])
                             + (" ..." if len(bad) > 5 else ""))
        return {k: np.array([getattr(c, k) for c in good]) for k in ("u0", "F0", "D", "k_sec")}

    #: Column titles of the cycle table (SI units), :meth:`summary` and :meth:`to_dataframe`.
    CYCLE_COLUMNS = ("cycle", "t0 [s]", "u0 [m]", "F0 [N]", "D [J]", "k_sec [N/m]", "flags")

    def cycle_rows(self) -> list:
        """One row per cycle, in :attr:`CYCLE_COLUMNS` (SI units; flags ``"ok"`` if none)."""
        return [(c.index, c.t_start, c.u0, c.F0, c.D, c.k_sec, "; ".join(c.flags) or "ok")
                for c in self.cycles]

    def summary(self) -> str:
        """Text table of the cycles in SI units (4 significant digits)."""
        lines = [f"{len(self.u)} samples, {self.t[-1] - self.t[0]:.4g} s, {len(self.cycles)} cycles "
                 f"({len(self.usable_cycles())} usable); source: {self.source or 'arrays'}"]
        lines += table_lines([(self.CYCLE_COLUMNS[0], "5d")]
                             + [(c, "11.4g") for c in self.CYCLE_COLUMNS[1:-1]]
                             + [("  flags", "<")],
                             [r[:-1] + ("  " + r[-1],) for r in self.cycle_rows()])
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe dict: samples, duration [s], source units, source and the cycles (SI)."""
        keys = ("index", "t0", "u0", "F0", "D", "k_sec", "flags")
        return json_safe({"samples": len(self.u), "duration": float(self.t[-1] - self.t[0]),
                          "units": dict(self.units), "source": self.source,
                          "cycles": [dict(zip(keys, r)) for r in self.cycle_rows()]})

    def to_dataframe(self):
        """The cycle table as a ``pandas.DataFrame`` (SI units; pandas imported only here)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("to_dataframe needs pandas: "
                              "pip install 'iwan-element[pandas]'") from None
        return pd.DataFrame(self.cycle_rows(), columns=list(self.CYCLE_COLUMNS))

    def _repr_html_(self) -> str:
        head = html.escape(f"{len(self.u)} samples, {self.t[-1] - self.t[0]:.4g} s, "
                           f"{len(self.usable_cycles())} of {len(self.cycles)} cycles usable; "
                           f"source: {self.source or 'arrays'}")
        return (f"<p><b>TestData</b>: {head}</p>"
                + html_table("cycles", self.CYCLE_COLUMNS, self.cycle_rows()))


# --------------------------------------------------------------------------- synthetic tests
def simulate_test(params: IwanParameters, amplitude, *, cycles: int = 3, frequency: float = 0.02,
                  sample_rate: float = 20.0, force_noise: float = 0.0,
                  displacement_noise: float = 0.0, seed=0) -> TestData:
    """Simulate a displacement-controlled quasi-static test with the exact :class:`IwanJoint`.

    The protocol is the seed paper's (sec. 3.2): ``u(t) = u0 sin(2 pi f t)`` from rest, here
    for each amplitude in turn, ``cycles`` periods each. The force is computed from the exact
    displacement; independent Gaussian white noise is then added to both measured signals.

    Parameters
    ----------
    params : IwanParameters
        The joint.
    amplitude : array_like, shape (m,)
        Displacement amplitudes [m], ``> 0``, in the order they are applied.
    cycles : int, keyword-only
        Periods per amplitude, ``>= 1``.
    frequency : float, keyword-only
        Excitation frequency [Hz], ``> 0`` (the paper: 0.02 Hz).
    sample_rate : float, keyword-only
        Samples per second [Hz], at least ``16 * frequency``.
    force_noise, displacement_noise : float, keyword-only
        Standard deviations of the sensor noise [N], [m], ``>= 0``.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the noise (default 0: reproducible).

    Returns
    -------
    TestData
        Noisy "measured" record in SI units, split into cycles.
    """
    if not isinstance(params, IwanParameters):
        raise ValueError(f"params must be an IwanParameters instance, got {type(params).__name__}")
    amps = check_magnitude("amplitude", finite_array("amplitude", amplitude, ndim=1), unit="m")
    if np.any(amps <= 0.0):
        raise ValueError("amplitude must all be > 0 [m]")
    cycles = check_int("cycles", cycles, 1)
    f = check_scalar("frequency", frequency, low=0.0, low_open=True)
    fs = check_scalar("sample_rate", sample_rate, low=16.0 * f)
    sf = check_scalar("force_noise", force_noise, low=0.0, high=1e100)
    su = check_scalar("displacement_noise", displacement_noise, low=0.0)
    rng = np.random.default_rng(seed)
    n_per = int(round(fs / f))
    phase = np.sin(2.0 * np.pi * np.arange(n_per * cycles) / n_per)
    u = np.concatenate([a * phase for a in amps] + [np.zeros(1)])
    t = np.arange(u.size) / fs
    F = IwanJoint(params).force_history(u)
    u_meas = u + rng.normal(0.0, su, u.size) if su > 0 else u
    F_meas = F + rng.normal(0.0, sf, u.size) if sf > 0 else F
    src = (f"simulate_test({params!r}, amplitude={np.round(amps, 12).tolist()} m, cycles={cycles}, "
           f"frequency={f:g} Hz, sample_rate={fs:g} Hz, force_noise={sf:g} N, "
           f"displacement_noise={su:g} m)")
    return TestData.from_arrays(t, u_meas, F_meas, source=src)

