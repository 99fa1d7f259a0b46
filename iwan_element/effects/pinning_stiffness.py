"""Pinning stiffness: a spring in parallel that engages after a clearance.

Physics: after macroslip a bolted joint keeps a residual stiffness (the bolt shank bearing on
the hole once the clearance ``delta`` is taken up, or the elastic stiffness of the clamped
region that never slips, ``delta = 0``): ``F = F_j(u) + k_p sign(u) max(|u| - delta, 0)``
(docs/equations.md section 7: the frequency floor / stiffening of a jointed beam at high
amplitude). In the amplitude domain the dead-zone spring adds the describing-function
stiffness ``k_p g(delta/X)``, ``g(r) = 1 - (2/pi)(asin r + r sqrt(1 - r^2))`` (first
harmonic of a dead-zone nonlinearity), and leaves the dissipation per cycle unchanged.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .base import Effect, ParamSpec

__all__ = ["PinningStiffness", "dead_zone_gain"]


def dead_zone_gain(X, delta) -> NDArray[np.float64]:
    """Describing function of ``sign(u) max(|u| - delta, 0)`` at amplitude ``X``: the
    equivalent linear stiffness per unit ``k_p`` [-] (1 for ``delta = 0``).
    """
    r = np.clip(delta / np.asarray(X, float), 0.0, 1.0)
    return 1.0 - (2.0 / np.pi) * (np.arcsin(r) + r * np.sqrt(1.0 - r * r))


class PinningStiffness(Effect):
    """A spring in parallel that engages after a clearance: ``k_p sign(u) max(|u| - delta, 0)``.

    Parameters
    ----------
    inner : joint element
    k_p : float, keyword-only
        Pinning stiffness [N/m], ``>= 0``.
    delta : float, keyword-only
        Clearance [m], ``>= 0`` (0: residual stiffness from the start, visible after
        macroslip; > 0: bolt shank bearing on the hole).
    """

    effect = "pinning_stiffness"
    loop_rank = 20
    kind = "stiffness"
    # the parameters, stored by _set_parameters from specs (SI units)
    k_p: float
    delta: float
    specs = (
        ParamSpec(
            "k_p",
            "N/m",
            "stiffness in parallel after the clearance",
            fs_power=1,
            ref="u_max",
            fit_bounds=(0.0, 20.0),
            prior=(0.0, 20.0),
            neutral=0.0,
            fit_starts=(0.0, 0.2, 0.3),
        ),
        ParamSpec(
            "delta",
            "m",
            "clearance before the pin bears",
            default=0.0,
            ref="u_max",
            ref_power=-1,
            fit_bounds=(0.0, 0.95),
            prior=(0.0, 0.95),
            fit_starts=(0.0, 0.0, 0.5),
        ),
    )
    modal_specs = (
        ParamSpec(
            "k_p_per_mass",
            "1/s^2",
            "added modal stiffness over modal mass",
            ref="omega2_ref",
            ref_power=-1,
            fit_bounds=(0.0, 10.0),
            prior=(0.0, 10.0),
            neutral=0.0,
            fit_starts=(0.0, 0.05, 0.05),
        ),
        ParamSpec(
            "delta",
            "m",
            "clearance in amplitude units",
            ref="X_max",
            ref_power=-1,
            fit_bounds=(0.0, 0.99),
            prior=(0.0, 0.99),
            fit_starts=(0.0, 0.0, 0.3),
        ),
    )

    def __init__(self, inner, *, k_p: float, delta: float = 0.0):
        super().__init__(inner)
        self._set_parameters({"k_p": k_p, "delta": delta})

    @classmethod
    def vector_force(cls, F, u, v, *, k_p, delta):
        """Force [N]: the inner force ``F`` [N] plus ``k_p sign(u) max(|u| - delta, 0)``."""
        e = np.maximum(np.abs(u) - delta, 0.0)
        return F + k_p * np.sign(u) * e

    @classmethod
    def vector_tangent(cls, u, v, *, k_p, delta):
        """``(k_p where |u| > delta else 0 [N/m], 0)``: the dead-zone spring's tangents."""
        return np.where(np.abs(u) > delta, k_p, 0.0), 0.0

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, k_p_per_mass, delta):
        """Frequency [Hz] raised by the dead-zone spring's describing-function stiffness; the
        hysteretic part of the damping ratio scaled by ``(f_old/f_new)^2`` (same dissipation,
        stiffer mode); the viscous floor ``zeta0`` unchanged.
        """
        f = np.sqrt(frequency**2 + k_p_per_mass * dead_zone_gain(X, delta) / (4 * np.pi**2))
        return f, zeta0 + (damping - zeta0) * (frequency / f) ** 2

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Joint spring ``k_p = kappa m / r^2`` [N/m] and clearance ``delta r`` [m]."""
        r = slip_per_amplitude
        return {"k_p": values["k_p_per_mass"] * modal_mass / r**2, "delta": values["delta"] * r}

    def _spring(self, u: float) -> tuple[float, float, float]:
        e = abs(u) - self.delta
        if e <= 0.0:
            return 0.0, 0.0, 0.0
        return math.copysign(self.k_p * e, u), self.k_p, 0.5 * self.k_p * e * e

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        f, k, _ = self._spring(u)
        self._set_trial(u, v, F + f)
        return F + f, K + k

    def _commit(self) -> None:
        self._inner.commit()
        self._W = self._inner.work + self._spring(self._tu)[2]
        self._D = self._inner.dissipated_energy
