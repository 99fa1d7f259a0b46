"""A bank of independent exact Iwan joints committed in one vectorised call.

Each point ``i`` is an exact four-parameter Iwan joint with its own parameters and its own
reversal-point memory (the extended Masing rules of :mod:`iwan_element.core.joint`,
docs/equations.md section 2, paper eqs. 13-15). :meth:`IwanJointBank.commit` moves every point to a
new displacement at once:

* points that continue their current branch without a reversal and without closing a loop
  (nearly all points at nearly all steps of a time integration) only record the new
  displacement (three numpy operations for the whole bank); their force, work and
  dissipation follow in closed form from the branch and the values where it started
  (branch formula, ``G`` and ``I_H``: the same formulas as ``IwanJoint``'s fast path) and are
  evaluated for all points at once when :attr:`IwanJointBank.force`, ``work`` or
  ``dissipated_energy`` is read (the names :class:`IwanJoint` uses);
* plain reversals (a new branch that reaches no older reversal point in the step) are
  committed for all such points at once with numpy;
* the few points that close a loop (or start from rest) walk their reversal stack one by
  one with the compiled kernel every exact element shares (:mod:`iwan_element.core.masing`).

The bank is the committed state of a multi-contact interface. The solver's trial forces come
from the symbolic law of :mod:`iwan_element.exudyn.laws.symbolic_law`, which reads the state
this bank exposes; a Newton iteration that needs trial forces and consistent tangents of all
points reads them from the same state (:mod:`iwan_element.exudyn.laws.condensed`, with
:meth:`IwanJointBank.trial`, the compiled walk of every point's stack).
"""

from __future__ import annotations

import math

import numpy as np

from ..base.validation import check_scalar, finite_array
from .history import REVERSAL_TOL
from .joint import REVERSAL_TOL_MAX
from .masing import _NOSEG, bank_trial_rows, masing_constants, masing_step
from .parameters import IwanParameters

__all__ = ["IwanJointBank"]

_INF = math.inf
_NONE = np.empty(0, dtype=np.intp)


