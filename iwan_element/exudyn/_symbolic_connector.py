"""The symbolic route of :func:`~iwan_element.exudyn.add_iwan_connector` (an ``IwanJoint``).

The force law is the exact Iwan law as an Exudyn symbolic expression
(:mod:`._symbolic_law`): no Python call and no Exudyn API call per force evaluation, so it
is safe with several solver threads. Once per accepted step the connector's post-step work
reads the accepted slip (views of the system coordinates), brings the ``IwanJoint`` to it
(``trial`` + ``commit``: the joint stays the exact reference and holds the energies), writes
the committed slip to the law's variable and, only when the joint's reversal stack changed,
the stack.
"""
from __future__ import annotations

import logging
import math

from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (ObjectConnectorCartesianSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper)

from ._slip_map import SlipMap
from ._symbolic_law import SymbolicIwanState

__all__: list[str] = []

_log = logging.getLogger(__name__)


def symbolic_item(conn, depth: int, name: str, vis):
    """The Exudyn connector item with the symbolic law; sets ``conn._state``."""
    joint = conn._joint
    st = SymbolicIwanState(joint.params, depth, joint_tolerance(joint))
    conn._state = st
    off = conn._offset
    m = [int(x) for x in conn._markers]
    if conn._kind == "coordinate":
        def law(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
            return st.force(deltaL - off if off else deltaL)
        fn = CreateSymbolicUserFunction(conn._mbs, law, "springForceUserFunction",
                                        itemTypeName="ObjectConnectorCoordinateSpringDamper")
        item = ObjectConnectorCoordinateSpringDamper(
            name=name, markerNumbers=m, stiffness=0.0, damping=0.0, offset=off,
            springForceUserFunction=fn, visualization=vis)
    else:
        a = conn._axis

        def law(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            u = None
            for k in range(3):
                if a[k] != 0.0:
                    term = displacement[k] if a[k] == 1.0 else displacement[k] * a[k]
                    u = term if u is None else u + term
            F = st.force(u - off if off else u)
            return [F if a[k] == 1.0 else F * a[k] for k in range(3)]
        fn = CreateSymbolicUserFunction(conn._mbs, law, "springForceUserFunction",
                                        itemTypeName="ObjectConnectorCartesianSpringDamper")
        item = ObjectConnectorCartesianSpringDamper(
            name=name, markerNumbers=m, springForceUserFunction=fn, visualization=vis)
    conn._function = fn          # keep the expression tree alive
    return item


def joint_tolerance(joint) -> float:
    """Absolute reversal tolerance [m] of an ``IwanJoint``."""
    return float(joint._tol)


def symbolic_refresh(conn, mbs) -> None:
    """Start of a run: the slip reader, and the accept function bound to it."""
    smap = SlipMap(mbs, [conn._markers], conn._kind, conn._axis, [conn._offset])
    conn._read = smap              # the dispatcher then checks for a re-assembly per step
    conn._accept = _accept_function(conn, smap)


def sync_stack(conn, t=None) -> None:
    """Write the joint's committed reversal stack to the law's variables (and check that
    the step just committed read no point deeper than the expression holds)."""
    joint = conn._joint
    us, Fr = joint.reversal_points()
    us, Fr = us.tolist(), Fr.tolist()
    st = conn._state
    if t is not None and st.disagrees(joint.displacement, joint.force):
        conn._overflows.append(t)
        _log.warning("Iwan connector %s at t=%g: the step closed loops beyond the %d reversal "
                     "points the symbolic law holds; that step's force was not exact (raise "
                     "depth)", conn.objectNumber, t, st.depth)
    st.set_stack(us, Fr)


def _accept_function(conn, smap):
    joint = conn._joint
    trial = joint.trial
    commit = joint.commit
    set_uc = conn._state.uc.SetValue
    buf = conn._buf
    extend = buf.extend if conn._record_on else None
    flush = conn._flush
    q = smap.q
    idx = smap.idx[0].tolist()
    coef = smap.coef[0].tolist()
    c0 = float(smap.c[0])
    simple = not smap.generic
    item = q.item
    terms = list(zip(idx, coef))

    def accept(t):
        if simple:
            u = c0
            for i, c in terms:
                u += c * item(i)
        else:
            u = float(smap.slips()[0])
        F = trial(u)[0]
        if t < conn._t_acc:
            conn._new_run(t, u)
        depth = joint.reversal_depth
        commit()
        if joint.reversal_depth != depth:     # the stack changed (see sync_stack)
            sync_stack(conn, t)
        set_uc(u)
        conn._t_acc = t
        if extend is not None:
            extend((t, u, F, joint.dissipated_energy, joint.work))
            if len(buf) >= 5 * 1024:
                flush()

    return accept


def reset_state(conn) -> None:
    """Virgin state of the law's variables (after ``joint.reset()``)."""
    conn._state.set_stack([], [])
    conn._state.set_uc(0.0)
    conn._overflows.clear()
    conn._t_acc = -math.inf
