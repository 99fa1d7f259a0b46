"""Compiled whole-history route of backlash around a wearing joint:
``Backlash(SlipDegradation(IwanJoint))``.

The slider thresholds of slip degradation depend on the energy dissipated up to each
commit, so the joint's path behind the gap cannot be found run by run
(:meth:`~iwan_element.effects.Backlash.joint_path` needs a joint whose state depends only on
its turning points). This module runs the elements' own per-sample rule, compiled: for every
sample the backlash solve (rigid stops, or the gap sliding against ``drag``, with the
safeguarded Newton search of :func:`._base._find_zero` for the point where the joint's force
reaches the drag), then the commit of the gap, the joint (:func:`iwan_element.core.masing.
masing_step`) and the wear bank (:func:`._sliders._bank_step`, :func:`.slip_degradation.
_degrade`). The numbers are those of the elements' ``trial``/``commit`` to round-off
(``tests/test_kernel.py``).

State vectors (float arrays, changed in place): joint ``J = [n, u_c, F_c, G_c, I_c, D]``
(depth, committed displacement [m], force [N], ``G`` and ``I_H`` [J], dissipation [J]);
wear ``S = [lambda, W_b, u_b]``; gap ``B = [w, e, side, F_inner]`` (joint displacement [m],
gap opening [m], contact side, committed force of the wearing joint [N]).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..core.masing import masing_step
from ._sliders import _bank_step
from .slip_degradation import _degrade

__all__: list[str] = []


@njit(cache=True)
def _trial(c, st, J, e, sl, k, sg, caps, S, w, e_new, s_new):
    """Force [N] and tangent [N/m] of the wearing joint at ``w`` from its committed state."""
    _, F, K, _, _, _, _ = masing_step(c, st[0], st[1], st[2], int(J[0]), J[1], J[2], J[3], J[4],
                                      w, st[3])
    _, dF, dK = _bank_step(e, sl, k, sg, caps, caps, w - S[2], e_new, s_new)
    return F + dF, K + dK


@njit(cache=True)
def _commit(c, st, J, e, sl, k, sg, phi, caps, S, rate, w, e_new, s_new):
    """Commit the wearing joint at ``w``; returns its force there [N] (before the clip)."""
    n, F, _, _, dD, G, I = masing_step(c, st[0], st[1], st[2], int(J[0]), J[1], J[2], J[3],
                                       J[4], w, st[3])
    J[0], J[1], J[2], J[3], J[4], J[5] = n, w, F, G, I, J[5] + dD
    W, dF, _ = _bank_step(e, sl, k, sg, caps, caps, w - S[2], e_new, s_new)
    e[:] = e_new
    sl[:] = s_new
    S[1] += W
    S[2] = w
    S[0], _ = _degrade(e, sg, k, phi, J[5], S[1], rate, caps, caps)
    return F + dF


@njit(cache=True)
def _zero(c, st, J, e, sl, k, sg, caps, S, shift, a, Fa, b, Fb, e_new, s_new):
    """:func:`._base._find_zero` on the wearing joint's force minus ``shift`` along
    ``a -> b`` (``Fa``, ``Fb`` of opposite sign): Newton on the tangent, bisection safeguard."""
    lo, hi = (a, b) if Fa < 0.0 else (b, a)
    x = a
    F = Fa
    K = _trial(c, st, J, e, sl, k, sg, caps, S, a + 1e-9 * (b - a), e_new, s_new)[1]
    scale = max(abs(Fa), abs(Fb))
    for _ in range(100):
        x_new = x - F / K if K > 0.0 else 0.5 * (lo + hi)
        if not (min(lo, hi) < x_new < max(lo, hi)):
            x_new = 0.5 * (lo + hi)
        x = x_new
        F, K = _trial(c, st, J, e, sl, k, sg, caps, S, x, e_new, s_new)
        F -= shift
        if abs(F) <= 1e-13 * scale or abs(hi - lo) <= 1e-15 * max(abs(a), abs(b), 1e-300):
            break
        if F < 0.0:
            lo = x
        else:
            hi = x
    return x


@njit(cache=True)
def _solve(c, st, J, e, sl, k, sg, caps, S, B, u, gap, drag, e_new, s_new):
    """``Backlash._solve_drag`` (``drag > 0``) or ``_solve_rigid``: the joint displacement,
    the contact side and the force at drive displacement ``u``."""
    wc, side, Fin = B[0], B[2], B[3]
    if drag > 0.0:
        w = u - B[1]
        F, _ = _trial(c, st, J, e, sl, k, sg, caps, S, w, e_new, s_new)
        for s in (1.0, -1.0):
            if s * F <= drag or side == s:
                continue
            Fc = Fin - s * drag
            if s * Fc >= 0.0:
                w_s = wc
            else:
                w_s = _zero(c, st, J, e, sl, k, sg, caps, S, s * drag, wc, Fc, w, F - s * drag,
                            e_new, s_new)
            if s * (u - w_s) >= gap:
                w = u - s * gap
                return w, s, _trial(c, st, J, e, sl, k, sg, caps, S, w, e_new, s_new)[0]
            return w_s, 0.0, s * drag
        return w, side, F
    if side == 0.0:
        w = min(max(wc, u - gap), u + gap)
        F = _trial(c, st, J, e, sl, k, sg, caps, S, w, e_new, s_new)[0]
        if w == wc:
            return wc, 0.0, F
        return w, 1.0 if w > wc else -1.0, F
    w_contact = u - gap * side
    F, _ = _trial(c, st, J, e, sl, k, sg, caps, S, w_contact, e_new, s_new)
    if (w_contact - wc) * side >= 0.0 or F * side > 0.0:
        return w_contact, side, F
    w0 = _zero(c, st, J, e, sl, k, sg, caps, S, 0.0, wc, Fin, w_contact, F, e_new, s_new)
    w_other = u + gap * side
    if (w_other - w0) * side < 0.0:
        return w_other, -side, _trial(c, st, J, e, sl, k, sg, caps, S, w_other, e_new, s_new)[0]
    return w0, 0.0, _trial(c, st, J, e, sl, k, sg, caps, S, w0, e_new, s_new)[0]


@njit(cache=True)
def backlash_wear_history(u, c, k, sg, phi, rate, gap, drag):
    """Force [N] of ``Backlash(SlipDegradation(IwanJoint))`` at every sample of ``u`` [m]
    from the virgin state. ``c``: the joint's kernel constants; ``k, sg, phi``: the wear
    bank's slider stiffnesses and signs (modified bank, then the plain one) and the slip
    displacements of one bank [m]; ``rate`` [1/J], ``gap`` [m], ``drag`` [N]."""
    m = u.size
    st = np.empty((2, m + 2))                       # joint stack: u_r, F_r
    J = np.zeros(6)
    S = np.array([1.0, 0.0, 0.0])
    B = np.zeros(4)
    n2 = k.size
    e = np.zeros(n2)
    sl = np.zeros(n2)
    e_new = np.empty(n2)
    s_new = np.empty(n2)
    caps = np.concatenate((phi, phi))
    at = np.empty(m + 2, np.int64)
    out = np.empty(m)
    stack = (st[0], st[1], at, np.empty((4, 0)))     # stack arrays, no segments recorded
    for i in range(m):
        w, side, F = _solve(c, stack, J, e, sl, k, sg, caps, S, B, u[i], gap,
                            drag, e_new, s_new)
        out[i] = F
        B[3] = _commit(c, stack, J, e, sl, k, sg, phi, caps, S, rate, w, e_new,
                       s_new)
        if drag > 0.0:
            B[1] = side * gap if side != 0.0 else min(max(u[i] - w, -gap), gap)
        B[0] = w
        B[2] = side
    return out
