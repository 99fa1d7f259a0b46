"""The exact reversal-stack (Masing) kernel of the continuous Iwan joint, compiled with numba.

Every exact element of the package moves the same reversal stack (Masing 1926; Iwan 1966,
1967; Segalman 2005, J. Appl. Mech. 72, 752-760, sec. 3; equations in ``docs/kernel.md``):

* on the branch that leaves the reversal ``(u_r, F_r)`` the force is
  ``F = F_r + 2 F_bb((u - u_r)/2)`` and on the virgin curve ``F = F_bb(u)``, with the odd
  backbone ``F_bb`` (``F_bb(x) = x (KT phi_max - a r^(chi+1))/phi_max``, ``r = |x|/phi_max``,
  saturating at ``Fs``); the tangent is ``F_bb'`` at the same argument;
* a reversal pushes the turning point onto the stack (unless its excursion from the previous
  reversal is at most the tolerance, when that reversal is forgotten instead); passing the
  reversal two levels down closes the inner loop and pops both points (Madelung's rule),
  passing ``-u_r`` of the last one returns to the virgin curve;
* along a branch the work is ``F_r du + 4 dG`` and the dissipation ``2 dI_H`` (virgin curve:
  ``dG`` and ``dI_H``), with ``G`` the backbone's integral and ``I_H`` the double integral of
  the slider density; both in closed form.

:func:`_advance` is the one walk; :func:`masing_step` applies it to one element's stack (the
slow path of :class:`~iwan_element.IwanJoint` and :class:`~iwan_element.IwanJointBank`),
:func:`bank_trial_rows` to trials of every element of a bank (a Newton iteration's forces and
consistent tangents), and
:func:`masing_history` to whole histories, one parameter set per row (a batch of parameter
sets, e.g. all the perturbations of a finite-difference Jacobian, is one call).
:func:`reversal_structure` gives the parameter-free part (which reversal each sample's branch
leaves, and the branch segments walked) for the vectorised evaluation of
:mod:`iwan_element.core.history`.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..base.validation import check_scalar, finite_array
from .parameters import IwanParameters

__all__ = [
    "masing_constants",
    "constants_from_arrays",
    "jenkins_constants",
    "masing_history",
    "masing_rows",
    "masing_step",
    "bank_trial_rows",
    "reversal_structure",
]

# Positions in the constants vector of one parameter set (see masing_constants).
KT, FS, PM, IPM, E1, E3, KTPM, A, B, G2, G3, GPM, IHC, FSPM, TOL = range(15)
N_CONST = 15


def masing_constants(params: IwanParameters, tol: float) -> np.ndarray:
    """The constants the kernel reads for one parameter set, shape ``(15,)``.

    Everything is written in ``r = x/phi_max <= 1`` (powers of ``phi_max`` itself overflow for
    large ``chi``). With ``Ks = KT/(1+beta)``: backbone ``r (KT phi_max - a r^(chi+1))``,
    tangent ``KT - b r^(chi+1)``, ``G = g2 r^2 - g3 r^(chi+3)``, ``I_H = ih_c r^(chi+3)``, each
    continued linearly (slope ``Fs``) beyond ``phi_max``.

    Parameters
    ----------
    params : IwanParameters
    tol : float
        Absolute reversal tolerance [m], ``>= 0``.
    """
    p = params
    pm = p.phi_max
    Ks = p.K_slider
    g2 = 0.5 * p.KT * pm * pm
    g3 = Ks * pm * pm / ((p.chi + 2.0) * (p.chi + 3.0))
    return np.array(
        [
            p.KT,
            p.Fs,
            pm,
            1.0 / pm,
            p.chi + 1.0,
            p.chi + 3.0,
            p.KT * pm,
            Ks * pm / (p.chi + 2.0),
            Ks,
            g2,
            g3,
            g2 - g3,
            (p.chi + 1.0) * g3,
            p.Fs * pm,
            float(tol),
        ]
    )


def constants_from_arrays(Fs, KT, chi, beta, tol=0.0, phi_max=None) -> np.ndarray:
    """:func:`masing_constants` for arrays of parameters (broadcast together), shape
    ``(m, 15)``; ``phi_max`` [m] from paper eq. 11 as :class:`IwanParameters` computes it
    unless given. The values are not validated here (the callers hold validated parameters).
    ``tol``: relative reversal tolerance (times ``phi_max``).
    """
    Fs, KT, chi, beta, tol = np.broadcast_arrays(
        *(np.asarray(x, float).ravel() for x in (Fs, KT, chi, beta, tol))
    )
    if phi_max is None:
        pm = Fs / KT * ((1.0 + beta) / (beta + (chi + 1.0) / (chi + 2.0)))
    else:
        pm = np.broadcast_to(np.asarray(phi_max, float).ravel(), Fs.shape)
    Ks = KT / (1.0 + beta)
    g2 = 0.5 * KT * pm * pm
    g3 = Ks * pm * pm / ((chi + 2.0) * (chi + 3.0))
    return np.ascontiguousarray(
        np.column_stack(
            [
                KT,
                Fs,
                pm,
                1.0 / pm,
                chi + 1.0,
                chi + 3.0,
                KT * pm,
                Ks * pm / (chi + 2.0),
                Ks,
                g2,
                g3,
                g2 - g3,
                (chi + 1.0) * g3,
                Fs * pm,
                tol * pm,
            ]
        )
    )


def jenkins_constants(k, phi) -> np.ndarray:
    """:func:`masing_constants` of Jenkins elements (a spring ``k`` [N/m] in series with a
    Coulomb slider that slides at stretch ``phi`` [m], force ``k phi``), shape ``(m, 15)``.

    A Jenkins element is the Iwan joint whose sliders all sit in the Dirac mass at
    ``phi_max`` (``beta -> inf``, no continuous density: Segalman 2005, eq. 3): its backbone
    is ``k x`` up to ``phi`` and ``k phi`` beyond, it follows Masing's rules (Iwan, J. Appl.
    Mech. 33:893-900, 1966), and the kernel walks it exactly with ``K_s = 0``; the
    dissipation is then that of sliding alone. The reversal tolerance is 0 (every reversal
    kept, as the stepped element keeps it), so every such row shares one reversal structure.
    """
    k = np.asarray(k, float).ravel()
    phi = np.asarray(phi, float).ravel()
    if k.shape != phi.shape or np.any(~np.isfinite(k)) or np.any(k < 0):
        raise ValueError("k must be finite stiffnesses >= 0 [N/m], one per phi")
    if np.any(~np.isfinite(phi)) or np.any(phi <= 0):
        raise ValueError("phi must be finite slip displacements > 0 [m]")
    return constants_from_arrays(k * phi, k, 0.0, np.inf, 0.0, phi_max=phi)


@njit(cache=True)
def _backbone(c, r):
    """Backbone force and tangent at ``x = r phi_max >= 0``."""
    if r < 1.0:
        q = r ** c[E1]
        return r * (c[KTPM] - c[A] * q), c[KT] - c[B] * q
    return c[FS], 0.0


@njit(cache=True)
def _energies(c, r):
    """``G`` and ``I_H`` at ``x = r phi_max >= 0`` [J]."""
    if r < 1.0:
        p3 = r ** c[E3]
        return c[G2] * r * r - c[G3] * p3, c[IHC] * p3
    ext = c[FSPM] * (r - 1.0)
    return c[GPM] + ext, c[IHC] + ext


@njit(cache=True)
def _segment(c, us, Fr, n, ua, ub):
    """Work, dissipation and ``(G, I_H)`` at ``ub`` of the monotone move ``ua -> ub`` on the
    branch from the stack top ``us[n-1]`` (the virgin curve when ``n == 0``).
    """
    if n == 0:
        Gb, Ib = _energies(c, c[IPM] * abs(ub))
        Ga, Ia = _energies(c, c[IPM] * abs(ua))
        return Gb - Ga, max(Ib - Ia, 0.0), Gb, Ib
    ur = us[n - 1]
    Gb, Ib = _energies(c, 0.5 * c[IPM] * abs(ub - ur))
    Ga, Ia = _energies(c, 0.5 * c[IPM] * abs(ua - ur))
    return Fr[n - 1] * (ub - ua) + 4.0 * (Gb - Ga), 2.0 * (Ib - Ia), Gb, Ib


@njit(cache=True)
def _advance(c, us, Fr, at, n, uc, Fc, Gc, IHc, u, i, seg, ns):
    """Move the stack ``us[:n], Fr[:n]`` (committed at ``(uc, Fc)``) to ``u``.

    A reversal is written at ``us[n], Fr[n], at[n]`` (beyond the committed entries, which are
    never changed, so a trial leaves the committed stack intact; ``at`` holds the sample index
    ``i - 1`` of the turning point); the new stack is ``us[:m]``. ``Gc, IHc``: ``G`` and
    ``I_H`` at ``uc`` in its branch's coordinate, reused when the move stays on the committed
    branch. If ``seg`` has columns, the branch segments walked are written to its columns
    ``ns, ns + 1, ...`` as ``(i, anchor sample, u_a, u_b)``.
    Returns ``(m, F, K, dW, dD, G, I_H, ns)``.
    """
    record = seg.shape[1] > 0
    du = u - uc
    W = 0.0
    D = 0.0
    G = Gc
    I = IHc
    if du != 0.0:
        d = uc - us[n - 1] if n else uc  # direction of the current branch
        up = du > 0.0  # signs, not products: d * du underflows
        simple = d != 0.0
        if (d < 0.0) if up else (d > 0.0):  # the motion reverses at uc
            simple = False
            if abs(d) <= c[TOL]:
                if n:
                    n -= 1  # ignore a negligible excursion
            else:
                us[n] = uc
                Fr[n] = Fc
                at[n] = i - 1
                n += 1
        pos = uc
        while n:  # close the loops that u passes
            bound = us[n - 2] if n >= 2 else -us[n - 1]
            if (u < bound) if up else (u > bound):
                break
            simple = False
            dW, dD, G, I = _segment(c, us, Fr, n, pos, bound)
            W += dW
            D += dD
            if record:
                seg[0, ns], seg[1, ns], seg[2, ns], seg[3, ns] = i, at[n - 1], pos, bound
                ns += 1
            pos = bound
            n -= 2 if n >= 2 else 1
        if record:
            seg[0, ns], seg[1, ns], seg[2, ns], seg[3, ns] = i, at[n - 1] if n else -1, pos, u
            ns += 1
        if simple:  # on the committed branch throughout
            if n:
                G, I = _energies(c, 0.5 * c[IPM] * abs(u - us[n - 1]))
                W = Fr[n - 1] * du + 4.0 * (G - Gc)
                D = 2.0 * (I - IHc)
            else:
                G, I = _energies(c, c[IPM] * abs(u))
                W = G - Gc
                D = max(I - IHc, 0.0)
        else:
            dW, dD, G, I = _segment(c, us, Fr, n, pos, u)
            W += dW
            D += dD
    if n:
        x = u - us[n - 1]
        f, k = _backbone(c, 0.5 * c[IPM] * abs(x))
        F = Fr[n - 1] + 2.0 * f if x >= 0.0 else Fr[n - 1] - 2.0 * f
    else:
        f, k = _backbone(c, c[IPM] * abs(u))
        F = f if u >= 0.0 else -f
    return n, F, k, W, D, G, I, ns


_NOSEG = np.empty((4, 0))


@njit(cache=True)
def masing_step(
    c, us, Fr, at, n, uc, Fc, Gc, IHc, u, seg
) -> tuple[int, float, float, float, float, float, float]:
    """One element's move from its committed state to ``u`` (:func:`_advance`; the compiled
    entry point from Python and from other compiled elements).

    ``c``: constants (:func:`masing_constants`); ``us, Fr, at``: the stack arrays with room for
    one more entry; ``n``: committed depth; ``uc, Fc``: committed displacement [m] and force
    [N]; ``Gc, IHc``: ``G`` and ``I_H`` there [J]; ``seg``: an empty ``(4, 0)`` array.
    Returns ``(m, F, K, dW, dD, G, I_H)``: the new depth (the first ``m`` stack entries),
    force [N], tangent [N/m], work and dissipation of the move [J], ``G`` and ``I_H`` at ``u``.
    """
    m, F, K, W, D, G, I, _ = _advance(c, us, Fr, at, n, uc, Fc, Gc, IHc, u, 0, seg, 0)
    return m, F, K, W, D, G, I


@njit(cache=True)
def bank_trial_rows(C, us, Fr, at, nst, uc, Fc, u, F, K) -> None:
    """Trial force ``F[i]`` [N] and tangent ``K[i]`` [N/m] of every element ``i`` of a bank at
    ``u[i]``: the walk of :func:`_advance` from the committed state ``(uc[i], Fc[i])`` and
    stack ``us[i, :nst[i]], Fr[i, :nst[i]]`` (constants ``C[i]``; each row with room for one
    more entry, which is all a trial writes), the committed entries unchanged.
    """
    seg = np.empty((4, 0))
    for i in range(u.size):
        _, F[i], K[i], _, _, _, _, _ = _advance(
            C[i], us[i], Fr[i], at[i], nst[i], uc[i], Fc[i], 0.0, 0.0, u[i], 0, seg, 0
        )


@njit(cache=True)
def _row(c, u, F, K, W, D, ids, seg):
    """Walk one history ``u`` from the virgin state; fill ``F, K`` and the cumulative ``W, D``.

    ``ids``: filled with the sample index of the reversal each sample's branch leaves (-1 for
    the virgin curve). With ``seg`` of shape ``(4, 2 len(u) + 1)`` the branch segments are
    recorded as columns ``(step, anchor sample, u_a, u_b)``; returns their number (0 if
    ``seg`` has no columns).
    """
    m = u.size
    us = np.empty(m + 1)
    Fr = np.empty(m + 1)
    at = np.empty(m + 1, np.int64)
    n = 0
    ns = 0
    uc = 0.0
    Fc = 0.0
    Gc = 0.0
    Ic = 0.0
    Wc = 0.0
    Dc = 0.0
    for i in range(m):
        n, Fc, K[i], dW, dD, Gc, Ic, ns = _advance(
            c, us, Fr, at, n, uc, Fc, Gc, Ic, u[i], i, seg, ns
        )
        uc = u[i]
        Wc += dW
        Dc += dD
        F[i] = Fc
        W[i] = Wc
        D[i] = Dc
        ids[i] = at[n - 1] if n else -1
    return ns


@njit(cache=True)
def _rows(C, U, F, K, W, D):
    """:func:`_row` for every row ``k`` of ``U`` with the constants ``C[k]``."""
    m = U.shape[1]
    ids = np.empty(m, np.int64)
    seg = np.empty((4, 0))
    for k in range(U.shape[0]):
        _row(C[k], U[k], F[k], K[k], W[k], D[k], ids, seg)


def masing_rows(
    C: np.ndarray, U: np.ndarray
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The kernel on raw arrays (no validation): constants ``C`` of shape ``(m, 15)``
    (:func:`constants_from_arrays`) and histories ``U`` of shape ``(m, n)`` [m], each from
    the virgin state. Returns ``F, K, W, D``, each ``(m, n)`` (see :func:`masing_history`).
    """
    C = np.ascontiguousarray(C, dtype=float)
    U = np.ascontiguousarray(U, dtype=float)
    F, K, W, D = (np.empty(U.shape) for _ in range(4))
    _rows(C, U, F, K, W, D)
    return F, K, W, D


