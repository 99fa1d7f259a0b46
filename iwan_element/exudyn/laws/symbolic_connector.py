"""The symbolic route of :func:`~iwan_element.exudyn.add_iwan_connector` (an ``IwanJoint``).

The force law is the exact Iwan law as an Exudyn symbolic expression
(:mod:`.symbolic_law`): no Python call and no Exudyn API call per force evaluation, so it
is safe with several solver threads. Once per accepted step the post-step work reads the
accepted slip (a view of the system coordinates) and writes it to the law's variable
``u_c``. That is all it does while the slip moves on along the current branch without
closing a loop (one interval test, the usual step): the joint's state on one branch is a
function of the end point alone (force, stored and dissipated energy are closed forms of
the branch, docs/equations.md section 2), so the ``IwanJoint`` is committed there only lazily —
at the next reversal or loop closure (then it is brought to the last point of the branch,
then walks the event exactly), at the end of the run and whenever the connector is read.
Only such events rewrite the law's branch and reversal stack.

Records hold ``(t, u)`` per accepted step; force and energies are replayed from a copy of
the joint taken when the records start (the same ``trial``/``commit`` sequence, so the
same numbers as a per-step commit) when they are read (:mod:`.symbolic_records`).

Depth overflow (a step needs an older reversal point than the expression holds) can only
happen while the committed stack is deeper than ``depth``. Only then a post-Newton user
function is installed (no cost otherwise): after each Newton solve it compares the law with
the exact joint at the converged slip; if they differ it writes to the variables the state
the joint would have after passing part of the step's loop closures (a state on the same
path, exact around the converged slip) and asks Exudyn for a discontinuous iteration, which
re-solves the step with it. See :func:`newton_check`.
"""

from __future__ import annotations

import copy
import logging
import math
from typing import Any

import exudyn as exu
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (
    ObjectConnectorCartesianSpringDamper,
    ObjectConnectorCoordinateSpringDamper,
    ObjectConnectorRigidBodySpringDamper,
)

from ..slips.slip_map import SlipMap
from .symbolic_law import (
    SymbolicIwanState,
    branch_of,
    cartesian_law,
    coordinate_law,
    make_probe,
    rigid_law,
)

__all__ = [
    "symbolic_item",
    "joint_tolerance",
    "symbolic_refresh",
    "branch_interval",
    "law_window",
    "flush_joint",
    "sync_stack",
    "walk_states",
    "newton_check",
    "reset_state",
]

_log = logging.getLogger(__name__)
_INF = math.inf
_OVT = exu.OutputVariableType


def symbolic_item(conn, depth: int, name: str, vis) -> Any:
    """The Exudyn connector item with the symbolic law; sets ``conn._state``."""
    joint = conn._joint
    st = SymbolicIwanState(joint.params, depth, joint_tolerance(joint))
    conn._state = st
    off = conn._offset
    c = conn._damping
    m = [int(x) for x in conn._markers]
    kind = "rigid" if conn._axis_marker is not None else conn._kind
    if kind == "coordinate":
        fn = CreateSymbolicUserFunction(
            conn._mbs,
            coordinate_law(st, off, c),
            "springForceUserFunction",
            itemTypeName="ObjectConnectorCoordinateSpringDamper",
        )
        item = ObjectConnectorCoordinateSpringDamper(
            name=name,
            markerNumbers=m,
            stiffness=0.0,
            damping=0.0,
            offset=off,
            springForceUserFunction=fn,
            visualization=vis,
        )
    elif kind == "rigid":  # the axis turns with marker 0 (RigidBodySpringDamper's J0)
        fn = CreateSymbolicUserFunction(
            conn._mbs,
            rigid_law(st, conn._axis, off, c),
            "springForceTorqueUserFunction",
            itemTypeName="ObjectConnectorRigidBodySpringDamper",
        )
        item = ObjectConnectorRigidBodySpringDamper(
            name=name, markerNumbers=m, springForceTorqueUserFunction=fn, visualization=vis
        )
    else:
        fn = CreateSymbolicUserFunction(
            conn._mbs,
            cartesian_law(st, conn._axis, off, c=c),
            "springForceUserFunction",
            itemTypeName="ObjectConnectorCartesianSpringDamper",
        )
        item = ObjectConnectorCartesianSpringDamper(
            name=name, markerNumbers=m, springForceUserFunction=fn, visualization=vis
        )
    conn._function = fn  # keep the expression tree alive
    st.probe = make_probe(conn._mbs, fn, kind, conn._axis, off, st=st)
    conn._snapshot = copy.deepcopy(joint)  # the records start from this state
    return item