class IwanJointBank:
    """``n`` exact Iwan joints with vectorised commits.

    Parameters
    ----------
    params : sequence of IwanParameters
        One parameter set per point (SI units).
    reversal_tol : float, keyword-only
        Relative reversal tolerance, as for :class:`~iwan_element.IwanJoint` (default 1e-12,
        range ``[0, 1e-9]``); the absolute tolerance of point ``i`` is
        ``reversal_tol * phi_max_i``.

    Notes
    -----
    The forces, energies and reversal stacks equal those of ``n`` separate
    :class:`~iwan_element.IwanJoint` objects driven by the same displacements (tested to
    round-off).
    """

    def __init__(self, params, *, reversal_tol: float = REVERSAL_TOL):
        if isinstance(params, (str, bytes, dict)) or not hasattr(params, "__iter__"):
            raise ValueError(
                f"params must be a sequence of IwanParameters, got {type(params).__name__}"
            )
        params = list(params)
        if not params:
            raise ValueError("params must hold at least one IwanParameters, got an empty sequence")
        for i, p in enumerate(params):
            if not isinstance(p, IwanParameters):
                raise ValueError(
                    f"params[{i}] must be an IwanParameters instance, got {type(p).__name__}"
                )
        tol = check_scalar("reversal_tol", reversal_tol, low=0.0, high=REVERSAL_TOL_MAX)
        self._params = tuple(params)
        self._rtol = tol
        f = np.array
        self.KT = f([p.KT for p in params], dtype=float)
        self.Fs = f([p.Fs for p in params], dtype=float)
        self.pm = f([p.phi_max for p in params], dtype=float)
        chi = f([p.chi for p in params], dtype=float)
        R = f([p.R for p in params], dtype=float)
        self.e1 = chi + 1.0
        self.e3 = chi + 3.0
        self.a = R / ((chi + 1.0) * (chi + 2.0))  # backbone x (KT - a x^(chi+1))
        self.b = R / (chi + 1.0)  # tangent KT - b x^(chi+1)
        self.g_pm = 0.5 * self.KT * self.pm**2 - self.a * self.pm**self.e3 / self.e3
        self.ih_c = R / ((chi + 2.0) * (chi + 3.0))
        self.ih_pm = self.ih_c * self.pm**self.e3
        self.tol = tol * self.pm
        self._halfKT = 0.5 * self.KT
        self._a_e3 = self.a / self.e3
        self._e1s = float(self.e1[0]) if np.all(self.e1 == self.e1[0]) else None
        self._consts = [masing_constants(p, tol * p.phi_max) for p in params]
        self._C = np.array(self._consts)
        self.reset()

    # ------------------------------------------------------------------ state
    @property
    def n_points(self) -> int:
        """Number of joints in the bank."""
        return len(self._params)

    @property
    def params(self) -> tuple:
        """The parameter sets, one per point."""
        return self._params

    def reset(self) -> None:
        """Return every point to the virgin, unloaded state; energies to zero."""
        n = self.n_points
        z = np.zeros(n)
        self.u = z.copy()
        self._F, self._W, self._D = z.copy(), z.copy(), z.copy()
        self._Gc, self._IHc = z.copy(), z.copy()
        # the branch through the committed state and the values where it started
        self.u0, self.W0, self.D0, self.G0, self.I0 = (
            z.copy(),
            z.copy(),
            z.copy(),
            z.copy(),
            z.copy(),
        )
        self._us = np.empty((n, 8))  # reversal stacks, oldest first: the first _nst[i]
        self._Fr = np.empty((n, 8))  # entries of row i (one more column than the deepest)
        self._at = np.empty((n, 8), np.int64)
        self.bur, self.bFr = z.copy(), z.copy()
        self.bc1, self.bc2 = np.ones(n), np.ones(n)
        self.blo, self.bhi = z.copy(), z.copy()
        self.bdir, self.bound = z.copy(), z.copy()
        self._c4 = np.ones(n)  # 4 on a branch from a reversal, 1 virgin
        self._up = np.zeros(n, dtype=bool)  # the branch runs towards larger u
        self._down = np.zeros(n, dtype=bool)  # ... towards smaller u
        self._stale = False  # F, W, D lag behind u (see _sync)
        self._nst = np.zeros(n, dtype=np.intp)  # stack lengths
        self.us = _Stacks(self, "_us")  # read-only views of the live entries
        self.Fr = _Stacks(self, "_Fr")
        self._fast_buf = np.zeros(n, dtype=bool)
        self._above_buf = np.zeros(n, dtype=bool)
        for i in range(n):
            self._set_branch(i)

    # ------------------------------------------------------------------ committed values
    @property
    def force(self) -> np.ndarray:
        """Committed force of every point [N], shape (n_points,) (resists positive slip)."""
        if self._stale:
            self._sync()
        return self._F

    @property
    def work(self) -> np.ndarray:
        """Work done on every point since the reset [J], shape (n_points,)."""
        if self._stale:
            self._sync()
        return self._W

    @property
    def dissipated_energy(self) -> np.ndarray:
        """Energy dissipated by every point since the reset [J], shape (n_points,)."""
        if self._stale:
            self._sync()
        return self._D

    @property
    def stored_energy(self) -> np.ndarray:
        """Stored (slider spring) energy of every point [J], shape (n_points,)."""
        return self.work - self.dissipated_energy

    def depth(self, i: int) -> int:
        """Number of reversal points remembered by point ``i``."""
        return int(self._nst[i])

    # ------------------------------------------------------------------ commit
    def commit(self, u) -> np.ndarray:
        """Move every point to the displacements ``u`` [m] (shape (n_points,)) and commit.

        Returns
        -------
        ndarray of int
            Indices of the points that left their branch (a reversal, a closed loop, or no
            move): their reversal stacks may differ from before the call.

        Notes
        -----
        A point that continues its branch only records ``u``; its force and energies follow
        in closed form from the branch and the values where the branch started (the Masing
        branch formula, and the telescoped sums of ``G`` and ``I_H``, docs/equations.md section 2),
        evaluated for all points at once when :attr:`F`, :attr:`W` or :attr:`D` is read.
        """
        u = np.asarray(u, dtype=float)
        fast, above = self._fast_buf, self._above_buf
        np.less(self.blo, u, out=fast)
        np.less(u, self.bhi, out=above)
        fast &= above
        if np.count_nonzero(fast) == fast.size:
            np.copyto(self.u, u)
            np.copyto(self.blo, u, where=self._up)
            np.copyto(self.bhi, u, where=self._down)
            self._stale = True
            return _NONE
        if self._stale:
            self._sync()  # the walks start from the committed values
        slow = np.flatnonzero(~fast)
        if not np.all(np.isfinite(u[slow])):
            bad = slow[~np.isfinite(u[slow])][0]
            raise ValueError(f"u must be finite, got u[{bad}] = {u[bad]}")
        np.copyto(self.u, u, where=fast)
        np.copyto(self.blo, u, where=fast & self._up)
        np.copyto(self.bhi, u, where=fast & self._down)
        rest = self._reversals(u, slow) if slow.size > 2 else slow
        for i in rest.tolist():
            self._walk_commit(i, float(u[i]))
        self._stale = True
        return slow

    def _reversals(self, u, slow) -> np.ndarray:
        """Commit the plain reversals among ``slow`` at once and return the other points.

        A plain reversal leaves its branch backwards (beyond the reversal tolerance) and does
        not reach the bound of the new branch from ``(u_c, F_c)`` (the newest older reversal
        point, or ``-u_c`` on the virgin curve): ``IwanJoint``'s walk then pushes ``(u_c, F_c)``
        and moves on the new branch, ``F = F_c + 2 F_bb(x/2)``, work ``F_c x + 4 G(|x|/2)``,
        dissipation ``2 I_H(|x|/2)`` with ``x = u - u_c`` (docs/equations.md section 2).
        """
        uu = u[slow]
        uc = self.u[slow]
        du = uu - uc
        dr = self.bdir[slow]
        bound = np.where(self._nst[slow] > 0, self.bur[slow], -uc)
        up = du > 0.0
        plain = (np.sign(du) == -dr) & (dr != 0.0)  # signs: du * dr may underflow
        plain &= np.abs(uc - self.bur[slow]) > self.tol[slow]
        plain &= np.where(up, uu < bound, uu > bound)
        if not plain.any():
            return slow
        idx = slow[plain]
        e, ub, bnd, upi = uc[plain], uu[plain], bound[plain], up[plain]
        eF = self._F[idx]
        x = ub - e
        f, Gb, Ib = self._curves(0.5 * np.abs(x), idx)
        W = self._W[idx] + (eF * x + 4.0 * Gb)  # as the walk sums it
        D = self._D[idx] + 2.0 * Ib
        self.u[idx] = ub
        self._F[idx] = eF + np.copysign(2.0 * f, x)
        self._W[idx], self._D[idx], self._Gc[idx], self._IHc[idx] = W, D, Gb, Ib
        self.u0[idx], self.W0[idx], self.D0[idx], self.G0[idx], self.I0[idx] = ub, W, D, Gb, Ib
        self.bur[idx], self.bFr[idx] = e, eF
        self.bc1[idx], self.bc2[idx], self._c4[idx] = 0.5, 2.0, 4.0
        self.bdir[idx] = np.where(upi, 1.0, -1.0)
        self.bound[idx] = bnd
        self._up[idx], self._down[idx] = upi, ~upi
        self.blo[idx] = np.where(upi, ub, bnd)
        self.bhi[idx] = np.where(upi, bnd, ub)
        for i, ei, Fi in zip(idx.tolist(), e.tolist(), eF.tolist()):
            self._room(i)
            k = self._nst[i]
            self._us[i, k] = ei
            self._Fr[i, k] = Fi
            self._nst[i] = k + 1
        return slow[~plain]

    def _curves(self, h, s):
        """Backbone ``F_bb(h)``, ``G(h)`` and ``I_H(h)`` for ``h >= 0`` at the points ``s``."""
        pm = self.pm[s]
        micro = h < pm
        hm = np.where(micro, h, pm)
        q = hm ** self.e1[s]
        f = np.where(micro, hm * (self.KT[s] - self.a[s] * q), self.Fs[s])
        p3 = q * hm * hm
        G = np.where(
            micro,
            hm * hm * self._halfKT[s] - self._a_e3[s] * p3,
            self.g_pm[s] + self.Fs[s] * (h - pm),
        )
        I = np.where(micro, self.ih_c[s] * p3, self.ih_pm[s] + self.Fs[s] * (h - pm))
        return f, G, I

    def _sync(self) -> None:
        """Force and energies of every point at its committed ``u`` from its branch: the branch
        formula ``F_r + c2 sign(x) F_bb(c1 |x|)`` and the closed-form work and dissipation since
        the branch started (the same formulas as ``IwanJoint``'s fast path).
        """
        u = self.u
        x = u - self.bur
        h = self.bc1 * np.abs(x)
        pm = self.pm
        micro = h < pm
        if micro.all():
            q = h ** (self._e1s if self._e1s is not None else self.e1)
            f = h * (self.KT - self.a * q)
            p3 = q * h * h  # h ** e3
            Gb = h * h * self._halfKT - self._a_e3 * p3
            Ib = self.ih_c * p3
        else:
            hm = np.where(micro, h, pm)
            q = hm**self.e1
            f = np.where(micro, hm * (self.KT - self.a * q), self.Fs)
            p3 = q * hm * hm
            Gb = np.where(
                micro, hm * hm * self._halfKT - self._a_e3 * p3, self.g_pm + self.Fs * (h - pm)
            )
            Ib = np.where(micro, self.ih_c * p3, self.ih_pm + self.Fs * (h - pm))
        bFr = self.bFr
        self._F = bFr + np.copysign(self.bc2 * f, x)
        self._W = self.W0 + bFr * (u - self.u0) + self._c4 * (Gb - self.G0)
        self._D = self.D0 + self.bc2 * np.maximum(Ib - self.I0, 0.0)
        self._Gc = Gb
        self._IHc = Ib
        self._stale = False

    # ------------------------------------------------------------------ one point
    def _room(self, i: int) -> None:
        """Make room for one more reversal point on the stack of point ``i``."""
        if self._nst[i] + 1 >= self._us.shape[1]:  # every row grows (a 2-D array)
            grow = (self.n_points, self._us.shape[1])
            self._us = np.hstack([self._us, np.empty(grow)])
            self._Fr = np.hstack([self._Fr, np.empty(grow)])
            self._at = np.hstack([self._at, np.empty(grow, np.int64)])

    def trial(self, u, F=None, K=None) -> tuple[np.ndarray, np.ndarray]:
        """Forces [N] and consistent tangents [N/m] of every point at the trial
        displacements ``u`` [m] (shape (n_points,)) from the committed state; nothing changes.

        The exact walk of each point's reversal stack (:func:`~.masing.bank_trial_rows`, the
        kernel every exact element shares): the tangent is the derivative of the force the
        walk gives (the consistent tangent a Newton iteration needs). ``F`` and ``K``: arrays
        of shape (n_points,) to fill (new ones if None).
        """
        u = np.ascontiguousarray(u, dtype=float)
        if u.shape != (self.n_points,):
            raise ValueError(f"u must have shape ({self.n_points},), got {u.shape}")
        if self._stale:
            self._sync()
        F = np.empty_like(u) if F is None else F
        K = np.empty_like(u) if K is None else K
        bank_trial_rows(self._C, self._us, self._Fr, self._at, self._nst, self.u, self._F, u, F, K)
        return F, K

    def _walk_commit(self, i: int, u: float) -> None:
        """Exact Masing walk of point ``i`` from its committed state to ``u`` (the compiled
        kernel, :func:`iwan_element.core.masing.masing_step`), committed.
        """
        self._room(i)
        n, F, _, dW, dD, G, I = masing_step(
            self._consts[i],
            self._us[i],
            self._Fr[i],
            self._at[i],
            int(self._nst[i]),
            float(self.u[i]),
            float(self._F[i]),
            float(self._Gc[i]),
            float(self._IHc[i]),
            u,
            _NOSEG,
        )
        self.u[i] = u
        self._F[i] = F
        self._W[i] += dW
        self._D[i] += dD
        self._Gc[i] = G
        self._IHc[i] = I
        self._nst[i] = n
        self._set_branch(i)

    def _set_branch(self, i: int) -> None:
        """Cache the branch through the committed state of point ``i`` (see
        ``IwanJoint._set_branch``): the open interval ``(blo, bhi)`` of displacements that
        continue it without a reversal or a closed loop.
        """
        n = int(self._nst[i])
        us = self._us[i]
        uc = float(self.u[i])
        self.u0[i], self.W0[i], self.D0[i] = uc, self._W[i], self._D[i]
        self.G0[i], self.I0[i] = self._Gc[i], self._IHc[i]
        if n:
            ur = float(us[n - 1])
            d = uc - ur
            bound = float(us[n - 2]) if n >= 2 else -ur
            self.bur[i], self.bFr[i], self.bc1[i], self.bc2[i] = ur, self._Fr[i][n - 1], 0.5, 2.0
            self._c4[i] = 4.0
        else:
            d = uc
            bound = math.copysign(_INF, uc)
            self.bur[i], self.bFr[i], self.bc1[i], self.bc2[i] = 0.0, 0.0, 1.0, 1.0
            self._c4[i] = 1.0
        self._up[i] = d > 0.0
        self._down[i] = d < 0.0
        if d > 0.0:
            self.blo[i], self.bhi[i], self.bdir[i], self.bound[i] = uc, bound, 1.0, bound
        elif d < 0.0:
            self.blo[i], self.bhi[i], self.bdir[i], self.bound[i] = bound, uc, -1.0, bound
        else:
            self.blo[i], self.bhi[i], self.bdir[i], self.bound[i] = uc, uc, 0.0, 0.0

    def force_history(self, u) -> np.ndarray:
        """Forces [N] of every point for a displacement history ``u`` [m] of shape
        (n_steps, n_points), from the virgin state, on a private copy (this bank is untouched).
        """
        arr = finite_array("u", u, ndim=2)
        if arr.shape[1] != self.n_points:
            raise ValueError(f"u must have shape (n_steps, {self.n_points}), got {arr.shape}")
        bank = IwanJointBank(self._params, reversal_tol=self._rtol)
        out = np.empty_like(arr)
        for k in range(arr.shape[0]):
            bank.commit(arr[k])
            out[k] = bank.force
        return out

    def __repr__(self) -> str:
        return f"IwanJointBank(n_points={self.n_points})"


class _Stacks:
    """Read-only access to the live reversal stacks of a bank: ``stacks[i]`` is a view of the
    committed entries of point ``i`` (oldest first).
    """

    __slots__ = ("_bank", "_name")

    def __init__(self, bank, name):
        self._bank, self._name = bank, name

    def __len__(self) -> int:
        return self._bank.n_points

    def __getitem__(self, i):
        return getattr(self._bank, self._name)[i, : self._bank._nst[i]]
