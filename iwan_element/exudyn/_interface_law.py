"""The interface's symbolic Iwan law: a short continuation path in front of the exact law.

At nearly every evaluation a contact point continues the branch it is on (no reversal, no
closed loop). For that case the law is the Masing branch formula alone (REFERENCE.md
section 2, paper eqs. 13-15): on the branch that left ``(u_r, F_r)`` in the direction
``s = +-1``, ``F = F_r + 2 s F_bb(s (u - u_r) / 2)``, and on the virgin curve
``F = s F_bb(s u)``, written ``F_r + s2 F_bb(s1 (u - u_r))`` with ``s1 = c1 s``,
``s2 = c2 s`` (``c1, c2 = 1/2, 2`` from a reversal point, ``1, 1`` virgin). On that branch
``sign(u - u_r) = s``, so this is bit for bit the formula of the exact law. It is taken while
the trial slip lies beyond the committed slip ``u_c`` in the branch direction and before the
branch's bound (the older reversal point it would close on, ``-u_r`` for the return to the
virgin curve, or infinity on the virgin curve): ``((u - u_c) s > 0) ((bound - u) s > 0)``.
Every other trial (a reversal, a loop closure, a point at rest with ``s = 0``) falls
through to the full exact law of :mod:`._symbolic_law` (``SymbolicIwanState.exact``, not
``force``, whose own shortcut is a subset of this one).

State: the branch ``(u_r, F_r, s1, s2, s, bound)`` of each point in named ``esym.Real``
variables, written only when the point leaves its branch; the committed slips of all points
in symbolic ``Vector``s of 6 (:func:`committed_slip_vectors`; one ``SetVector`` per 6 points
per accepted step; Exudyn 1.13.6 crashed on a 50-entry symbolic vector indexed in an
expression). The full law reads ``u_c`` from the same vector entry.
"""
from __future__ import annotations

import itertools

import exudyn as exu

__all__: list[str] = []

esym = exu.symbolic
_IDS = itertools.count()
_NAMES = ("ur", "Fr", "s1", "s2", "dir", "bound")
VIRGIN = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0)
CHUNK = 6                     # entries per symbolic Vector (longer ones crash Exudyn 1.13.6)


def committed_slip_vectors(n: int) -> list:
    """Symbolic vectors holding the committed slips of ``n`` points, ``CHUNK`` per vector."""
    uid = next(_IDS)
    return [esym.Vector(f"iwanuc{uid}_{k}", [0.0] * min(CHUNK, n - k * CHUNK))
            for k in range((n + CHUNK - 1) // CHUNK)]


class InterfacePointLaw:
    """The law of one point: branch formula when it continues its branch, else the exact law.

    Parameters
    ----------
    state : SymbolicIwanState
        The exact law and its reversal-stack variables; its ``uc`` is replaced by ``uc``.
    uc : esym expression
        The point's entry of the interface's committed-slip vectors.
    """

    def __init__(self, state, uc):
        uid = next(_IDS)
        self.state = state
        state.uc = uc
        self.vars = [esym.Real(f"iwanpt{uid}_{k}", v) for k, v in zip(_NAMES, VIRGIN)]
        self._setters = [v.SetValue for v in self.vars]

    def set_branch(self, ur, Fr, c1, c2, direction, bound) -> None:
        """Write the branch through the committed state (``direction`` +1, -1 or 0)."""
        for f, v in zip(self._setters, (ur, Fr, c1 * direction, c2 * direction, direction,
                                        bound)):
            f(v)

    def force(self, u):
        """Trial force [N] at the symbolic slip ``u``."""
        st = self.state
        ur, Fr, s1, s2, dr, bound = self.vars
        cont = Fr + s2 * st.backbone(s1 * (u - ur))
        fast = ((u - st.uc) * dr > 0.0) * ((bound - u) * dr > 0.0)
        return esym.IfThenElse(fast, cont, st.exact(u))  # its own shortcut already tried