def joint_tolerance(joint) -> float:
    """Absolute reversal tolerance [m] of an ``IwanJoint``."""
    return float(joint._tol)


def symbolic_refresh(conn, mbs, lazy_until=-_INF) -> None:
    """Start of a run: the slip reader, and the accept function bound to it. Steps at
    ``t < lazy_until`` may commit the joint lazily (see the module docstring).
    """
    conn._flush_joint()
    if conn._axis_marker is None:
        smap = SlipMap(mbs, [conn._markers], conn._kind, conn._axis, [conn._offset])
        conn._slip = _slip_reader(conn, smap)
    else:
        smap = None  # the axis turns: read in the joint frame J0
        conn._slip = _output_reader(conn, _OVT.DisplacementLocal, conn._offset)
    conn._read = smap  # the dispatcher then checks for a re-assembly per step
    conn._rate = _rate_reader(conn, mbs, smap) if conn._damping and conn._record_on else None
    conn._accept = _accept_function(conn, lazy_until)


def _output_reader(conn, variable, off):
    """``() -> a . out - off`` of the connector object's output ``variable`` (a vector: the
    displacement or velocity of marker 1 relative to marker 0, global or in J0): one Exudyn
    call, for markers whose position is not affine in the coordinates.
    """
    get = conn._mbs.GetObjectOutput
    obj = conn._object
    a0, a1, a2 = conn._axis

    def read():
        d = get(obj, variable)
        return float(a0 * d[0] + a1 * d[1] + a2 * d[2]) - off

    return read


def _rate_reader(conn, mbs, smap):
    """``() -> v``: the accepted slip rate (the dashpot's velocity, recorded per step): the
    slip map's row on a view of the ODE2 velocities, or the object's velocity output.
    """
    if smap is None:
        return _output_reader(conn, _OVT.VelocityLocal, 0.0)
    if smap.generic:
        return _output_reader(conn, _OVT.Velocity, 0.0)
    qt = mbs.systemData.GetODE2Coordinates_t(copy=False)
    item = qt.item
    terms = [(int(i), float(c)) for i, c in zip(smap.idx[0], smap.coef[0]) if c != 0.0]

    def rate():
        v = 0.0
        for i, c in terms:
            v += c * item(i)
        return v

    return rate


def _slip_reader(conn, smap):
    """``() -> u``: the accepted slip from the view of the ODE2 coordinates (no copy), or
    from the connector's displacement output where the markers are not affine.
    """
    if smap.generic:
        return _output_reader(conn, _OVT.Displacement, conn._offset)
    item = smap.q.item
    terms = [(int(i), float(c)) for i, c in zip(smap.idx[0], smap.coef[0]) if c != 0.0]
    c0 = float(smap.c[0])
    if len(terms) == 1 and terms[0][1] == 1.0:
        i = terms[0][0]
        read = lambda: c0 + item(i)  # noqa: E731
        read.single = (c0, i)
        return read
    if len(terms) == 2 and terms[0][1] == -1.0 and terms[1][1] == 1.0:
        i0, i1 = terms[0][0], terms[1][0]
        return lambda: c0 + item(i1) - item(i0)

    def read():
        u = c0
        for i, c in terms:
            u += c * item(i)
        return u

    return read


def branch_interval(joint) -> tuple[float, float, bool]:
    """``(lo, hi, up)``: the open interval of slips that continue the joint's current branch
    without a reversal or a loop closure (the extended Masing rules: between the committed
    slip and, ahead, the point where the branch's loop closes; the interval of
    ``IwanJoint``'s own shortcut), and the branch's direction; empty before the first
    motion.
    """
    us, _ = joint.reversal_points()
    uc = joint.displacement
    if len(us):
        d = uc - us[-1]
        bound = float(us[-2]) if len(us) >= 2 else -float(us[-1])
    else:
        d = uc
        bound = math.copysign(_INF, uc)
    if d > 0.0:
        return uc, bound, True
    if d < 0.0:
        return bound, uc, False
    return 0.0, 0.0, True


