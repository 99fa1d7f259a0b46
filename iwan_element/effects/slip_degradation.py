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

import numpy as np
from numba import njit

from .base import ParamSpec
from .engine.sliders import SliderEffect, bank_step, degrade

__all__ = ["SlipDegradation"]


@njit(cache=True)
def _degrade_history(e, slip, k, sgn, phi, lam, Wb, rate, u, prev, D_inner):
    """The per-sample rule of the correction bank along ``u`` [m] (compiled): each step moves
    every slider exactly (:func:`.engine.sliders.bank_step`, caps ``lambda phi`` in the modified
    bank, ``phi`` in the plain one), then ``lambda = exp(-rate D)`` from the energy
    dissipated so far and the modified sliders are clipped to their shrunken caps.

    ``e, slip``: both banks' stretches [m] and slip flags (modified first), changed in place;
    ``prev``: the displacement they were committed at [m]; ``D_inner``: dissipated energy of
    the wrapped joint after each step [J]. Returns ``(correction force per sample [N],
    lambda, Wb)``.
    """
    n = phi.size
    caps = np.empty(2 * n)
    caps[n:] = phi
    for j in range(n):
        caps[j] = lam * phi[j]
    out = np.empty(u.size)
    e_new = np.empty(2 * n)
    s_new = np.empty(2 * n)
    for i in range(u.size):
        du = u[i] - prev
        if du == 0.0:
            F = 0.0
            for j in range(2 * n):
                F += sgn[j] * k[j] * e[j]
            out[i] = F
            continue
        W, F, _ = bank_step(e, slip, k, sgn, caps, caps, du, e_new, s_new)
        e[:] = e_new
        slip[:] = s_new
        Wb += W
        out[i] = F  # the step's force, before the commit
        lam, _ = degrade(e, sgn, k, phi, D_inner[i], Wb, rate, caps, caps)
        prev = u[i]
    return out, lam, Wb


class SlipDegradation(SliderEffect):
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
    loop_rank = 40
    # the parameters, stored by _set_parameters from specs (SI units)
    rate: float
    specs = (
        ParamSpec(
            "rate",
            "1/J",
            "relative loss of slip capacity per joule dissipated",
            fs_power=-1,
            ref="D_ref",
            fit_bounds=(0.0, 5.0),
            prior=(0.0, 5.0),
            neutral=0.0,
            fit_starts=(0.0, 0.2),
        ),
    )

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

    def _after_commit(self) -> float:
        return self._after_commit_energy(self._inner.dissipated_energy)

    def _correction_energy(self, u: np.ndarray, D_inner, prev: float = 0.0) -> np.ndarray:
        """The per-sample rule of :meth:`SliderEffect._correction_energy`, compiled
        (:func:`_degrade_history`), from the state committed at ``prev`` [m].
        """
        D_inner = np.ascontiguousarray(D_inner, dtype=float)
        e, slip = self._e.copy(), self._slip.copy()
        out, self._lam, self._Wb = _degrade_history(
            e,
            slip,
            self._k,
            self._sign,
            self._phi,
            self._lam,
            self._Wb,
            self.rate,
            np.ascontiguousarray(u, dtype=float),
            float(prev),
            D_inner,
        )
        self._e, self._slip = e, slip
        self._refresh_caps()
        return out

    def _after_commit_energy(self, D_inner: float) -> float:
        """Update ``lambda`` from the joint's dissipated energy, clip the stretches and the
        caps (:func:`degrade`); returns the stored energy of the banks after the clip [J].
        """
        if self._cap_up is None:
            self._refresh_caps()
        up, dn = self._cap_up, self._cap_dn
        assert up is not None and dn is not None  # allocated by _refresh_caps
        self._lam, stored = degrade(
            self._e, self._sign, self._k, self._phi, D_inner, self._Wb, self.rate, *up
        )
        np.copyto(dn[0], up[0])
        np.copyto(dn[1], up[1])
        return stored
