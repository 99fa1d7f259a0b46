"""The exact Iwan force law as an Exudyn symbolic expression (no Python call per evaluation).

The trial force of an Iwan joint at slip ``u``, given its committed state, follows the
extended Masing rules (docs/equations.md section 2; paper eqs. 13-15):

* from the committed slip ``u_c`` the motion either continues the current branch or reverses
  (a new reversal point at ``(u_c, F_c)``);
* moving on, it closes every inner loop whose older reversal point it passes (Madelung's
  rule: both points of the loop are forgotten; with one point left, passing ``-u_r`` returns
  to the virgin curve);
* on the branch that leaves ``(u_r, F_r)`` the force is ``F_r + 2 F_bb((u - u_r)/2)``,
  on the virgin curve ``F_bb(u)``, with the odd backbone ``F_bb``.

:class:`SymbolicIwanState` holds the committed state of one point in named symbolic
variables and builds the law on them (one form for the connector and the interface):

* the **branch shortcut** (:meth:`SymbolicIwanState.force`): at nearly every evaluation the
  trial continues the branch through the committed state, and the force is the Masing
  branch formula alone, ``F = F_r + s2 F_bb(s1 (u - u_r))`` with ``s1 = c1 s``,
  ``s2 = c2 s`` (``c1, c2 = 1/2, 2`` from a reversal point, ``1, 1`` virgin) and the branch
  direction ``s = +-1``; on that branch ``sign(u - u_r) = s``, so this is the formula of the
  exact law. It is taken while the trial lies strictly between ``u_c`` and the branch's
  bound ahead (the older reversal point it would close on, ``-u_r`` for the return to the
  virgin curve, infinity on the virgin curve): ``(u - u_c) (bound - u) > 0`` (four
  operations; a point at rest, ``s = 0``, holds ``bound = u_c``, so the test fails; a product
  that underflows to zero only sends the trial to the exact law);
* every other trial (a reversal, a loop closure, a point at rest with ``s = 0``) falls
  through to the full reversal-point law (:meth:`SymbolicIwanState.exact`, nested
  ``IfThenElse``: Exudyn evaluates only the branch taken, so a deep expression costs nothing
  until a step leaves its branch).

State (measured on Exudyn 1.13.6: a ``SetValue`` costs about 0.2 us, a ``SetVector`` of 6
about 0.3 us; reading a ``Vector`` entry in an expression costs about 10 ns more than
reading a named ``Real``; vectors of more than 6 entries (:data:`CHUNK`) indexed in an
expression crashed): the branch ``(u_r, F_r, s1, s2, bound)``, read at every evaluation, in
named ``Real``s; the stack depth ``n`` and the newest ``depth`` reversal points
``(r_k, R_k)``, read only off the shortcut, interleaved in ``ceil((2 depth + 1) / 6)``
vectors (only those holding live entries are written); the committed slip ``u_c`` in a named
``Real`` of the connector, or an entry of the interface's committed-slip matrix. The
Python commit writes ``u_c`` at every accepted step and the rest only when the point leaves
its branch.

Exactness: the expression is exact as long as a step reads no reversal point older than the
``depth`` it holds, i.e. always while the committed stack holds at most ``depth`` points.
:meth:`SymbolicIwanState.disagrees` checks, after the exact commit, that the law gave the
exact force at the accepted slip (needed only for steps that started from a deeper stack and
closed a loop).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Any

import exudyn as exu
from exudyn.advancedUtilities import CreateSymbolicUserFunction

__all__ = [
    "VIRGIN",
    "SymbolicIwanState",
    "committed_slip_matrix",
    "branch_of",
    "make_probe",
    "coordinate_law",
    "cartesian_law",
    "rigid_law",
]

esym = exu.symbolic
_IDS = itertools.count()
CHUNK = 6  # entries per symbolic Vector (longer ones crash Exudyn 1.13.6)
VIRGIN = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0)  # the branch of an unloaded virgin point
_VIRGIN_VARS = (0.0, 0.0, 0.0, 0.0, 0.0)  # its (u_r, F_r, s1, s2, bound)


def _const(x: float):
    return esym.Real(float(x))


def committed_slip_matrix(n: int) -> Any:
    """A symbolic 1 x ``n`` matrix holding the committed slips of ``n`` points: one
    ``SetMatrix`` per accepted step (``Get(0, i)`` reads entry ``i`` live; unlike a
    ``Vector``, a long ``Matrix`` row did not crash Exudyn 1.13.6 and costs 1 call instead
    of ``n / 6``).
    """
    return esym.Matrix(f"iwanuc{next(_IDS)}", [[0.0] * n])


def branch_of(us, Fr, uc: float) -> tuple:
    """``(u_r, F_r, c1, c2, s, bound)``: the branch through the committed slip ``uc`` of a
    joint with the reversal stack ``us``, ``Fr`` (oldest first; the same branch as
    ``IwanJoint._set_branch`` and ``IwanJointBank._set_branch``).
    """
    if len(us):
        ur = float(us[-1])
        d = uc - ur
        bound = float(us[-2]) if len(us) >= 2 else -ur
        head = (ur, float(Fr[-1]), 0.5, 2.0)
    else:
        d = uc
        bound = math.copysign(math.inf, uc)
        head = VIRGIN[:4]
    if d > 0.0:
        return head + (1.0, bound)
    if d < 0.0:
        return head + (-1.0, bound)
    return head + (0.0, uc)  # at rest: an empty interval for the shortcut


class SymbolicIwanState:
    """Symbolic variables of one Iwan point, and the law built on them.

    Parameters
    ----------
    params : IwanParameters
        The joint parameters (embedded as constants).
    depth : int
        Number of reversal points the expression holds (>= 2).
    tol : float
        Absolute reversal tolerance [m] (``reversal_tol * phi_max``).
    uc : esym expression, optional
        Where the committed slip is held (an entry of the interface's committed-slip
        vectors); default: a named ``Real`` of its own (:meth:`set_uc` writes it).
    """

    def __init__(self, params, depth: int, tol: float, uc=None):
        uid = next(_IDS)
        self.depth = depth
        self.uc = esym.Real(f"iwan{uid}_uc", 0.0) if uc is None else uc
        width = 2 * depth + 1  # n, then (r_k, R_k) newest first
        self._stack = [
            esym.Vector(f"iwan{uid}_st{k}", [0.0] * min(CHUNK, width - k * CHUNK))
            for k in range((width + CHUNK - 1) // CHUNK)
        ]
        self._chunks = [
            (v.SetVector, k * CHUNK, k * CHUNK + v.NumberOfItems())
            for k, v in enumerate(self._stack)
        ]
        self._vals = [0.0] * width
        entry = [v[k] for v in self._stack for k in range(v.NumberOfItems())]
        self.n = entry[0]
        self.r = entry[1::2]
        self.R = entry[2::2]
        self._branch = [
            esym.Real(f"iwan{uid}_{k}", v)
            for k, v in zip(("ur", "Fr", "s1", "s2", "bound"), _VIRGIN_VARS)
        ]
        self._branch_set = [v.SetValue for v in self._branch]
        self.held = 0  # stack length the variables hold
        self.KT = float(params.KT)
        self.Fs = float(params.Fs)
        self.pm = float(params.phi_max)
        self.e1 = float(params.chi + 1.0)
        self.a = float(params.R / ((params.chi + 1.0) * (params.chi + 2.0)))
        self.tol = float(tol)
        # u [m] -> F [N] through the owner's symbolic user function (set by the owner)
        self.probe: Callable[[float], float] | None = None

    # ------------------------------------------------------------------ state transfer
    def set_stack(self, us, Fr) -> None:
        """Write the newest ``depth`` reversal points of the stack (oldest first) and its
        length (only the vectors holding live entries).
        """
        n = len(us)
        m = min(n, self.depth)
        v = self._vals
        v[0] = float(n)
        if m:
            stop = n - m - 1 if n > m else None
            v[1 : 2 * m + 1 : 2] = us[:stop:-1]  # newest first
            v[2 : 2 * m + 2 : 2] = Fr[:stop:-1]
        end = 2 * m + 1
        for f, a, b in self._chunks:  # entries beyond 2 m are not read
            if a >= end:
                break
            f(v[a:b])
        self.held = n

    def set_branch(self, ur, Fr, c1, c2, direction, bound) -> None:
        """Write the branch through the committed state (``direction`` +1, -1 or 0; with
        0, ``bound`` must be the committed slip).
        """
        self.set_branch_values((ur, Fr, c1 * direction, c2 * direction, bound))

    def set_branch_values(self, values) -> None:
        """Write ``(u_r, F_r, s1, s2, bound)`` (see :meth:`set_branch`)."""
        a, b, c, d, e = self._branch_set
        a(values[0])
        b(values[1])
        c(values[2])
        d(values[3])
        e(values[4])

    def set_uc(self, u: float) -> None:
        """Write the committed slip (own ``Real`` only)."""
        self.uc.SetValue(u)

    def set_state(self, us, Fr, uc: float) -> None:
        """Write the whole committed state: stack ``us``, ``Fr`` (oldest first), slip ``uc``
        and the branch through it.
        """
        self.set_stack(us, Fr)
        self.set_uc(uc)
        self.set_branch(*branch_of(us, Fr, uc))

    def disagrees(self, u: float, force: float) -> bool:
        """True if the law, with the variables as they are (the state before the step just
        committed), does not give the exact ``force`` [N] at the accepted slip ``u`` [m]:
        the step needed an older reversal point than the expression holds. Only a step from
        a stack deeper than ``depth`` can (:attr:`held`); evaluated through :attr:`probe`
        (``u -> F``, set by the owner to evaluate its symbolic user function).
        """
        assert self.probe is not None, "the owner sets probe when it places the law"
        return not abs(self.probe(u) - force) <= 1e-9 * self.Fs

    # ------------------------------------------------------------------ the law
    def backbone(self, x) -> Any:
        """``F_bb(x)`` for ``x >= 0`` (docs/equations.md section 2, paper eq. 12)."""
        return esym.IfThenElse(
            x < self.pm, x * (self.KT - self.a * esym.pow(x, self.e1)), _const(self.Fs)
        )

    def _virgin(self, u):
        return esym.sign(u) * self.backbone(esym.abs(u))

    def _branch_force(self, r, R, u):
        x = u - r
        return R + esym.sign(x) * (2.0 * self.backbone(0.5 * esym.abs(x)))

    def exact(self, u) -> Any:
        """Trial force [N] at the symbolic slip ``u`` by the full reversal-point law (no
        shortcut).
        """
        uc, n = self.uc, self.n
        du = u - uc
        moving = du != 0.0

        def passed(b):
            return ((u - b) * du >= 0.0) * moving

        def chain(T, m, j):
            if j >= len(T):  # deeper than held: only reached on overflow
                return self._virgin(u)
            r, R = T[j]
            single = esym.IfThenElse(passed(-r), self._virgin(u), self._branch_force(r, R, u))
            if j + 1 < len(T):
                inner = esym.IfThenElse(
                    passed(T[j + 1][0]), chain(T, m, j + 2), self._branch_force(r, R, u)
                )
            else:
                inner = self._branch_force(r, R, u)
            return esym.IfThenElse(
                m <= j + 0.5, self._virgin(u), esym.IfThenElse(m <= j + 1.5, single, inner)
            )

        held = list(zip(self.r, self.R))
        d = esym.IfThenElse(n >= 0.5, uc - self.r[0], uc)  # direction of the branch
        Fc = esym.IfThenElse(
            n >= 0.5, self._branch_force(self.r[0], self.R[0], uc), self._virgin(uc)
        )
        f_cont = chain(held, n, 0)
        f_new = chain([(uc, Fc)] + held, n + 1.0, 0)
        f_small = esym.IfThenElse(n >= 0.5, chain(held[1:], n - 1.0, 0), self._virgin(u))
        f_rev = esym.IfThenElse(esym.abs(d) <= self.tol, f_small, f_new)
        return esym.IfThenElse(d * du < 0.0, f_rev, f_cont)

    def force(self, u) -> Any:
        """Trial force [N] at the symbolic slip ``u`` (an expression of the solver's marker
        quantities): the branch shortcut in front of :meth:`exact`.
        """
        ur, Fr, s1, s2, bound = self._branch
        cont = Fr + s2 * self.backbone(s1 * (u - ur))
        fast = (u - self.uc) * (bound - u) > 0.0
        return esym.IfThenElse(fast, cont, self.exact(u))


def make_probe(mbs, fn, kind, axis, off, k=None, st=None) -> Callable[..., Any]:
    """``u -> F`` through the symbolic user function ``fn`` (no new expression); ``k``: the
    linear springs the function also carries (see :func:`cartesian_law`), taken out again.
    ``kind="rigid"`` (a ``RigidBodySpringDamper`` law, whose ``Evaluate`` takes no matrix
    arguments in exudyn 1.13.6): a coordinate law on the same state ``st`` is made for the
    probe.
    """
    if kind == "rigid":
        fn = CreateSymbolicUserFunction(
            mbs,
            coordinate_law(st, 0.0),
            "springForceUserFunction",
            itemTypeName="ObjectConnectorCoordinateSpringDamper",
        )
        return lambda u, fn=fn: fn.Evaluate(mbs, 0.0, 0, u, 0.0, 0.0, 0.0, 0.0)
    if kind == "coordinate":
        return lambda u: fn.Evaluate(mbs, 0.0, 0, u + off, 0.0, 0.0, 0.0, 0.0)
    a = axis
    zero = [0.0, 0.0, 0.0]
    ka = 0.0 if k is None else float(sum(a[i] * a[i] * float(k[i]) for i in range(3)))

    def probe(u):
        d = u + off
        f = fn.Evaluate(mbs, 0.0, 0, [d * a[0], d * a[1], d * a[2]], zero, zero, zero, zero)
        F = a[0] * f[0] + a[1] * f[1] + a[2] * f[2]
        return F - ka * d if ka else F

    return probe


def coordinate_law(st: SymbolicIwanState, off: float, c: float = 0.0) -> Callable[..., Any]:
    """Spring-force user function (ObjectConnectorCoordinateSpringDamper) to be traced;
    ``c`` [N s/m]: a dashpot in parallel (``c deltaL_t`` added).
    """

    def law(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        F = st.force(deltaL - off if off else deltaL)
        return F + c * deltaL_t if c else F

    return law


def _along(a, vec):
    """``a . vec`` as an expression, without the terms of zero components."""
    u = None
    for i in range(3):
        if a[i] != 0.0:
            term = vec[i] if a[i] == 1.0 else vec[i] * a[i]
            u = term if u is None else u + term
    return u


def cartesian_law(
    st: SymbolicIwanState, a, off: float, k=None, c: float = 0.0
) -> Callable[..., Any]:
    """Spring-force user function (ObjectConnectorCartesianSpringDamper) along the unit
    axis ``a``; components with ``a_k = 0`` are constant zeros (a shared sub-expression is
    evaluated once per appearance, so the law appears only in the non-zero components).
    ``k`` (3 floats, optional): linear springs along the global axes added in the same
    object, ``k_i d_i`` as Exudyn's built-in Cartesian spring (no offset, no damping);
    ``c`` [N s/m]: a dashpot in parallel with the law along ``a``.
    """
    k = (0.0, 0.0, 0.0) if k is None else tuple(float(x) for x in k)

    def law(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        u = _along(a, displacement)
        F = st.force(u - off if off else u)
        if c:
            F = F + c * _along(a, velocity)
        out = []
        for i in range(3):
            f = None if a[i] == 0.0 else (F if a[i] == 1.0 else F * a[i])
            if k[i] != 0.0:
                f = displacement[i] * k[i] if f is None else f + displacement[i] * k[i]
            out.append(esym.Real(0.0) if f is None else f)
        return out

    return law


def rigid_law(st: SymbolicIwanState, a, off: float, c: float = 0.0) -> Callable[..., Any]:
    """Spring-force-torque user function (ObjectConnectorRigidBodySpringDamper) along the
    unit axis ``a`` fixed in the frame of marker 0 (the joint frame J0; ``displacement`` and
    ``velocity`` are given in it): the force ``F a`` in J0, no torque; ``c`` [N s/m]: a
    dashpot in parallel along ``a``.
    """

    def law(
        mbs,
        t,
        itemNumber,
        displacement,
        rotation,
        velocity,
        angularVelocity,
        stiffness,
        damping,
        rotJ0,
        rotJ1,
        offset,
    ):
        u = _along(a, displacement)
        F = st.force(u - off if off else u)
        if c:
            F = F + c * _along(a, velocity)
        out = [
            esym.Real(0.0) if a[i] == 0.0 else (F if a[i] == 1.0 else F * a[i]) for i in range(3)
        ]
        return out + [esym.Real(0.0)] * 3

    return law