def law_window(joint, depth: int) -> tuple[float, float]:
    """Open interval of slips at which the law, holding the newest ``depth`` reversal points
    of the joint's committed stack, is exact for the next step: ends at the ``depth // 2``-th
    loop-closing point the walk passes either way (docs/equations.md section 2); the whole line
    when the stack fits.
    """
    us, Fr = joint.reversal_points()
    if len(us) <= depth:
        return -_INF, _INF
    us, Fr = us.tolist(), Fr.tolist()
    uc, Fc, tol = joint.displacement, joint.force, joint_tolerance(joint)
    k = depth // 2 - 1
    ends = []
    for far in (-1e300, 1e300):
        states = walk_states(us, Fr, uc, Fc, far, tol, limit=k + 1)
        ends.append(states[k][0] if len(states) > k else far)
    return ends[0], ends[1]


#: Record values (t, u) kept in the list buffer at most until the next event (then moved to
#: the array of the records).
RECORD_BLOCK = 8192

#: The post-Newton check is armed when the slip comes closer to the end of the law's exact
#: window than this many times the largest slip increment of one step on the current branch
#: segment (and the step that started it).
ARM_MARGIN = 10.0


def _commit_event(conn, t, u) -> None:
    """Commit the joint at an event step and bring the law's stack or branch up to date."""
    joint = conn._joint
    conn._flush_joint()
    n = joint.reversal_depth
    joint.trial(u)
    joint.commit()
    if joint.reversal_depth != n or conn._window:
        sync_stack(conn, t)
    else:  # same stack; the branch may start (from rest)
        us, Fr = joint.reversal_points()
        conn._state.set_branch(*branch_of(us, Fr, u))
        conn._state.uc.SetValue(u)


def _risk(conn, u, margin):
    """The law's exact window ``(wa, wb)`` and whether ``u`` is within ``margin`` of its
    ends (then every step is committed); tells the dispatcher when that changes.
    """
    wa, wb = law_window(conn._joint, conn._state.depth)
    risky = not wa + margin < u < wb - margin
    if risky != conn._risky:
        conn._risky = risky
        conn._dispatcher.set_risky(conn, risky)
    return wa, wb, risky


def _accept_function(conn, lazy_until):
    """The per-step work of one connector (see the module docstring)."""
    joint = conn._joint
    set_uc = conn._state.uc.SetValue
    read = conn._slip
    buf = conn._buf  # (t, u) of the newest steps; list.append is ~3x faster than
    rec = buf.append if conn._record_on else None  # array.append (moved at events)
    rate = conn._rate  # () -> v, recorded with (t, u) when there is a dashpot
    keep = conn._rec.fromlist
    lo = hi = 0.0  # the open interval of plain continuations (empty: slow path)
    up = True
    dmax = 0.0  # largest slip increment of one step on this branch segment
    at_event = None  # slip of the last step that took the slow path

    def event(t, u):
        nonlocal lo, hi, up, dmax, at_event
        if t < conn._t_acc:
            conn._new_run(t, u)
        prev = last_accepted()
        if prev is None:
            prev = at_event
        if prev is not None:
            dmax = max(dmax, abs(u - prev))
        at_event = u
        margin = ARM_MARGIN * dmax
        dmax = 0.0  # the next branch segment starts its own count
        _commit_event(conn, t, u)
        conn._t_acc = t
        wa, wb, risky = _risk(conn, u, margin)
        if len(buf) >= RECORD_BLOCK:
            keep(buf)
            buf.clear()
        if t < lazy_until and not risky:
            lo, hi, up = branch_interval(joint)
            lo, hi = max(lo, wa + margin), min(hi, wb - margin)
        else:
            lo = hi = 0.0

    single = getattr(read, "single", None)  # (c0, i): u = c0 + q[i]
    if single is not None:
        c0, i = single
        item = conn._read.q.item
    else:
        c0, i = 0.0, 0
        item = lambda _: read()  # noqa: E731

    def accept(t):
        nonlocal lo, hi, dmax
        u = c0 + item(i)
        if lo < u < hi and t < lazy_until:
            if up:
                d = u - lo
                lo = u
            else:
                d = hi - u
                hi = u
            if d > dmax:
                dmax = d
            set_uc(u)
        else:
            event(t, u)
        if rec is not None:
            rec(t)
            rec(u)
            if rate is not None:
                rec(rate())

    def last_accepted():
        """The last accepted slip while steps are left uncommitted, else ``None``."""
        if lo < hi:
            return lo if up else hi
        return None

    conn._lazy_last = last_accepted
    return accept


