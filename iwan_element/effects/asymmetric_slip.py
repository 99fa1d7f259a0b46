"""Asymmetric slip: different slip thresholds in the two directions.

Physics: a contact whose friction differs with the direction of sliding (a directional
surface lay, a wedge or an inclined contact where a constant load component adds to the
friction one way and subtracts the other, a band brake whose self-energising wrap angle
favours one direction). Every slider of the joint slips forward at ``(1 + a) phi_i`` and
back at ``-(1 - a) phi_i``; its stiffness is unchanged. The macroslip forces are therefore
``(1 + a) Fs`` and ``-(1 - a) Fs`` and the initial stiffness is ``KT`` in both directions.
This is *not* a force offset: in steady cycling a full-slip loop is the symmetric loop
shifted by ``a Fs``, but the shift only builds up as sliders slip (a microslip loop shifts
by ``a`` times the slipped capacity only) and the virgin curves differ forward and back,
whereas a load-cell offset shifts every force by the same constant from the first sample.

Exact on the continuous density (:mod:`iwan_element.effects.engine.law`, law
``sigma_d = kappa_d = 1 +- a``). Wrapped by :class:`~iwan_element.effects.BreakAway`, the laws
multiply: a contact that grips harder one way and whose static friction exceeds its kinetic
friction (a band brake, whose self-energising wrap favours one direction).
"""

from __future__ import annotations

from .base import ParamSpec
from .engine.law import LawEffect

__all__ = ["AsymmetricSlip"]


class AsymmetricSlip(LawEffect):
    """Slip thresholds ``(1 + a) phi_i`` forward and ``(1 - a) phi_i`` back on every slider.

    Parameters
    ----------
    inner : IwanJoint, DiscreteIwan or BreakAway
        The joint whose sliders are affected (a plain joint, or one with break-away; put
        other effects around this). On a DiscreteIwan it acts on that joint's own sliders.
    asymmetry : float, keyword-only
        ``a`` [-], in ``(-1, 1)``; macroslip forces ``Fs (1 + a)`` and ``-Fs (1 - a)``.
    """

    effect = "asymmetric_slip"
    loop_rank = 50
    # the parameters, stored by _set_parameters from specs (SI units)
    asymmetry: float
    specs = (
        ParamSpec(
            "asymmetry",
            "1",
            "relative difference of the forward and backward slip thresholds",
            lower=-1.0,
            upper=1.0,
            fit_bounds=(-0.9, 0.9),
            prior=(-0.9, 0.9),
            neutral=0.0,
            fit_starts=(0.0, 0.1, -0.1),
            open_range=True,
        ),
    )

    def __init__(self, inner, *, asymmetry: float):
        super().__init__(inner)
        self._set_parameters({"asymmetry": asymmetry})
        self._reset_own()

    def own_law(self) -> tuple:
        """Threshold factors ``(sigma_up, sigma_down, kappa_up, kappa_down)`` [-], ``1 +- a``."""
        a = self.asymmetry
        return (1.0 + a, 1.0 - a, 1.0 + a, 1.0 - a)
