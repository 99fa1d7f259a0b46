"""Slider-level effects: physics that changes the slip thresholds of the joint's sliders.

An Iwan joint is a bank of parallel Jenkins sliders (a spring ``k_i`` in series with a
Coulomb slider that slips at stretch ``phi_i``, docs/equations.md section 1, paper eq. 3). Effects
that change *how the sliders slip* (different thresholds forward and back, thresholds
falling with wear, a static threshold above the kinetic one) cannot be written as a function
of the joint's force; they act on each slider. Laws fixed per direction (asymmetric slip,
break-away) are evaluated exactly on the continuous density (:mod:`.law`); thresholds that
evolve with the state (slip degradation) use this module, without giving up the exact
joint:

``F = F_inner(u) + [F_bank(u; modified thresholds) - F_bank(u; plain thresholds)]``

where ``F_inner`` is the wrapped joint's own (exact) force and the bank is the moment-matched
discretisation of the same joint (:func:`~iwan_element.core.discrete.slider_distribution`,
which reproduces ``KT`` and ``Fs`` exactly). With the effect's parameters at their neutral
values the bracket is identically zero, so the effect reduces *exactly* to the wrapped joint;
otherwise the discretisation error is proportional to the size of the effect (about 0.5 %
of the effect's force change with 128 sliders).

Each slider's step is exact for a linear move: it sticks until its stretch reaches the
static threshold of the direction of motion, then slides at the kinetic threshold; the work
is integrated per slider, and the dissipation is the work minus the stored elastic energy.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...core.discrete import slider_distribution
from ..base import Effect, require_plain_joint

__all__ = ["SliderEffect"]

N_SLIDERS = 128


@njit(cache=True)
def bank_step(e, s, k, sgn, cs, ck, du, e_new, s_new):
    """Every slider's exact linear move ``du`` [m] (compiled): stick until the stretch in the
    direction of motion reaches the static cap ``cs``, then slide at the kinetic cap ``ck``.

    Writes the new stretches [m] to ``e_new`` and slip states (+1/-1 sliding that way, 0
    stuck) to ``s_new``; returns ``(W, F, K)``, the sums weighted by ``sgn`` (modified bank
    +1, plain bank -1) of the work [J], the force ``k e`` [N] and the stiffness of the stuck
    sliders [N/m]. (Arrays are passed in, not returned: a cached function that also runs
    inside another compiled one must not box arrays for Python.)
    """
    n = e.size
    W = 0.0
    F = 0.0
    K = 0.0
    if du == 0.0:
        for i in range(n):
            e_new[i] = e[i]
            s_new[i] = s[i]
            F += sgn[i] * k[i] * e[i]
            if s[i] == 0.0:
                K += sgn[i] * k[i]
        return W, F, K
    d = 1.0 if du > 0.0 else -1.0
    adu = abs(du)
    for i in range(n):
        ep = d * e[i]  # stretch in the direction of motion
        end = ep + adu
        if s[i] == d:  # sliding: stays at the kinetic cap
            ep_new = ck[i]
            work = k[i] * ck[i] * adu
            s_new[i] = d
        elif end > cs[i]:  # breaks: stick up to the static cap, slide
            ep_new = ck[i]
            work = 0.5 * k[i] * (cs[i] ** 2 - ep**2) + k[i] * ck[i] * (end - cs[i])
            s_new[i] = d
        else:  # stuck
            ep_new = end
            work = 0.5 * k[i] * (end**2 - ep**2)
            s_new[i] = 0.0
            K += sgn[i] * k[i]
        e_new[i] = d * ep_new
        W += sgn[i] * work
        F += sgn[i] * k[i] * e_new[i]
    return W, F, K


@njit(cache=True)
def degrade(e, sgn, k, phi, D_inner, Wb, rate, cap_s, cap_k):
    """The commit of the correction bank (compiled): ``lambda = exp(-rate D)`` from the energy
    dissipated so far (``D = D_inner + Wb - stored``), the modified sliders clipped to their
    shrunken caps ``lambda phi`` (``e`` changed in place) and the caps of the modified bank
    written to the first entries of ``cap_s``, ``cap_k``. Returns ``(lambda, stored energy
    after the clip [J])``.
    """
    n = phi.size
    stored = 0.0
    for j in range(2 * n):
        stored += sgn[j] * k[j] * (e[j] * e[j])
    lam = math.exp(-rate * max(D_inner + Wb - 0.5 * stored, 0.0))
    after = 0.0
    for j in range(2 * n):
        if j < n:
            c = lam * phi[j]
            e[j] = max(min(e[j], c), -c)
            cap_s[j] = c
            cap_k[j] = c
        after += sgn[j] * k[j] * (e[j] * e[j])
    return lam, 0.5 * after


class SliderEffect(Effect):
    """Base of slider-level effects whose thresholds evolve with the dissipated energy.
    Subclasses define :meth:`_caps` (static and kinetic thresholds of the modified bank,
    forward and back, as stretches [m]), :meth:`_after_commit` and
    :meth:`_after_commit_energy` (the thresholds' update from the committed state).
    """

    structure = "energy"

    def __init__(self, inner, *, n_sliders: int = N_SLIDERS):
        super().__init__(inner)
        require_plain_joint(inner, "a slider-level effect")
        k, phi = slider_distribution(inner.params, n_sliders)
        self._k = np.concatenate([k, k])  # modified bank, then the plain reference bank
        self._phi = phi
        self._n = k.size
        self._sign = np.concatenate([np.ones(k.size), -np.ones(k.size)])
        # thresholds (static, kinetic) of both banks, allocated by _refresh_caps
        self._cap_up: tuple[np.ndarray, np.ndarray] | None = None
        self._cap_dn: tuple[np.ndarray, np.ndarray] | None = None
        self._sk = self._sign * self._k

    # ---- thresholds
    def _caps(self):
        """``(static_up, static_down, kinetic_up, kinetic_down)`` of the modified bank, each
        an array of positive stretches [m] (``down`` is the magnitude for negative force).
        """
        raise NotImplementedError

    def _after_commit_energy(self, D_inner: float) -> float:
        """Update the thresholds from the wrapped joint's dissipated energy ``D_inner`` [J];
        returns the banks' stored energy after the update [J].
        """
        raise NotImplementedError

    def _refresh_caps(self) -> None:
        """Cache the thresholds of both banks (call after they change)."""
        n = self._n
        if getattr(self, "_cap_up", None) is None:  # both banks' caps, filled in place
            self._cap_up = (np.tile(self._phi, 2), np.tile(self._phi, 2))
            self._cap_dn = (np.tile(self._phi, 2), np.tile(self._phi, 2))
        up, dn = self._cap_up, self._cap_dn
        assert up is not None and dn is not None  # allocated just above
        su, sd, ku, kd = self._caps()
        up[0][:n] = su
        up[1][:n] = ku
        dn[0][:n] = sd
        dn[1][:n] = kd

    def _reset_own(self):
        self._e = np.zeros(2 * self._n)  # slider stretches [m]
        self._slip = np.zeros(2 * self._n)  # +1/-1 sliding forward/back, 0 stuck
        self._Wb = 0.0  # work of (modified - plain) bank [J]
        self._Db = 0.0
        self._ub = 0.0
        self._last = None
        self._refresh_caps()

    def _step(self, du: float):
        """Stretches, slip states and the signed work, force and stiffness of both banks for a
        linear move ``du`` [m] (:func:`bank_step`).
        """
        caps = self._cap_up if du > 0.0 else self._cap_dn
        assert caps is not None  # _reset_own allocates them (_refresh_caps)
        cs, ck = caps
        e, s = np.empty(self._e.size), np.empty(self._e.size)
        W, F, K = bank_step(self._e, self._slip, self._k, self._sign, cs, ck, du, e, s)
        return e, s, W, F, K

    def _stored(self, e):
        return 0.5 * float(self._sk @ (e * e))

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        e, s, work, dF, dK = self._step(float(u) - self._ub)
        self._last = (float(u), e, s, work)
        F += dF
        K += dK
        self._set_trial(u, v, F)
        return F, K

    def _commit(self) -> None:
        inner = self._inner
        inner.commit()
        last = self._last
        if last is not None and last[0] == float(self._tu):
            _, e, s, work = last
        else:
            e, s, work, _, _ = self._step(float(self._tu) - self._ub)
        self._last = None
        self._e, self._slip = e, s
        self._Wb += work
        self._ub = float(self._tu)
        stored = self._after_commit()
        self._W = inner.work + self._Wb
        self._D = (
            inner.dissipated_energy
            + self._Wb
            - (self._stored(self._e) if stored is None else stored)
        )

    def _after_commit(self):
        """Update the thresholds after a commit; may return the banks' stored energy [J]."""
        return None

    def correction_history(self, u, D_inner=None) -> np.ndarray:
        """Force correction ``F_bank(modified) - F_bank(plain)`` [N] along a displacement
        history ``u`` [m] from the virgin state, on a private state (this element is
        untouched). ``D_inner``: dissipated energy of the wrapped joint after each step [J].
        The same slider steps as :meth:`trial`/
        :meth:`commit`, with the bookkeeping the force does not need left out.
        """
        state = (self._e, self._slip, self._Wb, self._Db, self._ub, self._last)
        lam = getattr(self, "_lam", None)
        try:
            self._reset_own()
            return self._correction_energy(np.asarray(u, float), D_inner)
        finally:
            self._e, self._slip, self._Wb, self._Db, self._ub, self._last = state
            if lam is not None:
                self._lam = lam
            self._refresh_caps()

    def _correction_energy(self, u: np.ndarray, D_inner, prev: float = 0.0) -> np.ndarray:
        """Thresholds that fall with the dissipated energy: step by step (the reference;
        :class:`~iwan_element.effects.SlipDegradation` runs the same rule compiled).
        ``prev``: the displacement the state was committed at [m].
        """
        sk = self._sk
        out = np.empty(u.size)
        for i, x in enumerate(u.tolist()):
            du = x - prev
            if du != 0.0:
                e, s, work, F, _ = self._step(du)
                self._e, self._slip = e, s
                self._Wb += work
                out[i] = F  # the step's force, before the commit
                self._after_commit_energy(D_inner[i])  # lowers the thresholds
                prev = x
            else:
                out[i] = float(sk @ self._e)
        return out
