"""Compiled state of the exact slider laws (:mod:`iwan_element.effects.engine.law`).

The sliders' state is a table of rows (one column per row): an interval ``[a, b]`` of slip
displacement ``phi`` [m] (``a == b`` for a point mass of stiffness ``w`` [N/m]), the state
``e = s phi + c`` of its sliders, their slip flag (+1/-1 sliding that way, 0 stuck), the law
of the bank the row belongs to (static and kinetic factors up and down) and its sign. The
continuous rows carry the density ``rho = C / pm (phi / pm)^(p - 1)`` (``p = chi + 1``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__: list[str] = []

# rows of the state table
A, B, W, SU, SD, KU, KD, SG, S, C, SL = range(11)
N_ROWS = 11


@njit(cache=True)
def _moments(st, r, x, brk, pm, p, Cc):
    """``int rho phi^k`` over ``[a, x]`` of row ``r`` for ``k = 0, 1, 2`` (a point mass: all
    its weight if ``brk``).
    """
    a = st[A, r]
    w = st[W, r]
    if w > 0.0:
        if brk:
            return w, w * a, w * a * a
        return 0.0, 0.0, 0.0
    xr = x / pm
    ar = a / pm
    px = xr**p
    pa = ar**p
    M0 = Cc * (px - pa) / p
    px *= xr
    pa *= ar
    M1 = Cc * pm * (px - pa) / (p + 1.0)
    px *= xr
    pa *= ar
    M2 = Cc * (pm * pm) * (px - pa) / (p + 2.0)
    return M0, M1, M2


@njit(cache=True)
def _limit(st, r, d, delta):
    """Broken part of row ``r`` after a travel ``delta >= 0`` in direction ``d``: the sliders
    below ``raw = (c_d + delta)/(sigma_d - s_d)`` have reached their static threshold.
    Returns ``(x, brk, s_d, c_d, raw, den)``, ``x`` = ``raw`` clipped to the row.
    """
    s_d = d * st[S, r]
    c_d = d * st[C, r]
    num = c_d + delta
    den = (st[SU, r] if d > 0 else st[SD, r]) - s_d
    if den > 0.0:
        raw = num / den
    elif num > 0.0:
        raw = np.inf
    else:
        raw = -np.inf
    if st[SL, r] == d:
        raw = np.inf
    x = min(max(raw, st[A, r]), st[B, r])
    return x, raw > st[A, r], s_d, c_d, raw, den


@njit(cache=True)
def _row_force(st, r, d, dl, M0t, M1t, pm, p, Cc):
    """Force [N] and tangent [N/m] of row ``r`` (unsigned, in direction ``d``) after a travel
    ``dl >= 0``: ``kappa_d`` times the broken sliders' moment plus the stuck sliders'
    stretch; ``M0t, M1t``: the row's total moments.
    """
    sig = st[SU, r] if d > 0 else st[SD, r]
    kap = st[KU, r] if d > 0 else st[KD, r]
    x, brk, s_d, c_d, raw, den = _limit(st, r, d, dl)
    M0b, M1b, _ = _moments(st, r, x, brk, pm, p, Cc)
    f = kap * M1b + s_d * (M1t - M1b) + (c_d + dl) * (M0t - M0b)
    k = M0t - M0b
    if st[W, r] == 0.0 and raw > st[A, r] and raw < st[B, r] and den > 0.0:
        rho = Cc / pm * (x / pm) ** (p - 1.0)
        k -= rho * (sig - kap) * x / den
    return f, k


@njit(cache=True)
def _force(st, d, deltas, pm, p, Cc):
    """Signed force [N] and tangent [N/m] of the banks after each travel ``deltas[j] >= 0``
    [m] from the current state in direction ``d``.
    """
    m = deltas.size
    F = np.zeros(m)
    K = np.zeros(m)
    for r in range(st.shape[1]):
        M0t, M1t, _ = _moments(st, r, st[B, r], True, pm, p, Cc)
        sg = st[SG, r]
        for j in range(m):
            f, k = _row_force(st, r, d, deltas[j], M0t, M1t, pm, p, Cc)
            F[j] += sg * f
            K[j] += sg * k
    return d * F, K


@njit(cache=True)
def force_at(st, d, delta, pm, p, Cc):
    """:func:`_force` for one travel ``delta`` (scalars in and out, no arrays)."""
    F = 0.0
    K = 0.0
    for r in range(st.shape[1]):
        M0t, M1t, _ = _moments(st, r, st[B, r], True, pm, p, Cc)
        f, k = _row_force(st, r, d, delta, M0t, M1t, pm, p, Cc)
        F += st[SG, r] * f
        K += st[SG, r] * k
    return d * F, K


@njit(cache=True)
def _advance(st, d, delta, pm, p, Cc):
    """Move the state by a travel ``delta >= 0`` in direction ``d`` (stick to
    ``sigma_d phi``, slide at ``kappa_d phi``): the new table and the signed work [J].
    """
    nr = st.shape[1]
    out = np.empty((N_ROWS, 2 * nr))
    n = 0
    work = 0.0
    for r in range(nr):
        x, brk, s_d, c_d, raw, den = _limit(st, r, d, delta)
        Mb0, Mb1, Mb2 = _moments(st, r, x, brk, pm, p, Cc)
        M0, M1, M2 = _moments(st, r, st[B, r], True, pm, p, Cc)
        sig = st[SU, r] if d > 0 else st[SD, r]
        kap = st[KU, r] if d > 0 else st[KD, r]
        if st[SL, r] == d:
            wk = kap * delta * M1
        else:  # stick from s phi + c to sigma phi, drop to kappa phi, slide at kappa phi
            wb = (
                (0.5 * sig * sig - kap * sig - 0.5 * s_d * s_d + kap * s_d) * Mb2
                + (kap * delta + c_d * (kap - s_d)) * Mb1
                - 0.5 * c_d * c_d * Mb0
            )
            wk = (
                wb
                + delta * (s_d * (M1 - Mb1) + c_d * (M0 - Mb0))
                + 0.5 * delta * delta * (M0 - Mb0)
            )
        work += wk * st[SG, r]
        atom = st[W, r] > 0.0
        if brk if atom else x > st[A, r]:  # the broken part, now sliding
            out[:, n] = st[:, r]
            if not atom:
                out[B, n] = x
            out[S, n] = d * kap
            out[C, n] = 0.0
            out[SL, n] = d
            n += 1
        if (not brk) if atom else x < st[B, r]:  # the stuck part, carried along
            out[:, n] = st[:, r]
            if not atom:
                out[A, n] = x
            out[C, n] = st[C, r] + d * delta
            out[SL, n] = 0.0
            n += 1
    return _merge(out[:, :n]), work


@njit(cache=True)
def _merge(st):
    """Join neighbouring continuous rows with the same state and bank (keeps rows few)."""
    n = st.shape[1]
    out = np.empty_like(st)
    m = 0
    for i in range(n):
        same = i > 0 and st[W, i] == 0.0 and st[W, i - 1] == 0.0 and st[B, i - 1] == st[A, i]
        if same:
            for k in (S, C, SL, SG, SU, SD, KU, KD):
                if st[k, i] != st[k, i - 1]:
                    same = False
                    break
        if same:
            out[B, m - 1] = st[B, i]
        else:
            out[:, m] = st[:, i]
            m += 1
    return out[:, :m].copy()


# Entry points from Python. (A cached function that returns arrays must not also be called
# from another compiled function: numba then fails to box its arrays for Python.)
@njit(cache=True)
def law_force(st, d, deltas, pm, p, Cc):
    """:func:`_force`, called from Python."""
    return _force(st, d, deltas, pm, p, Cc)


@njit(cache=True)
def law_advance(st, d, delta, pm, p, Cc):
    """:func:`_advance`, called from Python."""
    return _advance(st, d, delta, pm, p, Cc)


@njit(cache=True)
def law_stored(st, pm, p, Cc):
    """Signed elastic energy of the banks [J]: ``0.5 int rho e^2``."""
    E = 0.0
    for r in range(st.shape[1]):
        M0, M1, M2 = _moments(st, r, st[B, r], True, pm, p, Cc)
        s = st[S, r]
        c = st[C, r]
        E += (s * s * M2 + 2.0 * s * c * M1 + c * c * M0) * st[SG, r]
    return 0.5 * E


@njit(cache=True)
def monotone_runs(u):
    """Monotone runs of ``u`` (as ``_base.monotone_runs``): a run starts where the sign of the
    (nonzero) increment from the previous sample (0 before the first) changes; pauses belong
    to the run they interrupt. Returns ``(starts, dirs, m)``: ``starts[:m]`` the first samples,
    ``starts[m] = len(u)``, ``dirs[:m]`` the directions (+1/-1).
    """
    n = u.size
    starts = np.empty(n + 1, np.int64)
    dirs = np.empty(n)
    m = 0
    d_prev = 0.0
    prev = 0.0
    for i in range(n):
        du = u[i] - prev
        prev = u[i]
        if du != 0.0:
            d = 1.0 if du > 0.0 else -1.0
            if d != d_prev:
                starts[m] = i
                dirs[m] = d
                m += 1
                d_prev = d
    starts[m] = n
    return starts, dirs, m


@njit(cache=True)
def law_history(st, u, pm, p, Cc):
    """Signed bank force [N] along the displacement history ``u`` [m] from the state ``st``:
    one :func:`_force` per monotone run of ``u`` (:func:`monotone_runs`; breaking is monotone
    within a run), then :func:`_advance` to its end; samples before the first move carry no
    force. Returns ``(force, final state)``.
    """
    out = np.zeros(u.size)
    starts, dirs, m = monotone_runs(u)
    for r in range(m):
        a = starts[r]
        b = starts[r + 1]
        d = dirs[r]
        u_s = u[a - 1] if a > 0 else 0.0
        deltas = d * (u[a:b] - u_s)
        F, _ = _force(st, d, deltas, pm, p, Cc)
        out[a:b] = F
        st, _ = _advance(st, d, deltas[-1], pm, p, Cc)
    return out, st
