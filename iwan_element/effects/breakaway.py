"""Break-away (static above kinetic friction): a stuck slider must reach a higher force to
start sliding than it carries while sliding.

Physics: the classical static/kinetic friction law (Coulomb-Morin; the stick-slip
literature, e.g. Armstrong-Helouvry, Dupont and Canudas de Wit, Automatica 30, 1994, the
"break-away force"). Every slider, once stuck (at the start and after every reversal of its
motion), holds until its force reaches ``r phi_i k_i`` (static), then slides at
``phi_i k_i`` (kinetic) until its motion reverses. In a loop this is a force peak of up to
``r`` times the sliding force just after the joint starts to slide in a new direction, the
signature the ARTS friction-damper records show (1.2-2.5 x the sliding force after each
reversal). The drop from the static to the kinetic level is instantaneous in this
rate-independent law; a real test rig answers that drop with its own structural ringing
(40-50 Hz on the damper rig), which is a property of the rig, not of the joint, and is
removed before fitting (see :func:`iwan_element.diagnose` ``lowpass``).
"""
from __future__ import annotations

from ._base import ParamSpec
from ._sliders import _SliderEffect

__all__ = ["BreakAway"]


class BreakAway(_SliderEffect):
    """Static threshold ``r phi_i``, kinetic threshold ``phi_i`` on every slider.

    Parameters
    ----------
    inner : IwanJoint or DiscreteIwan
        The joint (a plain joint; put other effects around this).
    ratio : float, keyword-only
        Static over kinetic friction ``r`` [-], ``>= 1`` (1: no break-away peak).
    n_sliders : int, keyword-only
        Sliders of the correction bank.
    """

    effect = "breakaway"
    specs = (ParamSpec("ratio", "1", "static over kinetic slip threshold", lower=1.0,
                       fit_bounds=(1.0, 3.0), fit_starts=(1.0, 1.2, 1.5, 2.0)),)
    #: Ratios scanned for a start: the force is a staircase in the ratio (a slider breaks at
    #: one sample or the next), so the least-squares step cannot move it; the best grid value
    #: is then polished by a bounded scalar search between its neighbours.
    fit_scan = tuple(1.0 + 0.1 * k for k in range(21))
    fit_scan_refine = True

    def __init__(self, inner, *, ratio: float, n_sliders: int = 128):
        super().__init__(inner, n_sliders=n_sliders)
        self._set_parameters({"ratio": ratio})
        self._reset_own()

    def _caps(self):
        p = self._phi
        s = self.ratio * p
        return s, s, p, p
