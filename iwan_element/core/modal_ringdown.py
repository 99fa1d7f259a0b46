"""The result of :func:`~iwan_element.modal_ringdown`: the single-mode modal Iwan oscillator's
free decay, with the package's result shape (as :func:`iwan_element.models.ringdown` returns
a result, not a tuple).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..base.result_shape import ResultShape, axes_or_new, format_value
from .parameters import IwanParameters

if TYPE_CHECKING:
    from matplotlib.lines import Line2D

__all__ = ["ModalRingdown"]


@dataclass(frozen=True)
class ModalRingdown(ResultShape):
    """Free decay of the modal Iwan oscillator ``m q'' + c q' + K_inf q + F_J(q) = 0``
    (Segalman 2005, J. Appl. Mech. 72:752-760; docs/equations.md section 7), integrated with
    the exact joint.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s] from the release.
    displacement, velocity, acceleration : ndarray, shape (n,)
        Modal displacement [m], velocity [m/s] and acceleration [m/s^2] at ``t``.
    joint : IwanParameters
        The joint (modal units).
    K_inf, zeta0, mass : float
        The rest of the mode's stiffness [N/m], the viscous floor's damping ratio [-] (a
        dashpot ``c = 2 zeta0 mass w0``) and the modal mass [kg].
    q0, v0 : float
        Release displacement [m] and velocity [m/s].
    warnings : tuple of str
        Always empty: the integration is exact up to its stated step error.
    """

    t: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    joint: IwanParameters
    K_inf: float
    zeta0: float
    mass: float
    q0: float
    v0: float = 0.0
    warnings: tuple = field(default=(), kw_only=True)

    def __post_init__(self):
        arrays = (self.t, self.displacement, self.velocity, self.acceleration)
        if len({np.shape(a) for a in arrays}) != 1 or np.ndim(self.t) != 1:
            raise ValueError("t, displacement, velocity and acceleration must be 1-D, one length")

    @property
    def success(self) -> bool:
        """True: a simulated decay has nothing the data cannot support."""
        return True

    @property
    def linear_frequency(self) -> float:
        """Stuck-joint natural frequency ``sqrt((K_inf + KT)/mass) / 2 pi`` [Hz]."""
        return math.sqrt((self.K_inf + self.joint.KT) / self.mass) / (2 * math.pi)

    def report(self) -> str:
        """The verdict, then the run: samples, span, release and final amplitude."""
        n = self.t.size
        tail = np.abs(self.displacement[-max(n // 20, 2) :]).max()
        return "\n".join(
            [
                self.verdict(),
                f"Modal Iwan ring-down: {n} samples, t = {format_value(self.t[0])} to "
                f"{format_value(self.t[-1])} s, stuck-joint frequency "
                f"{self.linear_frequency:.6g} Hz",
                f"  release q0 = {format_value(self.q0)} m, v0 = {format_value(self.v0)} m/s; "
                f"amplitude at the end {format_value(tail)} m",
                f"  joint Fs = {format_value(self.joint.Fs)} N, KT = "
                f"{format_value(self.joint.KT)} N/m, chi = {self.joint.chi:.4g}, beta = "
                f"{self.joint.beta:.4g}; K_inf = {format_value(self.K_inf)} N/m, zeta0 = "
                f"{format_value(self.zeta0)}, mass = {format_value(self.mass)} kg",
            ]
        )

    def to_dict(self) -> dict:
        """The time series and the run's settings as plain Python values (JSON-ready)."""
        return {
            "t": self.t.tolist(),
            "displacement": self.displacement.tolist(),
            "velocity": self.velocity.tolist(),
            "acceleration": self.acceleration.tolist(),
            "joint": self.joint.to_dict(),
            "K_inf": float(self.K_inf),
            "zeta0": float(self.zeta0),
            "mass": float(self.mass),
            "q0": float(self.q0),
            "v0": float(self.v0),
            "success": True,
            "warnings": list(self.warnings),
        }

    def _tables(self) -> list:
        cols = ("time [s]", "displacement [m]", "velocity [m/s]", "acceleration [m/s^2]")
        rows = list(
            zip(
                *(a.tolist() for a in (self.t, self.displacement, self.velocity, self.acceleration))
            )
        )
        run = [
            ("stuck-joint frequency [Hz]", self.linear_frequency),
            ("K_inf [N/m]", float(self.K_inf)),
            ("zeta0 [-]", float(self.zeta0)),
            ("mass [kg]", float(self.mass)),
            ("q0 [m]", float(self.q0)),
            ("v0 [m/s]", float(self.v0)),
        ]
        return [("time series", cols, rows), ("run", ("quantity", "value"), run)]

    def plot(self, ax=None, *, label: str | None = None) -> list[Line2D]:
        """The modal displacement against time on ``ax`` (a new figure if ``None``);
        returns the artists.
        """
        ax = axes_or_new(ax)
        arts = ax.plot(self.t, self.displacement, lw=0.6, label=label or "modal displacement")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("displacement [m]")
        if label:
            ax.legend()
        return arts
