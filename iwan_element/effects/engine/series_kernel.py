"""Compiled whole-history route of backlash around the joint and its slider effects:
``Backlash(inner)`` with ``inner`` the Iwan joint, optionally with slip degradation (a wear
bank) or with slider laws (break-away, asymmetric slip: their state table).

The slider thresholds of slip degradation depend on the energy dissipated up to each
commit, so the joint's path behind the gap cannot be found run by run
(:meth:`~iwan_element.effects.Backlash.joint_path` needs a joint whose state depends only on
its turning points). This module runs the elements' own per-sample rule, compiled: for every
sample the backlash solve (rigid stops, or the gap sliding against ``drag``, with the
safeguarded Newton search of :func:`iwan_element.effects.base._find_zero` for the point
where the joint's force reaches the drag), then the commit of the gap, the joint
(:func:`iwan_element.core.masing.masing_step`), the wear bank (:func:`.sliders.bank_step`,
:func:`.sliders.degrade`) and the law table (:mod:`.law_kernel`). The numbers are those of
the elements' ``trial``/``commit`` to round-off (``tests/test_kernel.py``).

State vectors (float arrays, changed in place): joint ``J = [n, u_c, F_c, G_c, I_c, D]``
(depth, committed displacement [m], force [N], ``G`` and ``I_H`` [J], dissipation [J]);
inner ``S = [lambda, W_b, u_b, dir]`` (wear capacity factor, wear work [J], committed
displacement of the slider effects [m], their last direction of motion); gap
``B = [w, e, side, F_inner]`` (joint displacement [m], gap opening [m], contact side,
committed force of the inner element [N]). ``L = (table, pm, p, C)``: the slider laws' state
table (no columns without laws) and its density constants.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...core.masing import masing_step
from .law_kernel import _advance as _law_advance
from .law_kernel import force_at as _law_force
from .law_kernel import monotone_runs
from .sliders import bank_step, degrade

__all__: list[str] = []


@njit(cache=True)
def _trial(c, st, J, e, sl, k, sg, caps, S, L, w, e_new, s_new):
    """Force [N] and tangent [N/m] of the inner element at ``w`` from its committed state."""
    _, F, K, _, _, _, _ = masing_step(
        c, st[0], st[1], st[2], int(J[0]), J[1], J[2], J[3], J[4], w, st[3]
    )
    du = w - S[2]
    if k.size:
        _, dF, dK = bank_step(e, sl, k, sg, caps, caps, du, e_new, s_new)
        F += dF
        K += dK
    if L[0].shape[1]:  # no move: the tangent of going on in the last direction
        d = (1.0 if du > 0.0 else -1.0) if du != 0.0 else S[3]
        dF, dK = _law_force(L[0], d, abs(du), L[1], L[2], L[3])
        F += dF
        K += dK
    return F, K


@njit(cache=True)
def _commit(c, st, J, e, sl, k, sg, phi, caps, S, L, rate, w, e_new, s_new):
    """Commit the inner element at ``w``: its force there [N] (before the wear bank's clip)
    and the slider laws' new state table.
    """
    Fw, _ = _trial(c, st, J, e, sl, k, sg, caps, S, L, w, e_new, s_new)
    n, F, _, _, dD, G, I = masing_step(
        c, st[0], st[1], st[2], int(J[0]), J[1], J[2], J[3], J[4], w, st[3]
    )
    J[0], J[1], J[2], J[3], J[4], J[5] = n, w, F, G, I, J[5] + dD
    du = w - S[2]
    table = L[0]
    if k.size:
        W, _, _ = bank_step(e, sl, k, sg, caps, caps, du, e_new, s_new)
        e[:] = e_new
        sl[:] = s_new
        S[1] += W
        S[0], _ = degrade(e, sg, k, phi, J[5], S[1], rate, caps, caps)
    if table.shape[1] and du != 0.0:
        S[3] = 1.0 if du > 0.0 else -1.0
        table, _ = _law_advance(table, S[3], abs(du), L[1], L[2], L[3])
    S[2] = w
    return Fw, table


@njit(cache=True)
def _zero(c, st, J, e, sl, k, sg, caps, S, L, shift, a, Fa, b, Fb, e_new, s_new):
    """:func:`iwan_element.effects.base._find_zero` on the wearing joint's force minus
    ``shift`` along ``a -> b`` (``Fa``, ``Fb`` of opposite sign): Newton on the tangent,
    bisection safeguard.
    """
    lo, hi = (a, b) if Fa < 0.0 else (b, a)
    x = a
    F = Fa
    K = _trial(c, st, J, e, sl, k, sg, caps, S, L, a + 1e-9 * (b - a), e_new, s_new)[1]
    scale = max(abs(Fa), abs(Fb))
    for _ in range(100):
        x_new = x - F / K if K > 0.0 else 0.5 * (lo + hi)
        if not (min(lo, hi) < x_new < max(lo, hi)):
            x_new = 0.5 * (lo + hi)
        x = x_new
        F, K = _trial(c, st, J, e, sl, k, sg, caps, S, L, x, e_new, s_new)
        F -= shift
        if abs(F) <= 1e-13 * scale or abs(hi - lo) <= 1e-15 * max(abs(a), abs(b), 1e-300):
            break
        if F < 0.0:
            lo = x
        else:
            hi = x
    return x


@njit(cache=True)
def _solve(c, st, J, e, sl, k, sg, caps, S, L, B, u, gap, drag, e_new, s_new):
    """``Backlash._solve_drag`` (``drag > 0``) or ``_solve_rigid``: the joint displacement,
    the contact side, the force at drive displacement ``u`` and the joint displacement where
    the gap began to slide open (``Backlash._slide_at``; NaN for none).
    """
    wc, side, Fin = B[0], B[2], B[3]
    if drag > 0.0:
        w = u - B[1]
        F, _ = _trial(c, st, J, e, sl, k, sg, caps, S, L, w, e_new, s_new)
        for s in (1.0, -1.0):
            if s * F <= drag or side == s:
                continue
            Fc = Fin - s * drag
            if s * Fc >= 0.0:
                w_s = wc
            else:
                w_s = _zero(
                    c,
                    st,
                    J,
                    e,
                    sl,
                    k,
                    sg,
                    caps,
                    S,
                    L,
                    s * drag,
                    wc,
                    Fc,
                    w,
                    F - s * drag,
                    e_new,
                    s_new,
                )
            if s * (u - w_s) >= gap:
                w = u - s * gap
                return w, s, _trial(c, st, J, e, sl, k, sg, caps, S, L, w, e_new, s_new)[0], w_s
            return w_s, 0.0, s * drag, w_s
        return w, side, F, np.nan
    if side == 0.0:
        w = min(max(wc, u - gap), u + gap)
        F = _trial(c, st, J, e, sl, k, sg, caps, S, L, w, e_new, s_new)[0]
        if w == wc:
            return wc, 0.0, F, wc
        return w, 1.0 if w > wc else -1.0, F, wc
    w_contact = u - gap * side
    F, _ = _trial(c, st, J, e, sl, k, sg, caps, S, L, w_contact, e_new, s_new)
    if (w_contact - wc) * side >= 0.0 or F * side > 0.0:
        return w_contact, side, F, np.nan
    w0 = _zero(c, st, J, e, sl, k, sg, caps, S, L, 0.0, wc, Fin, w_contact, F, e_new, s_new)
    w_other = u + gap * side
    if (w_other - w0) * side < 0.0:
        return (
            w_other,
            -side,
            _trial(c, st, J, e, sl, k, sg, caps, S, L, w_other, e_new, s_new)[0],
            w0,
        )
    return w0, 0.0, _trial(c, st, J, e, sl, k, sg, caps, S, L, w0, e_new, s_new)[0], w0


@njit(cache=True)
def _walk_gap(u, c, k, sg, phi, rate, table, pm, p, Cc, gap, drag, ends, out, path):
    """Drive ``Backlash(inner)`` from the virgin state through the samples ``ends`` of ``u``
    (trial and commit at each). ``path=False``: ``out[i]`` is the force at ``ends[i]``.
    ``path=True``: the ends are the last samples of the monotone runs of ``u`` and ``out``
    gets the joint's displacement at every sample (``Backlash.joint_path``: within a run of
    direction ``d`` it follows the drive with the gap's opening held, stops where the gap
    slides open, follows the far stop after contact).
    """
    m = u.size
    st = np.empty((2, m + 2))  # joint stack: u_r, F_r
    at = np.empty(m + 2, np.int64)
    J = np.zeros(6)
    S = np.array([1.0, 0.0, 0.0, 1.0])
    B = np.zeros(4)
    n2 = k.size
    e = np.zeros(n2)
    sl = np.zeros(n2)
    e_new = np.empty(n2)
    s_new = np.empty(n2)
    caps = np.concatenate((phi, phi))
    stack = (st[0], st[1], at, np.empty((4, 0)))
    a = 0
    for r in range(ends.size):
        i = ends[r]
        L = (table, pm, p, Cc)
        e0 = (u[a - 1] if a > 0 else 0.0) - B[0]
        w, side, F, ws = _solve(
            c, stack, J, e, sl, k, sg, caps, S, L, B, u[i], gap, drag, e_new, s_new
        )
        if not path:
            out[r] = F
        else:
            d = 1.0 if u[i] > (u[a - 1] if a > 0 else 0.0) else -1.0
            lim = d * np.inf if np.isnan(ws) else ws
            for j in range(a, i + 1):
                if d > 0.0:
                    out[j] = max(min(u[j] - e0, lim), u[j] - gap)
                else:
                    out[j] = min(max(u[j] - e0, lim), u[j] + gap)
            out[i] = w
            a = i + 1
        B[3], table = _commit(c, stack, J, e, sl, k, sg, phi, caps, S, L, rate, w, e_new, s_new)
        if drag > 0.0:
            B[1] = side * gap if side != 0.0 else min(max(u[i] - w, -gap), gap)
        B[0] = w
        B[2] = side


@njit(cache=True)
def backlash_history(u, c, k, sg, phi, rate, table, pm, p, Cc, gap, drag):
    """Force [N] of ``Backlash(inner)`` at every sample of ``u`` [m] from the virgin state.

    ``c``: the joint's kernel constants; ``k, sg, phi``: the wear bank's slider stiffnesses and
    signs (modified bank, then the plain one) and the slip displacements of one bank [m]
    (empty arrays: no slip degradation), ``rate`` its wear rate [1/J]; ``table, pm, p, Cc``:
    the slider laws' state table and density constants (no columns: no laws); ``gap`` [m],
    ``drag`` [N]: the backlash.
    """
    out = np.empty(u.size)
    _walk_gap(u, c, k, sg, phi, rate, table, pm, p, Cc, gap, drag, np.arange(u.size), out, False)
    return out


@njit(cache=True)
def backlash_path(u, c, table, pm, p, Cc, gap, drag):
    """``Backlash(inner).joint_path(u)`` [m] for an inner element whose state depends only on
    its turning points (the joint, optionally with slider laws: ``table, pm, p, Cc``): one
    trial and commit per monotone run of ``u``.
    """
    starts, dirs, m = monotone_runs(u)
    ends = starts[1 : m + 1] - 1
    out = np.zeros(u.size)
    z = np.zeros(0)
    _walk_gap(u, c, z, z, z, 0.0, table, pm, p, Cc, gap, drag, ends, out, True)
    return out
