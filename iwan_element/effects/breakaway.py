"""Break-away (static above kinetic friction): a stuck slider must reach a higher force to
start sliding than it carries while sliding.

Physics: the classical static/kinetic friction law (Coulomb-Morin; the stick-slip
literature, e.g. Armstrong-Helouvry, Dupont and Canudas de Wit, Automatica 30, 1994, the
"break-away force"). Every slider of the joint (slip displacement ``phi``, docs/equations.md
section 2), once stuck (at the start and after every reversal of its motion), holds until its
stretch reaches ``r phi`` (static), then slides at stretch ``phi`` (kinetic) until its
motion reverses. In a loop this is a force peak of up to ``r`` times the sliding force just
after the joint starts to slide in a new direction, the signature the ARTS friction-damper
records show (1.2-2.5 x the sliding force after each reversal). The drop from the static to
the kinetic level is instantaneous in this rate-independent law; a real test rig answers
that drop with its own structural ringing (40-50 Hz on the damper rig), which is a property
of the rig, not of the joint, and is removed before fitting (see :func:`iwan_element.diagnose`
``lowpass``).

Exact on the continuous density (no slider bank; :mod:`iwan_element.effects.engine.law`, whose
law is here ``sigma = r``, ``kappa = 1`` both ways), so the force, and the misfit of a fit,
are continuous in ``r`` (a bank of discrete sliders makes them a staircase: each slider
breaks at one sample or the next). On a :class:`~iwan_element.core.discrete.DiscreteIwan` it
acts on that joint's own sliders. At ``r = 1`` these are the Masing rules of the plain joint
and the element is exactly its joint. On :class:`~iwan_element.effects.AsymmetricSlip` the two
laws multiply (static ``r (1 +- a) phi``, kinetic ``(1 +- a) phi``). Checked against an
independent plain-Python slider bank, to which a dense bank converges
(``tests/test_breakaway.py``).
"""

from __future__ import annotations

from .base import ParamSpec
from .engine.law import LawEffect

__all__ = ["BreakAway"]


class BreakAway(LawEffect):
    """Static threshold ``r phi``, kinetic threshold ``phi`` on every slider of the joint.

    Parameters
    ----------
    inner : IwanJoint, DiscreteIwan or AsymmetricSlip
        The joint (a plain joint, or one with direction-dependent slip; put other effects
        around this). For a :class:`~iwan_element.core.discrete.DiscreteIwan` the effect
        acts on its own sliders.
    ratio : float, keyword-only
        Static over kinetic friction ``r`` [-], ``>= 1`` (1: no break-away peak).
    """

    effect = "breakaway"
    loop_rank = 60
    # the parameters, stored by _set_parameters from specs (SI units)
    ratio: float
    specs = (
        ParamSpec(
            "ratio",
            "1",
            "static over kinetic slip threshold",
            lower=1.0,
            fit_bounds=(1.0, 3.0),
            prior=(1.0, 3.0),
            neutral=1.0,
            fit_starts=(1.0, 1.2, 1.5, 2.0),
        ),
    )
    #: Ratios scanned for a start: the force changes only to second order in ``ratio - 1``
    #: near 1 (the static-kinetic jump and the shift of the break both scale with it), so a
    #: fit started at 1 has no gradient to follow.
    fit_scan = tuple(1.0 + 0.1 * k for k in range(21))
    #: The spike's sliders break all at once: the force jumps, and whether they break in a
    #: half cycle is a yes/no event of the parameters (fits restart around their result).
    force_jumps = True

    def __init__(self, inner, *, ratio: float):
        super().__init__(inner)
        self._set_parameters({"ratio": ratio})
        self._reset_own()

    def own_law(self) -> tuple:
        """Threshold factors ``(sigma_up, sigma_down, kappa_up, kappa_down) = (r, r, 1, 1)``."""
        r = self.ratio
        return (r, r, 1.0, 1.0)
