"""The exact steady hysteresis loop of Iwan joints under periodic displacement, with its Jacobian.

For harmonic balance with alternating frequency-time evaluation (AFT; Krack & Gross,
Harmonic Balance for Nonlinear Vibration Problems, Springer 2019, ch. 3) the joint force over
one period of a periodic slip ``u(t)`` is needed on the *steady* loop. For a Masing element
(Iwan 1966; Segalman 2005, J. Appl. Mech. 72, 752-760) the steady loop follows from the
reversal points alone (``docs/harmonic_balance.md`` section 2):

* start at the sample of the largest ``|u|`` (the global extremum ``u_e``), reached on the
  virgin curve from the assembled state ``u = 0`` (the joint's first loading);
* walk the period once with the package's reversal-stack kernel (:mod:`.masing`): every inner
  loop closes by Madelung's rule and the outer loop closes on the virgin curve at ``u_e``, so
  the period ends in the state it started from. The walk *is* the steady loop; no transient
  run and no slider bins.

The force at sample ``n`` is ``F_n = F_bb(u_b) + sum_k g_k(u_k - u_{k-1})`` over the reversal
chain ``b = a_L, ..., a_1`` of its branch (``u_0 = u_b`` on the virgin curve, the last term ends
at ``u_n``), with the branch shapes ``g_k = 2 F_bb(./2)``. Its exact derivatives are therefore
(``K_j``: the kernel's tangent at sample ``j``, the arriving branch's at a reversal sample)::

    dF_n/du_n = K_n,   dF_n/du_{a_1} = K_{a_1} - K_n,   dF_n/du_{a_k} = K_{a_k} - K_{a_{k-1}}

and zero elsewhere: the tangent on the diagonal plus one entry in the column of each
reversal sample of the chain (REFERENCE: "NOT only the tangent"). :func:`periodic_rows`
returns the force, the tangent, the chain and the dissipation of one period per row;
:func:`periodic_harmonic_jacobian` contracts the exact sample Jacobian with the harmonic
transforms in one compiled loop.

A *bank* of Masing rows driven by one coordinate (the Jenkins elements of a patch that
starts to slide, :func:`~iwan_element.core.masing.jenkins_constants`) is the sum of its
rows; rows with one reversal tolerance share one reversal structure (it depends on the
path and the tolerance alone), so the bank's sample Jacobian is the one above with the
rows' tangents summed. :class:`PeriodicForm` is how an element states its force in these
terms (Masing rows, a linear stiffness taken off, history-free laws beside them), so that
the harmonic balance evaluates it here, compiled and with its exact Jacobian, instead of
stepping the element sample by sample.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from .masing import KT, N_CONST, PM, TOL, B, _advance

__all__ = ["periodic_rows", "periodic_harmonic_jacobian", "PeriodicForm", "PeriodicLoop"]

_NOSEG = np.empty((4, 0))


@njit(cache=True)
def _periodic_row(c, u, F, K, anchor, seg):
    """Steady loop of one row (module docstring); fills ``F, K, anchor`` in sample order and
    returns the dissipation of one period [J].
    """
    N = u.size
    k0 = 0
    big = -1.0
    for j in range(N):
        if abs(u[j]) > big:
            big = abs(u[j])
            k0 = j
    us = np.empty(N + 2)
    Fr = np.empty(N + 2)
    at = np.empty(N + 2, np.int64)
    ids = np.empty(N, np.int64)
    # first loading from the assembled state onto the virgin curve at the extremum
    n, Fc, Kc, _, _, Gc, Ic, _ = _advance(c, us, Fr, at, 0, 0.0, 0.0, 0.0, 0.0, u[k0], 0, seg, 0)
    F[k0] = Fc
    K[k0] = Kc
    ids[0] = at[n - 1] if n else -1
    uc = u[k0]
    Dp = 0.0
    for j in range(1, N + 1):  # rotated sample j; j = N closes the period
        m = (k0 + j) % N
        n, Fc, Kc, _, dD, Gc, Ic, _ = _advance(c, us, Fr, at, n, uc, Fc, Gc, Ic, u[m], j, seg, 0)
        uc = u[m]
        Dp += dD
        if j < N:
            F[m] = Fc
            K[m] = Kc
            ids[j] = at[n - 1] if n else -1
    for j in range(N):  # anchors back in sample order
        a = ids[j]
        anchor[(k0 + j) % N] = -1 if a < 0 else (k0 + a) % N
    return Dp


@njit(cache=True)
def _rows(C, U, F, K, A, D):
    seg = np.empty((4, 0))
    for r in range(U.shape[0]):
        D[r] = _periodic_row(C[r], U[r], F[r], K[r], A[r], seg)


def periodic_rows(
    C: np.ndarray, U: np.ndarray
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.intp], NDArray[np.float64]]:
    """Steady-loop force of Iwan joints over one period of periodic slips.

    Parameters
    ----------
    C : ndarray, shape (m, 15)
        Kernel constants per row (:func:`iwan_element.core.masing.constants_from_arrays`).
    U : ndarray, shape (m, N)
        One period of each row's slip [m], ``N`` equidistant samples.

    Returns
    -------
    F, K : ndarray, shape (m, N)
        Force [N] and tangent [N/m] at every sample on the steady loop.
    anchor : ndarray of int, shape (m, N)
        Sample index of the reversal each sample's branch leaves (``-1``: the virgin curve);
        following ``anchor`` from a sample gives its reversal chain (module docstring).
    D : ndarray, shape (m,)
        Energy dissipated by each joint over one period [J] (the exact loop area of the
        sampled path).
    """
    C = np.ascontiguousarray(C, dtype=float)
    U = np.ascontiguousarray(U, dtype=float)
    if C.ndim != 2 or C.shape[1] != N_CONST or U.ndim != 2 or U.shape[0] != C.shape[0]:
        raise ValueError(
            f"C must be (m, {N_CONST}) and U (m, N) with the same m, got {C.shape} and {U.shape}"
        )
    F, K = np.empty(U.shape), np.empty(U.shape)
    A = np.empty(U.shape, np.int64)
    D = np.empty(U.shape[0])
    _rows(C, U, F, K, A, D)
    return F, K, A, D


@njit(cache=True)
def _add_entry(out, r, P, E, n, m, w):
    """Add the sample Jacobian entry ``dF_n/du_m = w`` of row ``r`` to the harmonic one."""
    for c in range(P.shape[0]):
        pcn = P[c, n] * w
        for d in range(E.shape[1]):
            out[r, c, d] += pcn * E[m, d]


@njit(cache=True)
def _harmonic_jacobian(K, A, P, E, shift, out):
    m, N = K.shape
    for r in range(m):
        for n in range(N):
            # row n of the exact sample Jacobian: diagonal K_n - shift, then the chain
            _add_entry(out, r, P, E, n, n, K[r, n] - shift[r])
            prev = n
            a = A[r, n]
            while a >= 0:
                _add_entry(out, r, P, E, n, a, K[r, a] - K[r, prev])
                prev = a
                a = A[r, a]


def periodic_harmonic_jacobian(K, anchor, P, E, *, shift=None) -> np.ndarray:
    """Derivative of the force's harmonic coefficients with respect to the slip's.

    With the slip samples ``u = E c_u`` and the force coefficients ``c_F = P F(u)``, returns
    ``dc_F/dc_u = P (dF/du - diag(shift)) E`` per row, ``dF/du`` the exact sample Jacobian of
    the steady loop (module docstring).

    Parameters
    ----------
    K, anchor : ndarray, shape (m, N)
        From :func:`periodic_rows`.
    P : ndarray, shape (nc, N)
        Samples to coefficients.
    E : ndarray, shape (N, nc)
        Coefficients to samples.
    shift : ndarray, shape (m,), optional, keyword-only
        A linear stiffness [N/m] subtracted from each row's tangent (the harmonic balance
        works with the force minus the stuck stiffness); default 0.

    Returns
    -------
    ndarray, shape (m, nc, nc)
    """
    K = np.ascontiguousarray(K, dtype=float)
    m = K.shape[0]
    s = (
        np.zeros(m)
        if shift is None
        else np.ascontiguousarray(np.broadcast_to(shift, (m,)), dtype=float)
    )
    out = np.zeros((m, P.shape[0], P.shape[0]))
    _harmonic_jacobian(
        K,
        np.ascontiguousarray(anchor, dtype=np.int64),
        np.ascontiguousarray(P, dtype=float),
        np.ascontiguousarray(E, dtype=float),
        s,
        out,
    )
    return out


class PeriodicLoop(NamedTuple):
    """One period of a :class:`PeriodicForm` on its steady loop (arrays of the ``N`` samples).

    Attributes
    ----------
    force : ndarray
        The element's force [N] (rows, shift and laws).
    tangent : ndarray
        The Masing rows' summed tangent [N/m] (the shift and the laws left out; rows that
        stayed linear over the period are in :attr:`shift` instead).
    anchor : ndarray of int
        The rows' reversal chain (:func:`periodic_rows`; ``-1`` everywhere without rows).
    dissipation : float
        The rows' dissipation over the period [J] (the laws' is the caller's: it needs the
        rate of the slip, ``int f du``).
    law_force, law_du, law_dv : ndarray
        The history-free laws' summed force [N] and its derivatives by the displacement
        [N/m] and the velocity [N s/m].
    shift : float
        The linear stiffness taken off [N/m], less that of the rows that stayed linear.
    """

    force: np.ndarray
    tangent: np.ndarray
    anchor: np.ndarray
    dissipation: float
    law_force: np.ndarray
    law_du: np.ndarray
    law_dv: np.ndarray
    shift: float


@dataclass(frozen=True, eq=False)
class PeriodicForm:
    """An element's force in the compiled kernel's terms (module docstring).

    ``F(u, v) = sum_r F_r(u) - shift u + sum_l f_l(u, v)``: Masing rows, a linear stiffness
    taken off, history-free laws.

    Parameters
    ----------
    constants : array_like, shape (m, 15), optional
        Masing rows driven by the element's displacement ``u`` (kernel constants,
        :func:`~iwan_element.core.masing.masing_constants`), all with one reversal
        tolerance; default none.
    shift : float, optional
        Linear stiffness taken off [N/m] (a bank that replaces stiffness it already holds).
    laws : tuple of callables, optional
        History-free parts ``law(u, v) -> (f [N], df/du [N/m], df/dv [N s/m])`` on arrays
        of displacement [m] and velocity [m/s].
    """

    constants: np.ndarray = field(default_factory=lambda: np.empty((0, N_CONST)))
    shift: float = 0.0
    laws: tuple = ()

    def __post_init__(self):
        C = np.ascontiguousarray(np.array(self.constants, dtype=float).reshape(-1, N_CONST))
        if not np.all(np.isfinite(C)):
            raise ValueError("constants must be finite kernel constants, shape (m, 15)")
        if C.shape[0] and np.any(C[:, TOL] != C[0, TOL]):
            raise ValueError("constants must share one reversal tolerance (one reversal structure)")
        if not np.isfinite(self.shift):
            raise ValueError(f"shift must be a finite stiffness [N/m], got {self.shift!r}")
        if not all(callable(f) for f in self.laws):
            raise ValueError("laws must be callables law(u, v) -> (f, df/du, df/dv)")
        C.setflags(write=False)
        object.__setattr__(self, "constants", C)
        object.__setattr__(self, "shift", float(self.shift))
        object.__setattr__(self, "laws", tuple(self.laws))

    def plus(self, other: PeriodicForm) -> PeriodicForm | None:
        """The form of the two elements' forces added (parallel), or None when their rows'
        reversal tolerances differ.
        """
        a, b = self.constants, other.constants
        if a.shape[0] and b.shape[0] and a[0, TOL] != b[0, TOL]:
            return None
        return PeriodicForm(np.vstack([a, b]), self.shift + other.shift, self.laws + other.laws)

    def loop(self, u: np.ndarray, v: np.ndarray) -> PeriodicLoop:
        """The steady loop over one period of samples ``u`` [m] (the rows started at the
        sample of the largest ``|u|``, :func:`periodic_rows`) and velocities ``v`` [m/s].

        A row without continuous slider density (a Jenkins element) whose slip
        displacement the period never exceeds stays on its elastic line, ``F = KT u``: it
        is taken as that line (into :attr:`PeriodicLoop.shift`) instead of being walked, an
        exact shortcut.
        """
        u = np.ascontiguousarray(u, dtype=float)
        N = u.size
        C, shift = self.constants, self.shift
        if C.shape[0]:
            elastic = (C[:, B] == 0.0) & (C[:, PM] >= float(np.abs(u).max()))
            if elastic.any():
                shift -= float(C[elastic, KT].sum())
                C = C[~elastic]
        m = C.shape[0]
        if m:
            F, K, A, D = periodic_rows(C, np.broadcast_to(u, (m, N)))
            force, tangent, anchor, diss = F.sum(axis=0), K.sum(axis=0), A[0], float(D.sum())
        else:
            force, tangent = np.zeros(N), np.zeros(N)
            anchor, diss = np.full(N, -1, np.int64), 0.0
        force -= shift * u
        lf, lu, lv = np.zeros(N), np.zeros(N), np.zeros(N)
        for law in self.laws:
            f, fu, fv = law(u, v)
            lf += f
            lu += fu
            lv += fv
        return PeriodicLoop(force + lf, tangent, anchor, diss, lf, lu, lv, shift)
