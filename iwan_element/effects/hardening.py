"""Amplitude hardening: a cubic spring in parallel with the joint.

Physics: a stiffness that grows with the deflection, ``F = F_j(u) + k3 u^3``. In a jointed
beam it can stand for

* **bending-stretching (membrane) coupling**: a beam whose ends are held axially stretches
  as it bends, and the axial force stiffens the bending mode by a cubic term (the classical
  Duffing form of a clamped-clamped beam; Nayfeh & Mook, *Nonlinear Oscillations*, Wiley
  1979, ch. 7). A free-free beam has no such restraint, so on a free-free specimen the term
  points to the next two;
* **a contact whose area or pressure grows with the load**: the lap's edges closing under
  bending (prying) or the pressure cones widening, so that more interface carries load as
  the amplitude grows;
* **the test set-up**: the shaker's stinger, the suspension or the fixture adding a
  stiffening restoring force.

The Tribomechadynamics Research Challenge 2021 (Krack et al., Mech. Syst. Signal Process.
2025, doi 10.1016/j.ymssp.2024.112016) found bending-stretching hardening on top of
frictional softening in a bolted panel.

Modal (amplitude-domain) form: the first harmonic of ``kappa3 q^3`` at amplitude ``X`` is
``(3/4) kappa3 X^3`` in phase with the motion, so ``w(X)^2 = w_base(X)^2 + (3/4) kappa3 X^2``
and the dissipation per cycle is unchanged: the hysteretic part of the damping ratio is
scaled by ``(w_base / w)^2`` (same energy lost, stiffer mode), the viscous floor is not.
Equations: ``docs/vibration_effects.md``.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, ParamSpec

__all__ = ["Hardening"]


class Hardening(Effect):
    """A cubic spring in parallel with the joint: ``F = F_j(u) + k3 u^3``.

    Parameters
    ----------
    inner : joint element
    k3 : float, keyword-only
        Cubic stiffness [N/m^3], ``>= 0`` (0: the wrapped element itself).

    Notes
    -----
    Conservative: it stores ``k3 u^4 / 4`` and dissipates nothing. The modal form
    (:meth:`modal_form`) is the Duffing first harmonic; :meth:`modal_to_joint` converts the
    modal coefficient for a joint slip ``u = r q`` of a mode with modal mass ``m``:
    ``k3 = kappa3 m / r^4``.
    """

    effect = "hardening"
    # the parameters, stored by _set_parameters from specs (SI units)
    k3: float
    specs = (
        ParamSpec(
            "k3",
            "N/m^3",
            "cubic stiffness in parallel with the joint",
            fs_power=1,
            ref="u_max",
            ref_power=3,
            fit_bounds=(0.0, 5.0),
            prior=(0.0, 5.0),
            neutral=0.0,
            fit_starts=(0.0, 0.1, 1.0),
        ),
    )
    modal_specs = (
        ParamSpec(
            "k3_per_mass",
            "1/(m^2 s^2)",
            "cubic modal stiffness over modal mass (amplitude in curve units)",
            ref="omega2_per_X2",
            ref_power=-1,
            fit_bounds=(0.0, 1.0),
            prior=(0.0, 1.0),
            neutral=0.0,
            fit_starts=(0.0, 1e-3, 2e-2),
        ),
    )
    kind = "stiffness"

    def __init__(self, inner, *, k3: float):
        super().__init__(inner)
        self._set_parameters({"k3": k3})

    @classmethod
    def vector_force(cls, F, u, v, *, k3):
        """Force [N]: the inner force ``F`` [N] plus ``k3 u**3`` (``u`` [m], ``k3`` [N/m^3])."""
        return F + k3 * u**3

    @classmethod
    def vector_tangent(cls, u, v, *, k3):
        """``(3 k3 u^2 [N/m], 0)``: the cubic spring's tangents."""
        return 3.0 * k3 * np.asarray(u, float) ** 2, 0.0

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, k3_per_mass):
        """Frequency [Hz] raised by the Duffing first harmonic ``(3/4) kappa3 X^2`` [1/s^2];
        the hysteretic damping scaled by ``(f_base / f)^2``, the floor ``zeta0`` unchanged.
        """
        X = np.asarray(X, float)
        f = np.sqrt(frequency**2 + 0.75 * k3_per_mass * X**2 / (4 * np.pi**2))
        return f, zeta0 + (damping - zeta0) * (frequency / f) ** 2

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Joint cubic stiffness ``k3 = kappa3 m / r^4`` [N/m^3]."""
        return {"k3": values["k3_per_mass"] * modal_mass / slip_per_amplitude**4}

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        F += self.k3 * u**3
        self._set_trial(u, v, F)
        return F, K + 3.0 * self.k3 * u * u

    def _commit(self) -> None:
        self._inner.commit()
        self._W = self._inner.work + 0.25 * self.k3 * self._tu**4
        self._D = self._inner.dissipated_energy
