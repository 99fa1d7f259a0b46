"""The frequency response result of the harmonic balance (the package's result shape)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..base.result_shape import ResultShape, column, panels, table_lines
from ..base.serialize import json_safe

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["FrequencyResponse", "ENERGY_TOL", "macroslip_lines", "slip_ratio"]

#: Largest relative energy error per period (input work against the joints' and the floor's
#: dissipation) a converged point may show and the response still count as a success.
ENERGY_TOL = 1e-2


@dataclass(frozen=True)
class FrequencyResponse(ResultShape):
    """Steady periodic response at each frequency, by harmonic balance.

    Attributes
    ----------
    frequency : ndarray, shape (n,)
        Excitation frequency [Hz], in the order solved.
    force : ndarray, shape (n,)
        Fundamental force amplitude at the excitation point [N].
    amplitude : ndarray, shape (n,)
        Fundamental displacement amplitude at the sensor [m].
    phase : ndarray, shape (n,)
        Phase of the sensor's fundamental displacement relative to the force [rad]
        (receptance-like: 0 well below a resonance, -pi above).
    harmonics : ndarray, shape (n, n_h), complex
        The sensor displacement's complex amplitude of every kept harmonic [m]
        (``x(t) = Re sum_h X_h e^{i h W t}``).
    harmonic_numbers : tuple of int
        The kept harmonics.
    converged : ndarray of bool, shape (n,)
        Newton converged at the point.
    iterations : ndarray of int, shape (n,)
    input_work, joint_dissipation, floor_dissipation : ndarray, shape (n,)
        Per period [J]: the force's work, the joints' exact hysteresis loss of the computed
        slips, the linear floor's loss.
    wall_time : float
        Seconds for the whole response.
    metadata : dict
        ``samples`` per period, the system's notes, and the route's settings.
    slip_ratio : ndarray, shape (n, n_j), optional
        Each joint's slip amplitude (half its peak-to-peak slip over the period) over its
        ``phi_max`` [-] (:func:`slip_ratio`): ``>= 1`` where the joint is fully slipped
        (macroslip); NaN at points that did not converge.
    failures : tuple of str
        Why the response is not usable beyond the solver's own checks (each also among
        ``warnings``), e.g. a specimen whose whole interface is fully slipped.
    """

    plot_panels = 2

    frequency: np.ndarray
    force: np.ndarray
    amplitude: np.ndarray
    phase: np.ndarray
    harmonics: np.ndarray
    harmonic_numbers: tuple
    converged: np.ndarray
    iterations: np.ndarray
    input_work: np.ndarray
    joint_dissipation: np.ndarray
    floor_dissipation: np.ndarray
    wall_time: float
    metadata: dict = field(default_factory=dict)
    slip_ratio: np.ndarray | None = None
    failures: tuple = ()

    def __post_init__(self):
        self._fold_failures()

    @property
    def energy_error(self) -> np.ndarray:
        """``(input - joints - floor) / input`` per point [-]. The balance holds exactly for
        the truncated harmonic force; the joints' loss is the exact loop of the sampled slip
        path: the difference is the error of the harmonic truncation and of the AFT's
        sampling (it shrinks with more harmonics and more ``samples`` per period).
        """
        d = self.joint_dissipation + self.floor_dissipation
        with np.errstate(divide="ignore", invalid="ignore"):
            return (self.input_work - d) / np.abs(self.input_work)

    @property
    def success(self) -> bool:
        """Every point converged and closes its energy balance to :data:`ENERGY_TOL`."""
        return (
            bool(np.all(self.converged) and np.all(np.abs(self.energy_error) <= ENERGY_TOL))
            and not self.failures
        )

    def failure_reasons(self) -> tuple:
        """Why :attr:`success` is False (unconverged points, energy balance, the maker's
        ``failures``), or ``()``.
        """
        out = list(self.failures)
        bad = ~self.converged
        if bad.any():
            out.append(
                f"{int(bad.sum())} of {bad.size} frequencies did not converge (near a "
                "turning point of the response curve: trace it by continuation)"
            )
        e = np.abs(self.energy_error)
        if np.any(e[self.converged] > ENERGY_TOL):
            out.append(
                f"energy balance off by up to {np.nanmax(e):.2g} of the input work: "
                "keep more harmonics"
            )
        return tuple(out)

    def report(self) -> str:
        """Verdict, the points, the energy check, warnings."""
        lines = [
            self.verdict(),
            f"harmonic balance: {self.frequency.size} frequencies "
            f"{self.frequency.min():.5g}-{self.frequency.max():.5g} Hz, harmonics "
            f"{', '.join(map(str, self.harmonic_numbers))}, {self.metadata.get('samples')} "
            f"samples per period, {self.wall_time:.3g} s",
        ]
        rows = [
            (f, F, a, p, bool(c), e)
            for f, F, a, p, c, e in zip(
                self.frequency,
                self.force,
                self.amplitude,
                self.phase,
                self.converged,
                self.energy_error,
            )
        ]
        lines += table_lines(
            [
                ("f [Hz]", "10.5f"),
                ("F [N]", "9.4g"),
                ("X [m]", "11.4e"),
                ("phase [rad]", "11.4f"),
                ("converged", ">9"),
                ("energy err [-]", "14.2e"),
            ],
            rows,
        )
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe: every per-point array, the harmonics as real and imaginary parts."""
        return json_safe(
            {
                "frequency": self.frequency,
                "force": self.force,
                "amplitude": self.amplitude,
                "phase": self.phase,
                "harmonic_numbers": list(self.harmonic_numbers),
                "harmonics_real": self.harmonics.real,
                "harmonics_imag": self.harmonics.imag,
                "converged": self.converged,
                "iterations": self.iterations,
                "input_work": self.input_work,
                "joint_dissipation": self.joint_dissipation,
                "floor_dissipation": self.floor_dissipation,
                "energy_error": self.energy_error,
                "wall_time": self.wall_time,
                "metadata": self.metadata,
                "slip_ratio": self.slip_ratio,
                "failures": list(self.failures),
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def _tables(self) -> list:
        """The response, one row per frequency (the main table), then the run."""
        cols = (
            column("frequency", "Hz"),
            column("force", "N"),
            column("amplitude", "m"),
            column("phase", "rad"),
            "converged",
            "iterations",
            column("input work", "J"),
            column("joint dissipation", "J"),
            column("floor dissipation", "J"),
            column("energy error", "-"),
        )
        arrays = (self.frequency, self.force, self.amplitude, self.phase)
        rows = [
            (*map(float, r[:4]), bool(c), int(i), *map(float, r[4:]))
            for *r, c, i in zip(
                *arrays,
                self.input_work,
                self.joint_dissipation,
                self.floor_dissipation,
                self.energy_error,
                self.converged,
                self.iterations,
            )
        ]
        run = [
            ("harmonics", ", ".join(map(str, self.harmonic_numbers))),
            ("samples per period", self.metadata.get("samples")),
            (column("wall time", "s"), float(self.wall_time)),
        ]
        return [("response", cols, rows), ("run", ("quantity", "value"), run)]

    def plot(self, ax=None, *, label="harmonic balance") -> list[Artist]:
        """Amplitude per force [m/N] and phase [rad] against frequency on ``ax = (ax_a,
        ax_p)``; returns the artists.
        """
        a, p = panels(ax, 2, sharex=True)
        arts = a.plot(self.frequency, self.amplitude / self.force, "-", label=label)
        arts += p.plot(self.frequency, self.phase, "-", label=label)
        a.set(ylabel="amplitude / force [m/N]")
        p.set(xlabel="frequency [Hz]", ylabel="phase [rad]")
        if label is not None:
            a.legend(fontsize=8)
            p.legend(fontsize=8)
        return arts


def slip_ratio(system, basis, cz) -> np.ndarray:
    """Each joint's slip amplitude over its ``phi_max`` [-], shape ``(n_j,)``, from the joint
    coefficients ``cz`` (n_z, nc) of one periodic solution: half the peak-to-peak slip of
    the sampled period (the Masing loop's amplitude, a static offset left out).
    """
    nj = len(system.joints)
    z = np.asarray(cz)[:nj] @ basis.E.T
    amp = 0.5 * (z.max(axis=1) - z.min(axis=1))
    return amp / np.array([j.phi_max for j in system.joints])


def _span(values, unit: str) -> str:
    v = np.asarray(values, float)
    lo, hi = float(v.min()), float(v.max())
    return f"{lo:.4g} {unit}" if lo == hi else f"{lo:.4g} .. {hi:.4g} {unit}"


def macroslip_lines(ratio, at, *, unit: str, what: str = "points", groups=()) -> tuple:
    """What a result says of its fully slipped joints (macroslip: a joint's slip amplitude
    at or beyond its ``phi_max``, where every slider slides and the joint carries ``Fs``
    whatever the slip).

    Parameters
    ----------
    ratio : array_like, shape (n, n_j)
        Slip amplitude over ``phi_max`` of every joint at each of the ``n`` points (NaN:
        not solved, counted as not slipped).
    at : array_like, shape (n,)
        The points' abscissa (amplitude [m], frequency [Hz]) in ``unit``.
    unit : str, keyword-only
    what : str, keyword-only
        What the points are ("amplitudes", "frequencies").
    groups : sequence of (str, sequence of int), keyword-only
        Named groups of joints (:attr:`ModalSystem.joint_groups`); default each joint.

    Returns
    -------
    tuple of str
        Empty when no group is fully slipped anywhere; else one line for the whole set of
        joints fully slipped (when it is) and one naming each fully slipped group with
        where it is.
    """
    r = np.nan_to_num(np.atleast_2d(np.asarray(ratio, float)), nan=0.0)
    at = np.asarray(at, float)
    full = r >= 1.0
    nj = r.shape[1]
    groups = tuple(groups) or tuple((f"joint {j + 1}", (j,)) for j in range(nj))
    lines = []
    every = full.all(axis=1)
    if every.any():
        who = (
            "the joint is fully slipped (macroslip: at or beyond its"
            if nj == 1
            else f"the interface is fully slipped (macroslip: all {nj} joints at or beyond their"
        )
        lines.append(
            f"{who} slip displacement phi_max) at {int(every.sum())} of {every.size} {what} "
            f"({_span(at[every], unit)})"
        )
    parts = []
    for label, idx in groups:
        g = full[:, list(idx)].all(axis=1)
        if g.any():
            parts.append(f"{label} at {int(g.sum())} {what} ({_span(at[g], unit)})")
    if parts and not (every.any() and len(parts) == 1 and len(groups) == 1):
        lines.append("fully slipped (macroslip of every joint in it): " + "; ".join(parts))
    return tuple(lines)
