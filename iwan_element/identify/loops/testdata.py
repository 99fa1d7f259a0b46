"""Measured test data in, clean cycles out.

A quasi-static joint test (the seed paper's section 3.2: imposed ``u(t) = u0 sin(w t)``, force
measured) is read from a CSV file by :func:`load_test`, converted to SI units at the boundary
and split into cycles by :func:`~iwan_element.identify.loops.cycles.split_cycles` (turning points
with a dead band, refined peaks, loop areas, flags: :mod:`iwan_element.identify.loops.cycles`).
:class:`TestData` holds the record and its cycles; :func:`simulate_test` makes one from an
exact Iwan joint.

All arrays are in SI units: time [s], displacement [m], force [N], energy [J].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, axes_or_new, table_lines
from ...base.serialize import json_safe
from ...base.validation import (
    check_int,
    check_magnitude,
    check_scalar,
    check_time,
    finite_array,
    same_length,
)
from ...core.joint import IwanJoint
from ...core.parameters import IwanParameters
from .cycles import Cycle, check_varies, default_hysteresis, split_cycles

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["TestData", "simulate_test"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class TestData(ResultShape):
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

    It has the package's result shape (:mod:`iwan_element.base.result_shape`): usable when
    at least two cycles close without drift (what a loop fit needs); its main table is the
    cycle table.
    """

    __test__ = False  # not a pytest test class despite its name

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
        check_varies(uu)
        for name, arr in (("t", tt), ("u", uu), ("F", FF)):
            object.__setattr__(self, name, _readonly(arr))

    @classmethod
    def from_arrays(
        cls,
        t,
        u,
        F,
        *,
        units: dict | None = None,
        source: str | None = None,
        hysteresis: float | None = None,
        close_tol: float = 0.02,
        drift_tol: float = 0.05,
    ) -> TestData:
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
        check_varies(uu)
        h = (
            default_hysteresis(uu)
            if hysteresis is None
            else check_scalar("hysteresis", hysteresis, low=0.0, low_open=True)
        )
        cycles = split_cycles(tt, uu, FF, hysteresis=h, close_tol=close_tol, drift_tol=drift_tol)
        if len(cycles) < 2:
            raise ValueError(
                f"found {len(cycles)} complete cycle(s) (maximum to maximum of the "
                f"displacement, dead band {h:.3g} m); at least 2 are needed"
            )
        return cls(
            t=_readonly(tt),
            u=_readonly(uu),
            F=_readonly(FF),
            cycles=tuple(cycles),
            units=dict(units or {"time": "s", "displacement": "m", "force": "N"}),
            source=source,
            hysteresis=float(h),
        )

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
            raise ValueError(
                f"only {len(good)} of {len(self.cycles)} cycles close without drift "
                f"(at least {min_cycles} needed); "
                + "; ".join(bad[:5])
                + (" ..." if len(bad) > 5 else "")
            )
        return {k: np.array([getattr(c, k) for c in good]) for k in ("u0", "F0", "D", "k_sec")}

    #: Column titles of the cycle table (SI units), :meth:`summary` and :meth:`to_dataframe`.
    CYCLE_COLUMNS = ("cycle", "t0 [s]", "u0 [m]", "F0 [N]", "D [J]", "k_sec [N/m]", "flags")

    def cycle_rows(self) -> list:
        """One row per cycle, in :attr:`CYCLE_COLUMNS` (SI units; flags ``"ok"`` if none)."""
        return [
            (c.index, c.t_start, c.u0, c.F0, c.D, c.k_sec, "; ".join(c.flags) or "ok")
            for c in self.cycles
        ]

    @property
    def success(self) -> bool:
        """At least two cycles close without drift (what a loop fit needs)."""
        return len(self.usable_cycles()) >= 2

    def failure_reasons(self) -> tuple:
        """Why the record is not usable for a loop fit, or ``()``."""
        if self.success:
            return ()
        return (
            f"only {len(self.usable_cycles())} of {len(self.cycles)} cycles close without "
            "drift (at least 2 needed for a loop fit)",
        )

    def _head(self) -> str:
        return (
            f"{len(self.u)} samples, {self.t[-1] - self.t[0]:.4g} s, {len(self.cycles)} cycles "
            f"({len(self.usable_cycles())} usable); source: {self.source or 'arrays'}"
        )

    def report(self) -> str:
        """The verdict, then the cycle table in SI units (4 significant digits)."""
        lines = [self.verdict(), self._head()]
        lines += table_lines(
            [(self.CYCLE_COLUMNS[0], "5d")]
            + [(c, "11.4g") for c in self.CYCLE_COLUMNS[1:-1]]
            + [("  flags", "<")],
            [r[:-1] + ("  " + r[-1],) for r in self.cycle_rows()],
        )
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe dict: samples, duration [s], source units, source and the cycles (SI)."""
        keys = ("index", "t0", "u0", "F0", "D", "k_sec", "flags")
        return json_safe(
            {
                "samples": len(self.u),
                "duration": float(self.t[-1] - self.t[0]),
                "units": dict(self.units),
                "source": self.source,
                "cycles": [dict(zip(keys, r)) for r in self.cycle_rows()],
            }
        )

    def _tables(self) -> list:
        """The cycle table (the main one), then the record's size and source."""
        record = [
            ("samples", len(self.u)),
            ("duration [s]", float(self.t[-1] - self.t[0])),
            ("usable cycles", len(self.usable_cycles())),
            ("dead band [m]", float(self.hysteresis)),
            ("source", self.source or "arrays"),
        ]
        return [
            ("cycles", self.CYCLE_COLUMNS, self.cycle_rows()),
            ("record", ("quantity", "value"), record),
        ]

    def plot(self, ax=None) -> list[Artist]:
        """The force against the displacement, usable cycles solid, flagged ones grey, on
        one Axes (a new figure if ``None``); returns the artists.
        """
        ax = axes_or_new(ax)
        arts = []
        for c in self.cycles:
            sl = slice(c.start, c.stop)
            kw = {"color": "C0", "lw": 0.8} if c.usable else {"color": "0.6", "lw": 0.6}
            arts += ax.plot(self.u[sl], self.F[sl], **kw)
        ax.set(xlabel="displacement [m]", ylabel="force [N]")
        return arts


# --------------------------------------------------------------------------- synthetic tests
def simulate_test(
    params: IwanParameters,
    amplitude,
    *,
    cycles: int = 3,
    frequency: float = 0.02,
    sample_rate: float = 20.0,
    force_noise: float = 0.0,
    displacement_noise: float = 0.0,
    seed=0,
) -> TestData:
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
    src = (
        f"simulate_test({params!r}, amplitude={np.round(amps, 12).tolist()} m, cycles={cycles}, "
        f"frequency={f:g} Hz, sample_rate={fs:g} Hz, force_noise={sf:g} N, "
        f"displacement_noise={su:g} m)"
    )
    return TestData.from_arrays(t, u_meas, F_meas, source=src)
