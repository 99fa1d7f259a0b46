"""A hammer impact on the specimen: a half-sine force pulse at a point of the beams' axis.

``F(t) = P sin(pi t / tau)`` for ``0 <= t <= tau``, zero after, transverse (the sensor's
direction) at ``position``; its Fourier magnitude at ``w`` [rad/s] is

    |F^(w)| = (2 P tau / pi) |cos(w tau / 2)| / |1 - (w tau / pi)^2|

(``P tau 2 / pi`` at ``w = 0``, ``P tau / 2`` at ``w = pi / tau``), so a short pulse excites
every mode below about ``1 / tau`` alike; an undamped linear mode is left ringing at the
modal amplitude ``|phi(x_F)| |F^(w)| / w`` (mass-normalised ``phi``).
:func:`~iwan_element.models.ringdown` takes an :class:`Impact` instead of a release.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from iwan_element.base.validation import plain_fields

__all__ = ["Impact"]


@dataclass(frozen=True)
class Impact:
    """A half-sine force pulse (module docstring).

    Parameters
    ----------
    position : float
        Where it acts along the assembly [m] (the axis of ``sensor_position``).
    peak_force : float
        Peak force ``P`` [N], transverse, ``!= 0`` (its sign is the direction).
    contact_time : float
        Pulse duration ``tau`` [s], > 0.
    """

    position: float
    peak_force: float
    contact_time: float

    def __post_init__(self):
        plain_fields(self)

        def finite(v):
            return not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)

        if not finite(self.position) or self.position < 0:
            raise ValueError(f"position must be a finite number >= 0 [m], got {self.position!r}")
        if not finite(self.contact_time) or self.contact_time <= 0:
            raise ValueError(
                f"contact_time must be a finite number > 0 [s], got {self.contact_time!r}"
            )
        if not finite(self.peak_force) or self.peak_force == 0:
            raise ValueError(
                f"peak_force must be a finite, non-zero force [N], got {self.peak_force!r}"
            )

    def force(self, t: float) -> float:
        """The force [N] at time ``t`` [s]."""
        tau = self.contact_time
        return self.peak_force * math.sin(math.pi * t / tau) if 0.0 <= t <= tau else 0.0

    def spectrum(self, omega) -> np.ndarray:
        """``|F^(w)|`` [N s] at angular frequencies ``omega`` [rad/s]."""
        w = np.asarray(omega, float)
        P, tau = abs(self.peak_force), self.contact_time
        x = w * tau / math.pi
        near = np.abs(1.0 - x * x) < 1e-9
        safe = np.where(near, 0.0, 1.0 - x * x)
        val = (
            2
            * P
            * tau
            / math.pi
            * np.abs(np.cos(0.5 * w * tau))
            / np.where(near, 1.0, np.abs(safe))
        )
        return np.where(near, 0.5 * P * tau, val)