def _as_params(params) -> list:
    if isinstance(params, IwanParameters):
        return [params]
    if isinstance(params, (str, bytes, dict)) or not hasattr(params, "__iter__"):
        raise ValueError(
            f"params must be an IwanParameters or a sequence of them, got {type(params).__name__}"
        )
    out = list(params)
    if not out or not all(isinstance(p, IwanParameters) for p in out):
        raise ValueError("params must be a non-empty sequence of IwanParameters")
    return out


def masing_history(
    u, params, *, reversal_tol: float = 1e-12
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Exact force, tangent, work and dissipation of Iwan joints along displacement histories.

    Parameters
    ----------
    u : array_like, shape (n,) or (m, n)
        Displacement histories [m] from the virgin state (one row per parameter set; a 1-D
        history is shared by every parameter set).
    params : IwanParameters or sequence of m IwanParameters
        One parameter set per row.
    reversal_tol : float, keyword-only
        Relative reversal tolerance (times ``phi_max`` of each row), ``[0, 1e-9]``, as for
        :class:`~iwan_element.IwanJoint`.

    Returns
    -------
    F, K, W, D : ndarray, shape (m, n) (``(n,)`` for one parameter set and a 1-D ``u``)
        Force [N], consistent tangent [N/m], work done on the joint [J] and energy
        dissipated [J] after each sample; the stored energy is ``W - D``.
    """
    plist = _as_params(params)
    tol = check_scalar("reversal_tol", reversal_tol, low=0.0, high=1e-9)
    arr = finite_array("u", u, ndim=None)
    if arr.ndim not in (1, 2):
        raise ValueError(f"u must have shape (n,) or (m, n), got {arr.shape}")
    single = arr.ndim == 1 and len(plist) == 1
    U = np.ascontiguousarray(
        np.broadcast_to(arr, (len(plist), arr.shape[-1])) if arr.ndim == 1 else arr, dtype=float
    )
    if U.shape[0] != len(plist):
        raise ValueError(f"u has {U.shape[0]} rows but params has {len(plist)} sets")
    C = np.array([masing_constants(p, tol * p.phi_max) for p in plist])
    F, K, W, D = masing_rows(C, U)
    if single:
        return F[0], K[0], W[0], D[0]
    return F, K, W, D


_UNIT = masing_constants(IwanParameters(1.0, 1.0, 0.0, 0.0), 0.0)


def reversal_structure(
    u: np.ndarray, tol: float, *, segments: bool = False
) -> tuple[
    NDArray[np.intp],
    tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]] | None,
]:
    """Reversal structure of the history ``u`` [m] from the virgin state (parameter free).

    Parameters
    ----------
    u : ndarray, shape (n,)
        Displacement history [m].
    tol : float
        Absolute reversal tolerance [m].
    segments : bool, keyword-only
        Also return the monotone branch segments walked by each step.

    Returns
    -------
    anchor : ndarray of int, shape (n,)
        Sample index of the reversal each sample's branch leaves (``-1``: virgin curve).
    segs : tuple of ndarray or None
        With ``segments=True``: ``(step, anchor, ua, ub)`` of every segment, its step index,
        the reversal sample its branch leaves (``-1``: virgin curve) and its end
        displacements [m].
    """
    u = np.ascontiguousarray(u, dtype=float)
    c = _UNIT.copy()
    c[TOL] = tol
    m = u.size
    F, K, W, D = (np.empty(m) for _ in range(4))
    ids = np.empty(m, np.int64)
    seg = np.empty((4, 2 * m + 1 if segments else 0))
    ns = _row(c, u, F, K, W, D, ids, seg)
    anchor = ids.astype(np.intp)
    if not segments:
        return anchor, None
    s = seg[:, :ns]
    return anchor, (s[0].astype(np.intp), s[1].astype(np.intp), s[2].copy(), s[3].copy())
