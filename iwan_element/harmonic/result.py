"""The frequency response result of the harmonic balance (the package's result shape)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..base.result_shape import ResultShape, column, panels, table_lines
from ..base.serialize import json_safe

__all__ = ["FrequencyResponse", "ENERGY_TOL"]

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
        return bool(np.all(self.converged) and np.all(np.abs(self.energy_error) <= ENERGY_TOL))

    def failure_reasons(self) -> tuple:
        """Why :attr:`success` is False (unconverged points, energy balance), or ``()``."""
        out = []
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

    def plot(self, ax=None, *, label="harmonic balance"):
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
