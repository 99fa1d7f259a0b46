"""Viscous damping: a dashpot in parallel with the joint.

Physics: material and air damping of the jointed structure act in parallel with the joint's
friction, ``F = F_j(u) + c v`` (docs/equations.md section 7, the damping floor of a jointed
beam's modal damping at low amplitude, where the joint's hysteresis fades). In the amplitude
domain it is a constant added modal damping ratio ``zeta_v = c r^2 / (2 m omega)``.
"""

from __future__ import annotations

from .base import Effect, ParamSpec

__all__ = ["ViscousDamping"]


class ViscousDamping(Effect):
    """A dashpot in parallel with the joint: ``F = F_j + c v``.

    Parameters
    ----------
    inner : joint element
    c : float, keyword-only
        Damping coefficient [N s/m], ``>= 0``.

    Notes
    -----
    The dashpot's dissipation over a step is ``c (v_0 + v_1)/2 (u_1 - u_0)`` (the trapezoidal
    value of ``int c v du``), exact when the velocity is linear in time over the step.
    Modal form (:meth:`modal_form`): an added damping ratio ``zeta_v`` [-], frequency unchanged.
    """

    effect = "viscous_damping"
    needs = ("rate",)
    loop_rank = 10
    kind = "dissipation"
    modal_floor = True
    # the parameters, stored by _set_parameters from specs (SI units)
    c: float
    specs = (
        ParamSpec(
            "c",
            "N s/m",
            "dashpot coefficient in parallel with the joint",
            fs_power=1,
            ref="v_rms",
            fit_bounds=(0.0, 2.0),
            prior=(0.0, 2.0),
            neutral=0.0,
            fit_starts=(0.0, 0.03),
        ),
    )
    modal_specs = (
        ParamSpec(
            "zeta_v",
            "1",
            "added modal viscous damping ratio",
            ref="zeta_ref",
            ref_power=-1,
            fit_bounds=(0.0, 100.0),
            prior=(0.0, 100.0),
            neutral=0.0,
            fit_starts=(0.0, 0.5, 5.0),
        ),
    )

    def __init__(self, inner, *, c: float):
        super().__init__(inner)
        self._set_parameters({"c": c})
        self._reset_own()

    def _reset_own(self):
        self._v = 0.0

    @classmethod
    def vector_force(cls, F, u, v, *, c):
        """Force [N]: the inner force ``F`` [N] plus ``c v`` (``v`` [m/s], ``c`` [N s/m])."""
        return F + c * v

    @classmethod
    def vector_tangent(cls, u, v, *, c):
        """``(0, c [N s/m])``: the dashpot's tangents."""
        return 0.0, c

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, zeta_v):
        """Frequency [Hz] and damping ratio [-] with ``zeta_v`` added (frequency unchanged)."""
        return frequency, damping + zeta_v

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Joint dashpot ``c = 2 zeta_v omega0 m / r^2`` [N s/m] from the modal ratio."""
        return {"c": 2.0 * values["zeta_v"] * omega0 * modal_mass / slip_per_amplitude**2}

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent ``dF/du`` [N/m] (the velocity tangent is ``c``)."""
        F, K = self._inner.trial(u, v)
        F += self.c * v
        self._set_trial(u, v, F)
        return F, K

    def _commit(self) -> None:
        W0 = self._inner.work
        D0 = self._inner.dissipated_energy
        self._inner.commit()
        dvisc = self.c * 0.5 * (self._v + self._tv) * (self._tu - self._u)
        self._W += self._inner.work - W0 + dvisc
        self._D += self._inner.dissipated_energy - D0 + dvisc
        self._v = self._tv
