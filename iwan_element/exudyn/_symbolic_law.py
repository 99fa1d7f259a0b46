"""The exact Iwan force law as an Exudyn symbolic expression (no Python call per evaluation).

The trial force of an Iwan joint at slip ``u``, given its committed state, follows the
extended Masing rules (REFERENCE.md section 2; paper eqs. 13-15):

* from the committed slip ``u_c`` the motion either continues the current branch or reverses
  (a new reversal point at ``(u_c, F_c)``);
* moving on, it closes every inner loop whose older reversal point it passes (Madelung's
  rule: both points of the loop are forgotten; with one point left, passing ``-u_r`` returns
  to the virgin curve);
* on the branch that leaves ``(u_r, F_r)`` the force is ``F_r + 2 F_bb((u - u_r)/2)``,
  on the virgin curve ``F_bb(u)``, with the odd backbone ``F_bb``.

:class:`SymbolicIwanState` holds the committed state of one point in named ``esym.Real``
variables: the committed slip ``u_c``, the stack depth ``n`` and the newest ``depth``
reversal points ``(r_k, R_k)``. :func:`iwan_force_expression` builds the trial force from
them with nested ``IfThenElse`` (Exudyn evaluates only the branch taken, so a deep
expression costs nothing until a step closes loops). The variables are set by the Python
commit once per accepted step: ``u_c`` at every step, the stack only when it changed.

Exactness: the expression is exact as long as a step reads no reversal point older than the
``depth`` it holds. :meth:`SymbolicIwanState.disagrees` checks, after the exact commit and
only for steps whose stack changed, that the law gave the exact force at the accepted slip.
"""
from __future__ import annotations

import itertools

import exudyn as exu

__all__: list[str] = []

esym = exu.symbolic
_IDS = itertools.count()


def _const(x: float):
    return esym.Real(float(x))


