"""The continuous four-parameter Iwan joint, exact for any displacement history.

A parallel array of Jenkins elements obeys the extended Masing rules, so the continuous
model needs no slider discretisation: it is enough to remember the reversal points of the
displacement history (Segalman 2005, sec. 3; paper eqs. 13-15).

* On a branch that leaves the reversal ``(u_r, F_r)`` the force is
  ``F = F_r + 2 F_bb((u - u_r)/2)`` with the odd backbone ``F_bb`` (paper eq. 13, and the
  corrected eq. 15); its tangent is ``F_bb'(|u - u_r|/2)``.
* When ``u`` passes the reversal two levels down, the inner loop closes and both points are
  forgotten (Madelung's rule). With a single reversal left, passing ``-u_r`` returns to the
  virgin curve. Macroslip needs no special case (``F_bb`` saturates at ``Fs``).
* Energy: along a branch the work is ``F_r du + 4 dG`` with ``G`` the backbone's integral
  and the dissipation is ``2 dI_H`` with ``I_H(y) = int_0^y int_0^q phi rho(phi)``; the stored
  (slider spring) energy is their difference. All three are exact closed forms.

The cost per call is O(1) amortised: only the top of the reversal stack is touched. The
reversal walk is the compiled kernel of :mod:`iwan_element.core.masing`, shared by every
exact element. A trial that continues the current branch without closing a loop (most
trials and commits of a time integration) takes a shortcut in Python (an interval test
against the cached branch, cheaper than any call into compiled code) that gives bit-for-bit
the numbers of the kernel; its commit reuses ``G`` and ``I_H`` at the committed point, kept
from the previous commit.
"""

from __future__ import annotations

import math

import numpy as np

from ..base.validation import check_scalar, finite_array, same_length
from .history import REVERSAL_TOL
from .masing import _NOSEG, masing_constants, masing_history, masing_step
from .parameters import IwanParameters
from .protocol import CommittedState

__all__ = ["IwanJoint"]

#: Largest accepted ``reversal_tol`` (relative to ``phi_max``): it only guards against
#: round-off, see :class:`IwanJoint`.
REVERSAL_TOL_MAX = 1e-9

_INF = math.inf
_NINF = -math.inf