def flush_joint(conn) -> None:
    """Commit the joint at the last accepted slip if that was left pending."""
    u = conn._lazy_last()
    if u is not None and u != conn._joint.displacement:
        conn._joint.trial(u)
        conn._joint.commit()


def sync_stack(conn, t=None) -> None:
    """Write the joint's committed state (reversal stack, slip and the branch through it) to
    the law's variables, and check that the step just committed read no point deeper than
    the expression holds (possible only from a stack deeper than ``depth``).
    """
    joint = conn._joint
    us, Fr = joint.reversal_points()
    us, Fr = us.tolist(), Fr.tolist()
    st = conn._state
    if (
        t is not None
        and (st.held > st.depth or conn._window)
        and st.disagrees(joint.displacement, joint.force)
    ):
        conn._overflows.append(t)
        _log.warning(
            "Iwan connector %s at t=%g: the step closed loops beyond the %d reversal "
            "points the symbolic law holds and could not be re-solved exactly; that "
            "step's force was not exact (raise depth)",
            conn.objectNumber,
            t,
            st.depth,
        )
    st.set_state(us, Fr, joint.displacement)
    conn._window = False


# ---------------------------------------------------------------------------- overflow
def walk_states(us, Fr, uc, Fc, u, tol, limit=None) -> list[tuple[int, list[float], list[float]]]:
    """The committed states the joint passes through on the monotone move ``uc -> u``.

    Mirrors :meth:`IwanJoint._walk` (extended Masing rules, docs/equations.md section 2): a
    reversal at ``uc`` if the move turns back, then one state per loop the move closes.
    Returns a list of ``(p, stack_u, stack_F)``: the slip ``p`` at which a loop closes
    and the reversal stack (oldest first) right after it; at most ``limit`` states.
    """
    n = len(us)
    du = u - uc
    if du == 0.0:
        return []
    up = du > 0.0
    d = uc - us[n - 1] if n else uc
    e = None
    if (d < 0.0) if up else (d > 0.0):
        if abs(d) <= tol:
            if n:
                n -= 1
        else:
            e = uc
    out = []
    while True:
        if e is not None:
            bound = us[n - 1] if n else -e
        elif n:
            bound = us[n - 2] if n >= 2 else -us[n - 1]
        else:
            break
        if (u < bound) if up else (u > bound):
            break
        if e is not None:
            e = None
            if n:
                n -= 1
        else:
            n -= 2 if n >= 2 else 1
        out.append((bound, n))
        if limit is not None and len(out) >= limit:
            break
    return [(p, list(us[:k]), list(Fr[:k])) for p, k in out]


def newton_check(conn, big: float) -> float:
    """Post-Newton check of one connector whose stack is deeper than the law holds.

    Compares the law (variables as they are) with the exact joint at the converged slip.
    Equal: returns 0. Different (the step closed loops beyond the points held): writes to the
    variables the joint's state after passing some of the step's loop closures, so that the
    law is exact from there on for the next ``depth // 2 - 1`` closures, and returns ``big``
    (larger than Exudyn's discontinuous ``iterationTolerance``): Exudyn then re-solves the
    step with it. The state is chosen ``depth // 2 - 2`` closures before the last one passed,
    so a re-solved slip a little before or after it is still exact.
    """
    joint = conn._joint
    st = conn._state
    u = conn._slip()
    F = joint.trial(u)[0]
    joint.revert()
    if abs(st.probe(u) - F) <= 1e-9 * st.Fs:
        return 0.0
    us, Fr = joint.reversal_points()
    states = walk_states(
        us.tolist(), Fr.tolist(), joint.displacement, joint.force, u, joint_tolerance(joint)
    )
    if not states:
        return 0.0  # nothing to re-solve with (cannot happen in depth)
    k = max(0, len(states) - 1 - max(0, st.depth // 2 - 2))
    p, su, sF = states[k]
    st.set_state(su, sF, p)
    conn._window = True
    conn._n_resolved += 1
    _log.debug(
        "Iwan connector %s: a step closes %d loops; re-solved from the state at u=%g",
        conn.objectNumber,
        len(states),
        p,
    )
    return big


def _none():
    return None


def reset_state(conn) -> None:
    """Virgin state of the law's variables (after ``joint.reset()``)."""
    conn._lazy_last = _none
    conn._window = False
    sync_stack(conn)
    conn._state.set_uc(0.0)
    conn._overflows.clear()
    conn._t_acc = -math.inf
    conn._snapshot = copy.deepcopy(conn._joint)
    conn._replay = None
