"""Slip degradation (wear): slip capacity falls with the energy the joint has dissipated.

Physics: fretting wear and the loss of preload it causes lower the friction capacity of the
contact as energy is dissipated in it, while the elastic stiffness of the stuck contact
(set by the clamped geometry) stays. Archard-type wear makes the worn volume proportional to
the frictional work, so the capacity is taken as ``lambda(D) = exp(-rate D)`` times the
original, with ``D`` the energy dissipated by the joint so far [J]. Every slider's threshold
is ``lambda phi_i``; its stiffness ``k_i`` is unchanged, so ``KT`` stays and ``Fs`` becomes
``lambda Fs``. A slider stretched beyond its shrunken threshold slips back to it at the
commit (the elastic energy released is dissipated).
"""
from __future__ import annotations

import math

import numpy as np

from ._base import ParamSpec
from ._sliders import _SliderEffect

__all__ = ["SlipDegradation"]


class SlipDegradation(_SliderEffect):
    """Slider thresholds ``lambda phi_i``, ``lambda = exp(-rate D)``, stiffness unchanged.

    Parameters
    ----------
    inner : IwanJoint or DiscreteIwan
        The joint that wears (a plain joint; put other effects around this).
    rate : float, keyword-only
        Decay rate of the slip capacity per dissipated energy [1/J], ``>= 0``.
    n_sliders : int, keyword-only
        Sliders of the correction bank.
    """

    effect = "slip_degradation"
    specs = (ParamSpec("rate", "1/J", "relative loss of slip capacity per joule dissipated",
                       fs_power=-1, ref="D_ref", fit_bounds=(0.0, 5.0), fit_starts=(0.0, 0.2)),)

    def __init__(self, inner, *, rate: float, n_sliders: int = 128):
        super().__init__(inner, n_sliders=n_sliders)
        self._set_parameters({"rate": rate})
        self._reset_own()

    def _reset_own(self):
        self._lam = 1.0
        super()._reset_own()

    @property
    def capacity_factor(self) -> float:
        """Committed ``lambda`` in (0, 1]."""
        return self._lam

    def _caps(self):
        c = self._lam * self._phi
        return c, c, c, c

    needs_energy = True

    def _after_commit(self) -> None:
        self._after_commit_energy(self._inner.dissipated_energy)

    def _after_commit_energy(self, D_inner: float) -> None:
        """Update ``lambda`` from the joint's dissipated energy and clip the stretches."""
        D = D_inner + self._Wb - self._stored(self._e)
        self._lam = math.exp(-self.rate * max(D, 0.0))
        n = self._n
        cap = self._lam * self._phi
        self._e[:n] = np.clip(self._e[:n], -cap, cap)
        self._refresh_caps()