class IwanJoint(CommittedState):
    """Exact time-domain Iwan joint with reversal-point memory (element protocol).

    The element follows the protocol of a history-dependent material (as in OpenSees):
    :meth:`trial` evaluates the force at a trial displacement without changing the
    committed history, :meth:`commit` accepts the last trial, :meth:`revert` discards it and
    :meth:`reset` returns to the virgin state.

    Parameters
    ----------
    params : IwanParameters
        Joint parameters (SI units).
    reversal_tol : float, keyword-only
        Round-off guard, relative to ``phi_max`` [-], range ``[0, 1e-9]`` (default ``1e-12``).
        A reversal whose excursion from the previous reversal is at most
        ``reversal_tol * phi_max`` is ignored. Ignoring it changes the force by at most
        ``KT * reversal_tol * phi_max`` (``<= 1e-9 KT phi_max = 1e-9 Fs (1+beta)/c``), and
        keeps the stack of a slow decay from growing once its amplitude is at round-off
        level. ``0`` is exact for every history. Larger values are refused: they would
        silently erase small real reversals (and their loops) from the history.

    Notes
    -----
    Closed loops are removed from the stack, so its depth is bounded by the number of
    nested, still-open loops: on random histories it stays small (it grows like the log of
    the number of reversals); a slowly decaying vibration adds two entries per cycle until
    its amplitude falls below the tolerance.

    Examples
    --------
    >>> j = IwanJoint(IwanParameters(Fs=1e3, KT=1e6, chi=-0.5, beta=0.2))
    >>> F, K = j.trial(1e-4)
    >>> j.commit()
    """

    __slots__ = (
        "_p",
        "_tol",
        "_KT",
        "_Fs",
        "_pm",
        "_e1",
        "_e3",
        "_a",
        "_b",
        "_g_pm",
        "_ih_c",
        "_ipm",
        "_KTpm",
        "_g2",
        "_g3",
        "_Fspm",
        "_rtol",
        "_c",
        "_n",
        "_at",
        "_ih_pm",
        "_u",
        "_F",
        "_K",
        "_us",
        "_Fr",
        "_W",
        "_D",
        "_tu",
        "_tF",
        "_tK",
        "_tn",
        "_tacc",
        "_has_trial",
        "_tfast",
        "_Gc",
        "_IHc",
        "_blo",
        "_bhi",
        "_bur",
        "_bFr",
        "_bc1",
        "_bc2",
        "_bdir",
    )
    # the fast-path interval (_set_branch assigns the three in one tuple)
    _blo: float
    _bhi: float
    _bdir: int

    def __init__(self, params: IwanParameters, *, reversal_tol: float = REVERSAL_TOL):
        if not isinstance(params, IwanParameters):
            raise ValueError(
                f"params must be an IwanParameters instance, got {type(params).__name__}"
            )
        tol = check_scalar("reversal_tol", reversal_tol, low=0.0, high=REVERSAL_TOL_MAX)
        self._p = params
        p = params
        self._rtol = tol
        self._tol = tol * p.phi_max
        self._KT = p.KT
        self._Fs = p.Fs
        self._pm = p.phi_max
        self._e1 = p.chi + 1.0
        self._e3 = p.chi + 3.0
        # Everything is written in r = x/phi_max <= 1 (docs/equations.md section 2): powers of
        # phi_max itself overflow for large chi (IwanParameters.R). With Ks = KT/(1+beta):
        pm = p.phi_max
        Ks = p.K_slider
        self._ipm = 1.0 / pm
        self._KTpm = p.KT * pm  # backbone: r (KT pm - a r^(chi+1))
        self._a = Ks * pm / (p.chi + 2.0)
        self._b = Ks  # tangent:  KT - b r^(chi+1)
        self._g2 = 0.5 * p.KT * pm * pm  # G = g2 r^2 - g3 r^(chi+3)
        self._g3 = Ks * pm * pm / ((p.chi + 2.0) * (p.chi + 3.0))
        self._g_pm = self._g2 - self._g3
        self._ih_c = (p.chi + 1.0) * self._g3  # I_H = ih_c r^(chi+3)
        self._ih_pm = self._ih_c
        self._Fspm = p.Fs * pm
        self._c = masing_constants(p, self._tol)  # the same numbers, for the kernel
        self.reset()

    # ------------------------------------------------------------------ public protocol
    @property
    def params(self) -> IwanParameters:
        """The joint parameters."""
        return self._p

    def reset(self) -> None:
        """Return to the virgin, unloaded state and zero the energy counters."""
        self._u = 0.0
        self._F = 0.0
        self._K = self._KT
        self._us = np.empty(16)  # reversal stack (oldest first), the first _n entries
        self._Fr = np.empty(16)
        self._at = np.empty(16, np.int64)
        self._n = 0
        self._W = 0.0
        self._D = 0.0
        self._Gc = 0.0  # G and I_H at the committed point, in the coordinate of the
        self._IHc = 0.0  # branch it lies on (|u| virgin, |u - u_r|/2 otherwise)
        self._set_branch()
        self.revert()

    def revert(self) -> None:
        """Discard the last trial; the committed state is unchanged."""
        self._has_trial = False
        self._tfast = False
        self._tu = self._u
        self._tF = self._F
        self._tK = self._K

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force and consistent tangent at trial displacement ``u``; commits nothing.

        Parameters
        ----------
        u : float
            Joint displacement (slip across the joint) [m].
        v : float
            Velocity [m/s]; the Iwan model is rate independent and ignores it.

        Returns
        -------
        force : float
            Joint force [N].
        stiffness : float
            Consistent tangent ``dF/du`` [N/m] for motion from the committed state to ``u``.
        """
        try:  # text, complex, None and arrays fail here, at no cost
            if self._blo < u < self._bhi:
                # Fast path, the usual case: u continues the current branch without reaching
                # the point where its loop closes (see _set_branch); the numbers of the walk.
                u = float(u)
                x = u - self._bur
                h = self._bc1 * abs(x)  # r = |x|/phi_max on the branch's scale
                if h < 1.0:
                    q = h**self._e1
                    f = h * (self._KTpm - self._a * q)
                    K = self._KT - self._b * q
                else:
                    f = self._Fs
                    K = 0.0
                F = self._bFr + self._bc2 * f if x >= 0.0 else self._bFr - self._bc2 * f
                self._tu = u
                self._tF = F
                self._tK = K
                self._tfast = True
                self._has_trial = True
                return F, K
            u = float(u)
        except (TypeError, ValueError):
            raise ValueError(f"u must be a real number (displacement [m]), got {u!r:.40}") from None
        if not _NINF < u < _INF:
            raise ValueError(f"u must be finite, got {u}")
        n, F, K, dW, dD, G, I = self._kernel(u)
        self._tu = u
        self._tF = F
        self._tK = K
        self._tn = n
        self._tacc = (dW, dD, G, I)
        self._tfast = False
        self._has_trial = True
        return F, K

    def commit(self) -> None:
        """Accept the last trial as the new committed state (no-op if there is none)."""
        if not self._has_trial:
            return
        if self._tfast:  # one segment on the current branch (see trial)
            u = self._tu
            xb = self._bc1 * abs(u - self._bur)
            if xb < 1.0:  # _G(xb) and _IH(xb), inlined, sharing the power
                p3 = xb**self._e3
                Gb = self._g2 * xb * xb - self._g3 * p3
                Ib = self._ih_c * p3
            else:
                Gb = self._g_pm + self._Fspm * (xb - 1.0)
                Ib = self._ih_pm + self._Fspm * (xb - 1.0)
            if self._bc2 == 2.0:  # a branch from a reversal point
                self._W += self._bFr * (u - self._u) + 4.0 * (Gb - self._Gc)
                self._D += 2.0 * (Ib - self._IHc)
            else:  # the virgin curve
                self._W += Gb - self._Gc
                self._D += max(Ib - self._IHc, 0.0)
            self._Gc = Gb
            self._IHc = Ib
            self._u = u
            self._F = self._tF
            self._K = self._tK
            self._has_trial = False
            if self._bdir > 0:  # the fast interval now starts at u
                self._blo = u
            else:
                self._bhi = u
            return
        dW, dD, self._Gc, self._IHc = self._tacc
        self._n = self._tn  # the trial wrote its reversal above the committed stack
        self._u = self._tu
        self._F = self._tF
        self._K = self._tK
        self._W += dW
        self._D += dD
        self._has_trial = False
        self._set_branch()

    def _set_branch(self) -> None:
        """Cache the branch through the committed state for the fast path of :meth:`trial`.

        The walk leaves the branch unchanged (no reversal, no loop closed) exactly when
        ``u`` lies strictly between the committed ``u_c`` and, in the branch's direction,
        the point where its loop closes (the reversal below the top one, or ``-u_r`` for the
        last one; none on the virgin curve): the open interval ``(_blo, _bhi)``. (The walk
        decides with the same sign comparisons, so the two agree at any magnitude.) On that
        branch the force is
        ``F_r + c2 F_bb(c1 |u - u_r|)`` with the sign of ``u - u_r``: ``c1, c2 = 1/2, 2``
        from a reversal point, ``1, 1`` with ``u_r = F_r = 0`` on the virgin curve.
        """
        n = self._n
        uc = self._u
        if n:
            ur = float(self._us[n - 1])
            d = uc - ur
            bound = float(self._us[n - 2]) if n >= 2 else -ur
            self._bur = ur
            self._bFr = float(self._Fr[n - 1])
            self._bc1 = 0.5 * self._ipm
            self._bc2 = 2.0
        else:
            d = uc
            bound = math.copysign(_INF, uc)
            self._bur = 0.0
            self._bFr = 0.0
            self._bc1 = self._ipm
            self._bc2 = 1.0
        if d > 0.0:
            self._blo, self._bhi, self._bdir = uc, bound, 1
        elif d < 0.0:
            self._blo, self._bhi, self._bdir = bound, uc, -1
        else:  # no direction yet: always the general walk
            self._blo, self._bhi, self._bdir = 0.0, 0.0, 0

    # ------------------------------------------------------------------ state read-out
    # (displacement, force, work, dissipated and stored energy: CommittedState)
    @property
    def stiffness(self) -> float:
        """Committed consistent tangent [N/m]."""
        return self._K

    @property
    def reversal_depth(self) -> int:
        """Number of reversal points remembered (committed)."""
        return self._n

    def reversal_points(self) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the remembered reversal points ``(u_r [m], F_r [N])``, oldest first."""
        return self._us[: self._n].copy(), self._Fr[: self._n].copy()

    def force_history(self, u, v=None) -> np.ndarray:
        """Forces [N] for a whole displacement history ``u`` [m], shape (n,), from the virgin
        state. Each sample is committed in turn on a private copy; this element is untouched.
        The joint is rate independent: velocities ``v`` [m/s] (shape (n,)), accepted like
        every element's, are checked and do not change the forces.
        """
        arr = finite_array("u", u, ndim=1)
        if v is not None:
            same_length(u=arr, v=finite_array("v", v, ndim=1))
        return masing_history(arr, self._p, reversal_tol=self._rtol)[0]

    def __repr__(self) -> str:
        return f"IwanJoint({self._p!r}, depth={self._n}, u={self._u:.6g})"

    # ------------------------------------------------------------------ kernel
    def _kernel(self, u: float):
        """The compiled walk (:func:`iwan_element.core.masing.masing_step`) from the committed
        state to ``u``: ``(n, F, K, dW, dD, G, I_H)``; the new stack is the first ``n``
        entries of the arrays (a reversal is written above the committed ones).
        """
        if self._n + 1 >= self._us.size:  # room for one more reversal
            grow = self._us.size
            self._us = np.concatenate([self._us, np.empty(grow)])
            self._Fr = np.concatenate([self._Fr, np.empty(grow)])
            self._at = np.concatenate([self._at, np.empty(grow, np.int64)])
        return masing_step(
            self._c,
            self._us,
            self._Fr,
            self._at,
            self._n,
            self._u,
            self._F,
            self._Gc,
            self._IHc,
            u,
            _NOSEG,
        )

    def _walk(self, u: float, acc):
        """The general walk to ``u`` (the fast path's reference in the tests).

        Returns ``(n, None, 0.0, F, K)``: the new stack is the first ``n`` entries of the
        stack arrays (the kernel writes a new reversal in place, above the committed entries).
        With ``acc = [W, D, G, I_H]`` the work and dissipation of the move are added to it and
        ``G``, ``I_H`` at ``u`` put in its last two entries.
        """
        n, F, K, dW, dD, G, I = self._kernel(float(u))
        if acc is not None:
            acc[0] += dW
            acc[1] += dD
            acc[2] = G
            acc[3] = I
        return n, None, 0.0, F, K
