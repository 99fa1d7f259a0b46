"""The handle of a connector placed by :func:`~iwan_element.exudyn.add_iwan_connector`:
records, read-outs, reset, and the per-step work of the Python force law (the symbolic
law's is in :mod:`.laws.symbolic_connector`). See :mod:`iwan_element.exudyn.connector` for how
the history is kept.
"""

from __future__ import annotations

import logging
import math
from array import array

import exudyn as exu
import numpy as np

from ._dispatch import _installed_post_step
from .laws import symbolic_connector as _symbolic
from .laws.symbolic_records import replay_records, stride

__all__: list[str] = []

_log = logging.getLogger("iwan_element.exudyn.connector")
_FORCE = exu.OutputVariableType.Force
_NAN = math.nan
_INF = math.inf

_NCOL = 5  # recorded per step: time, slip, force, dissipated energy, work
_BLOCK = 5 * 1024  # record values buffered in a list before moving them to the array


def _no_pending():
    return None


# ---------------------------------------------------------------------------- public API
class IwanConnector:
    """Handle of a joint element placed in an Exudyn system (made by :func:`add_iwan_connector`).

    The records hold one row per accepted step (plus one for the initial state of each
    run), appended after the joint was committed.

    All attributes are read-only; the geometry (markers, axis, offset) is fixed when the
    connector is created.
    """

    def __init__(
        self, mbs, markerNumbers, joint, kind, axis, axisMarker, offset, record, damping=0.0
    ):
        self._mbs = mbs
        self._markers = tuple(markerNumbers)
        self._joint = joint
        self._kind = kind
        self._axis = axis
        self._axis_marker = axisMarker
        self._offset = offset
        self._damping = damping  # dashpot in parallel with the joint [N s/m]
        self._dash = None  # its (u, v, dissipated) at the last accepted step
        self._record_on = record
        self._rec = array("d")  # the records, row-major, _NCOL values per row
        self._buf = []  # newest rows, moved to _rec in blocks (list.extend is
        # ~4x faster than array.extend with a tuple)
        self._guard = _INF  # force evaluations at t < _guard check the set-up first
        self._t_acc = -_INF  # time of the last accepted step
        self._lu = _NAN  # cache of the last trial: (u, v) -> F
        self._lv = _NAN
        self._lF = 0.0
        self._object = None
        self._dispatcher = None
        self._allow_adaptive_explicit = False  # set by add_iwan_connector
        self._read = None  # (q, q_t, i0, i1) on the fast route, else None (generic)
        self._fast_nodes = None  # set for two NodeCoordinate markers; resolved in _refresh
        self._accept = self._generic_accept
        self._route = "python"
        self._state = None  # symbolic route: the law's variables
        self._overflows = []
        self._lazy_last = _no_pending  # symbolic route: () -> accepted slip not yet
        # committed (lazy), or None
        self._window = False  # the law's variables hold a post-Newton window
        self._risky = False  # the committed stack is deeper than the law holds
        self._snapshot = None  # copy of the joint where the records start
        self._replay = None  # cache of the replayed records
        self._slip = None  # () -> accepted slip (symbolic route)
        self._n_resolved = 0  # post-Newton re-solves of steps beyond the law's depth

    # -------------------------------------------------------------- per-step work
    def _generic_accept(self, t):
        """Post-step (generic route): Exudyn evaluates the force function at the accepted
        state, which leaves (u, F) of that state in the cache; commit and record.
        """
        self._mbs.GetObjectOutput(self._object, _FORCE)
        u = self._lu
        v = self._lv
        F = self._lF
        if t < self._t_acc:
            self._new_run(t, u)
        j = self._joint
        j.commit()
        self._lu = _NAN
        self._guard = t
        self._t_acc = t
        if self._record_on:
            d = self._dash_step(u, v) if self._damping else 0.0
            buf = self._buf
            buf.extend((t, u, F + self._damping * v, j.dissipated_energy + d, j.work + d))
            if len(buf) >= _BLOCK:
                self._flush()

    def _dash_step(self, u, v) -> float:
        """The dashpot's dissipation [J] up to the accepted state ``(u, v)``: the previous
        one plus ``c (v0 + v) / 2 (u - u0)``, the trapezoidal ``int c v du`` (as
        :class:`~iwan_element.effects.ViscousDamping`), exact when the velocity is linear in
        time over the step, as in the average-acceleration (Newmark) scheme.
        """
        prev = self._dash
        d = 0.0 if prev is None else prev[2] + self._damping * 0.5 * (prev[1] + v) * (u - prev[0])
        self._dash = (u, v, d)
        return d

    def _fast_accept(self, q, qt, i0, i1):
        """Post-step function for two node coordinates: reads the accepted slip and its rate
        through views ``q``, ``q_t`` of Exudyn's current system coordinates (no copy) and
        evaluates a new trial only if the last one was elsewhere.
        """
        conn = self
        joint = self._joint
        trial = joint.trial
        commit = joint.commit
        off = self._offset
        buf = self._buf
        extend = buf.extend if self._record_on else None
        flush = self._flush
        item = q.item
        item_t = qt.item
        c = self._damping
        dash = self._dash_step

        def accept(t):
            # the same operations as the force function's u = deltaL - offset with
            # deltaL = q[i1] - q[i0] (0.0 for ground), so a trial at the accepted state is
            # recognised by exact equality
            u = ((item(i1) if i1 >= 0 else 0.0) - (item(i0) if i0 >= 0 else 0.0)) - off
            v = (item_t(i1) if i1 >= 0 else 0.0) - (item_t(i0) if i0 >= 0 else 0.0)
            if u == conn._lu and v == conn._lv:
                # the last trial was at the accepted state, bit for bit (the implicit solvers
                # and explicit ones with end-of-step accelerations end every step there)
                F = conn._lF
            else:  # e.g. an explicit solver whose last call was a stage
                F = trial(u, v)[0]
            if t < conn._t_acc:
                conn._new_run(t, u)
            commit()
            conn._lu = _NAN
            conn._guard = t
            conn._t_acc = t
            if extend is not None:
                d = dash(u, v) if c else 0.0
                extend((t, u, F + c * v, joint.dissipated_energy + d, joint.work + d))
                if len(buf) >= _BLOCK:
                    flush()

        return accept

    def _newton_check(self, big: float) -> float:
        return _symbolic.newton_check(self, big)

    def _flush_joint(self) -> None:
        """Symbolic route: commit the joint at the last accepted slip if that was left
        pending (the joint is committed lazily along a branch).
        """
        if self._route == "symbolic":
            _symbolic.flush_joint(self)

    def _flush(self) -> None:
        """Move the buffered record rows to the array."""
        self._flush_joint()
        buf = self._buf
        if buf:
            self._rec.fromlist(buf)
            buf.clear()

    def _new_run(self, t, u):
        """A run restarts before the last accepted time: warn if it starts from another slip
        than the joint holds (a forgotten reset, not a continuation such as static ->
        dynamic).
        """
        held = self._joint.displacement
        if u != held:
            _log.warning(
                "Iwan connector %s: a new run starts at t=%g, before the end (t=%g) of the "
                "history the joint holds, and the slip jumps from %g to %g; call reset() "
                "before starting a fresh run",
                self.objectNumber,
                t,
                self._t_acc,
                held,
                u,
            )

    def _refresh(self, mbs, lazy_until=-_INF):
        """Start of a run: resolve the global coordinate indices and take fresh views of the
        system coordinates (Assemble may have moved them); the views stay valid during a
        run (checked at every accepted step for all solvers, see the tests).
        """
        if self._route == "symbolic":
            _symbolic.symbolic_refresh(self, mbs, lazy_until)
            return
        if self._fast_nodes is None:
            self._read = None
            self._accept = self._generic_accept
            return
        i0, i1 = [
            -1 if node is None else mbs.GetNodeODE2Index(node) + coord
            for node, coord in self._fast_nodes
        ]
        sd = mbs.systemData
        q = sd.GetODE2Coordinates(copy=False)
        qt = sd.GetODE2Coordinates_t(copy=False)
        self._read = (q, qt, i0, i1)
        self._accept = self._fast_accept(q, qt, i0, i1)

    def _check(self, mbs, t, u):
        """First force evaluation of a run: take fresh coordinate views and make sure the
        dispatcher runs (a post-step function set later would have replaced it).

        A run is recognised by a force evaluation at or before the last accepted time: a new
        run from an earlier time, or a continued run, whose first evaluation (generalized-alpha's
        initial accelerations, an explicit method's first stage) is at that time. Within a run
        only explicit methods evaluate there again (their first stage of every step), at the
        cost of one check per step.
        """
        d = self._dispatcher
        d.refresh(mbs)
        if not d.reachable_from(_installed_post_step(mbs)):
            _log.debug(
                "connector %s: post-step function was replaced; chaining it behind the "
                "connector dispatcher",
                self.objectNumber,
            )
            d.install(mbs)
        self._guard = math.nextafter(t, -math.inf)  # no second check at this same time

    # -------------------------------------------------------------- read-only set-up
    @property
    def objectNumber(self):
        """The underlying Exudyn connector object (``ObjectIndex``)."""
        return self._object

    @property
    def markerNumbers(self) -> tuple:
        """The two markers ``(m0, m1)``, as given."""
        return self._markers

    @property
    def joint(self):
        """The joint element; its committed state is the state at the last accepted step.

        Symbolic route: during a run the element is committed lazily (at every reversal or
        loop closure, at the last step of a run and when read through the connector); a
        Python function that reads the element itself during a run should read it through
        this property.
        """
        self._flush_joint()
        return self._joint

    @property
    def kind(self) -> str:
        """``"coordinate"`` (ObjectConnectorCoordinateSpringDamper) or ``"position"``
        (ObjectConnectorCartesianSpringDamper).
        """
        return self._kind

    @property
    def axis(self):
        """Unit axis, tuple of 3 floats (global, or in the frame of :attr:`axisMarker`);
        ``None`` for coordinate markers.
        """
        return self._axis

    @property
    def axisMarker(self):
        """Marker whose orientation carries :attr:`axis`; ``None`` for a global axis."""
        return self._axis_marker

    @property
    def damping(self) -> float:
        """Coefficient of the dashpot in parallel with the joint [N s/m] (0: none). Its
        force is in :attr:`force_history`, its dissipation in
        :attr:`dissipated_energy_history` and :attr:`work_history`.
        """
        return self._damping

    @property
    def offset(self) -> float:
        """Slip at which the virgin joint is unloaded [m] (or [rad] for rotation
        coordinates).
        """
        return self._offset

    # -------------------------------------------------------------- user API
    def reset(self) -> None:
        """Return the joint to its virgin state and clear the records; energy recorders
        holding the connector start again.

        A solve that starts before the last accepted time (``SolveDynamic`` from the
        initial conditions again) does this by itself before its first step; a solve that
        starts at the last accepted time continues the history.
        """
        self._lazy_last = _no_pending
        self._dash = None
        self._joint.reset()
        if self._route == "symbolic":
            _symbolic.reset_state(self)
        del self._rec[:]
        self._buf.clear()
        self._lu = _NAN
        self._lv = _NAN
        self._guard = _INF
        self._t_acc = -_INF
        if self._dispatcher is not None:
            self._dispatcher.last_t = _NAN
            self._dispatcher.joint_reset(self)

    def _check_running(self) -> None:
        """The symbolic route has no Python force function to notice a replaced post-step
        function; refuse to return records of a run in which the joint was not committed.
        """
        d = self._dispatcher
        if (
            self._route == "symbolic"
            and d is not None
            and not d.reachable_from(_installed_post_step(self._mbs))
        ):
            raise RuntimeError(
                "the connector's post-step dispatcher was replaced by another post-step user "
                "function, so the joint was not committed; set your post-step function before "
                "add_iwan_connector (it is then chained) and run again"
            )

    @property
    def route(self) -> str:
        """``"symbolic"`` (the exact Iwan law as an Exudyn symbolic expression) or
        ``"python"`` (a Python force function calling ``joint.trial``).
        """
        return self._route

    @property
    def overflow_times(self) -> np.ndarray:
        """Symbolic route: times [s] of accepted steps that read an older reversal point
        than the law holds and could not be re-solved (a jump from far outside the window
        at which the re-solve is armed; not exact: raise ``depth``). Empty in a sound run.
        """
        return np.array(self._overflows)

    def _table(self) -> np.ndarray:
        """All records, shape (n, 5): time, slip, force, dissipated energy, work."""
        self._check_running()
        self._flush()
        if self._route == "symbolic":
            return replay_records(self)
        return np.array(self._rec, dtype=float).reshape(-1, _NCOL)

    def _column(self, i: int) -> np.ndarray:
        return self._table()[:, i].copy()

    @property
    def n_records(self) -> int:
        """Number of recorded rows."""
        if self._route == "symbolic":
            return (len(self._rec) + len(self._buf)) // stride(self)
        return (len(self._rec) + len(self._buf)) // _NCOL

    @property
    def time_history(self) -> np.ndarray:
        """Times of the accepted steps [s], shape (n,)."""
        return self._column(0)

    @property
    def slip_history(self) -> np.ndarray:
        """Joint slip ``u`` at the accepted steps [m], shape (n,)."""
        return self._column(1)

    @property
    def force_history(self) -> np.ndarray:
        """Joint force at the accepted steps [N], shape (n,), the dashpot's included;
        positive when it pulls marker 1 back towards marker 0 (resists positive slip).
        """
        return self._column(2)

    @property
    def dissipated_energy_history(self) -> np.ndarray:
        """Energy dissipated by the joint (and its dashpot) since the last reset [J],
        shape (n,).
        """
        return self._column(3)

    @property
    def work_history(self) -> np.ndarray:
        """Work done on the joint, ``int F du`` since the last reset [J], shape (n,)."""
        return self._column(4)

    @property
    def stored_energy_history(self) -> np.ndarray:
        """Elastic energy stored in the joint [J], shape (n,): ``work - dissipated_energy``
        (the element protocol's identity; only these two are recorded per step).
        """
        return self._column(4) - self._column(3)

    def records(self) -> dict:
        """All records as a dict of arrays of shape (n,): ``time [s], slip [m], force [N],
        stored_energy [J], dissipated_energy [J], work [J]``.
        """
        data = self._table()
        return {
            "time": data[:, 0].copy(),
            "slip": data[:, 1].copy(),
            "force": data[:, 2].copy(),
            "stored_energy": data[:, 4] - data[:, 3],
            "dissipated_energy": data[:, 3].copy(),
            "work": data[:, 4].copy(),
        }

    def __repr__(self) -> str:
        return (
            f"IwanConnector(objectNumber={self.objectNumber}, kind={self.kind!r}, "
            f"markerNumbers={self.markerNumbers}, joint={self.joint!r}, "
            f"records={self.n_records})"
        )