class SymbolicIwanState:
    """Named symbolic variables of one Iwan point, and the law built on them.

    Parameters
    ----------
    params : IwanParameters
        The joint parameters (embedded as constants).
    depth : int
        Number of reversal points the expression holds (>= 2).
    tol : float
        Absolute reversal tolerance [m] (``reversal_tol * phi_max``).
    """

    def __init__(self, params, depth: int, tol: float):
        uid = next(_IDS)
        self.depth = depth
        self.uc = esym.Real(f"iwan{uid}_uc", 0.0)
        self.n = esym.Real(f"iwan{uid}_n", 0.0)
        self.r = [esym.Real(f"iwan{uid}_r{k}", 0.0) for k in range(depth)]
        self.R = [esym.Real(f"iwan{uid}_R{k}", 0.0) for k in range(depth)]
        # derived from the stack (set with it): direction of the branch from the newest
        # reversal point (0 on the virgin curve) and the slip where its loop closes
        self.s = esym.Real(f"iwan{uid}_s", 0.0)
        self.b = esym.Real(f"iwan{uid}_b", 0.0)
        self.KT = float(params.KT)
        self.Fs = float(params.Fs)
        self.pm = float(params.phi_max)
        self.e1 = float(params.chi + 1.0)
        self.a = float(params.R / ((params.chi + 1.0) * (params.chi + 2.0)))
        self.tol = float(tol)
        self.probe = None        # u -> F through the owner's symbolic user function

    # ------------------------------------------------------------------ state transfer
    def set_stack(self, us, Fr) -> None:
        """Write the newest ``depth`` reversal points of the stack (oldest first) and its
        length to the variables."""
        n = len(us)
        self.n.SetValue(float(n))
        m = min(n, self.depth)
        for k in range(m):                   # r[0] is the newest point
            self.r[k].SetValue(us[n - 1 - k])
            self.R[k].SetValue(Fr[n - 1 - k])
        # the branch from r0 heads for the point where its loop closes (the point below
        # it, or -r0 for the last one): Masing's rule, REFERENCE.md section 2
        if n:
            b = float(us[n - 2]) if n >= 2 else -float(us[n - 1])
            d = b - float(us[n - 1])
            self.s.SetValue(1.0 if d > 0.0 else (-1.0 if d < 0.0 else 0.0))
            self.b.SetValue(b)
        else:
            self.s.SetValue(0.0)
            self.b.SetValue(0.0)

    def set_uc(self, u: float) -> None:
        self.uc.SetValue(u)

    def disagrees(self, u: float, force: float) -> bool:
        """True if the law, with the variables as they are (the state before the step just
        committed), does not give the exact ``force`` [N] at the accepted slip ``u`` [m]:
        the step needed an older reversal point than the expression holds. Evaluated only
        for steps whose reversal stack changed, through :attr:`probe` (``u -> F``, set by
        the owner to evaluate its symbolic user function)."""
        return not abs(self.probe(u) - force) <= 1e-9 * self.Fs

    # ------------------------------------------------------------------ the law
    def backbone(self, x):
        """``F_bb(x)`` for ``x >= 0`` (REFERENCE.md section 2, paper eq. 12)."""
        return esym.IfThenElse(x < self.pm, x * (self.KT - self.a * esym.pow(x, self.e1)),
                               _const(self.Fs))

    def _virgin(self, u):
        return esym.sign(u) * self.backbone(esym.abs(u))

    def _branch(self, r, R, u):
        x = u - r
        return R + esym.sign(x) * (2.0 * self.backbone(0.5 * esym.abs(x)))

    def exact(self, u):
        """Trial force [N] at the symbolic slip ``u`` by the full reversal-point law (no
        shortcut; a caller with its own branch shortcut, the interface, wraps this)."""
        uc, n = self.uc, self.n
        du = u - uc
        moving = du != 0.0

        def passed(b):
            return ((u - b) * du >= 0.0) * moving

        def chain(T, m, j):
            if j >= len(T):                  # deeper than held: only reached on overflow
                return self._virgin(u)
            r, R = T[j]
            single = esym.IfThenElse(passed(-r), self._virgin(u), self._branch(r, R, u))
            if j + 1 < len(T):
                inner = esym.IfThenElse(passed(T[j + 1][0]), chain(T, m, j + 2),
                                        self._branch(r, R, u))
            else:
                inner = self._branch(r, R, u)
            return esym.IfThenElse(m <= j + 0.5, self._virgin(u),
                                   esym.IfThenElse(m <= j + 1.5, single, inner))

        held = list(zip(self.r, self.R))
        d = esym.IfThenElse(n >= 0.5, uc - self.r[0], uc)        # direction of the branch
        Fc = esym.IfThenElse(n >= 0.5, self._branch(self.r[0], self.R[0], uc), self._virgin(uc))
        f_cont = chain(held, n, 0)
        f_new = chain([(uc, Fc)] + held, n + 1.0, 0)
        f_small = esym.IfThenElse(n >= 0.5, chain(held[1:], n - 1.0, 0), self._virgin(u))
        f_rev = esym.IfThenElse(esym.abs(d) <= self.tol, f_small, f_new)
        return esym.IfThenElse(d * du < 0.0, f_rev, f_cont)

    def force(self, u):
        """Trial force [N] at the symbolic slip ``u`` (an expression of the solver's marker
        quantities): the branch shortcut in front of :meth:`exact`."""
        uc = self.uc
        # the usual trial continues the branch from r0 strictly between u_c and the point b
        # where its loop closes (IwanJoint's own shortcut): the branch alone, with
        # y = |u - r0| = (u - r0) s and 2 F_bb(y/2) = y (KT - a 2^-(chi+1) y^(chi+1))
        s, b = self.s, self.b
        fast = ((u - uc) * s > 0.0) * ((b - u) * s > 0.0)
        y = (u - self.r[0]) * s
        a2 = self.a * 0.5 ** self.e1
        f_fast = self.R[0] + esym.IfThenElse(y < 2.0 * self.pm,
                                             s * (y * (self.KT - a2 * esym.pow(y, self.e1))),
                                             s * (2.0 * self.Fs))
        return esym.IfThenElse(fast, f_fast, self.exact(u))


def make_probe(mbs, fn, kind, axis, off):
    """``u -> F`` through the symbolic user function ``fn`` (no new expression)."""
    if kind == "coordinate":
        return lambda u: fn.Evaluate(mbs, 0.0, 0, u + off, 0.0, 0.0, 0.0, 0.0)
    a = axis
    zero = [0.0, 0.0, 0.0]

    def probe(u):
        d = u + off
        f = fn.Evaluate(mbs, 0.0, 0, [d * a[0], d * a[1], d * a[2]], zero, zero, zero, zero)
        return a[0] * f[0] + a[1] * f[1] + a[2] * f[2]
    return probe


def coordinate_law(st: SymbolicIwanState, off: float):
    """Spring-force user function (ObjectConnectorCoordinateSpringDamper) to be traced."""
    def law(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        return st.force(deltaL - off if off else deltaL)
    return law


def cartesian_law(st: SymbolicIwanState, a, off: float):
    """Spring-force user function (ObjectConnectorCartesianSpringDamper) along the unit
    axis ``a``; components with ``a_k = 0`` are constant zeros (a shared sub-expression is
    evaluated once per appearance, so the law appears only in the non-zero components)."""
    def law(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        u = None
        for k in range(3):
            if a[k] != 0.0:
                term = displacement[k] if a[k] == 1.0 else displacement[k] * a[k]
                u = term if u is None else u + term
        F = st.force(u - off if off else u)
        return [esym.Real(0.0) if a[k] == 0.0 else (F if a[k] == 1.0 else F * a[k])
                for k in range(3)]
    return law
