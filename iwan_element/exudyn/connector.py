"""Drop-in Exudyn connector for any joint element of this package (the only module importing exudyn).

:func:`add_iwan_connector` puts a history-dependent joint (an :class:`~iwan_element.IwanJoint`,
a :class:`~iwan_element.DiscreteIwan`, or anything else following
:class:`~iwan_element.JointElement`) between two Exudyn markers:

* two **coordinate markers** (``MarkerNodeCoordinate`` ...): a 1-D joint on the relative
  coordinate, built on ``ObjectConnectorCoordinateSpringDamper``; the slip is
  ``u = q1 - q0 - offset``;
* two **position markers** (``MarkerBodyPosition``, ``MarkerNodePosition``, rigid markers ...):
  the force acts along a unit ``axis``, built on ``ObjectConnectorCartesianSpringDamper``;
  the slip is ``u = a . (p1 - p0) - offset``. The axis is global, or, with ``axisMarker``,
  fixed in the frame of a marker that has an orientation (it then rotates with that body).

How the history is kept
-----------------------
Exudyn evaluates a connector's force many times per step: Newton iterations and
finite-difference Jacobians of the implicit solvers, the stages of explicit Runge-Kutta
methods, and attempts that an adaptive solver rejects. The force law therefore never
changes the joint's history; once per *accepted* step a post-step dispatcher brings every
joint to the accepted state, commits it and appends a row to the connector's record.

Two force laws (``law=``), chosen automatically:

* **symbolic** (an :class:`~iwan_element.IwanJoint` on two ``MarkerNodeCoordinate`` markers
  or on position markers with a global axis): the exact Iwan law as an Exudyn symbolic
  expression (:mod:`._symbolic_law`), evaluated in C++ without Python and without Exudyn
  API calls (safe with several solver threads). Its state (the committed slip and the newest
  ``depth`` reversal points) lives in named symbolic variables. Per accepted step the
  post-step reads the slip through a view of Exudyn's coordinates and writes it to one
  variable; while the slip continues the current branch (one interval test) nothing else
  happens: the ``IwanJoint`` (the reference, holding the energies) is committed lazily, at
  the next reversal or loop closure, at the last step of the run, and when read through
  the connector (:mod:`._symbolic_connector`). Records hold ``(t, u)`` per step; force and
  energies are replayed on a copy of the joint when read. A step that needs an older
  reversal point than the law holds (possible only while the stack is deeper than
  ``depth``) is re-solved exactly: near the end of the law's exact window a post-Newton
  function compares the law with the joint and, if they differ, writes a state on the
  step's path and asks Exudyn for a discontinuous iteration. A step that jumps past that
  window from far away (more than ten times the branch's step increments) is still
  detected (the law at the accepted slip against the exact force), logged, and listed in
  :attr:`IwanConnector.overflow_times`.
* **python** (any element, e.g. the effects, or a rotating ``axisMarker``): a Python force
  function calling ``joint.trial(u, v)``. For two node coordinates the post-step reads the
  accepted slip and its rate through coordinate views and evaluates a new trial only if the
  last one was elsewhere; otherwise it calls ``mbs.GetObjectOutput``, which evaluates the
  force function at the accepted state.

Exudyn calls the post-step function only after accepted steps (and once at the start of a
run, which commits the initial state: an initial slip is reached by monotone virgin
loading); rejected attempts leave no trace. ``SolveStatic`` calls it after every load step,
so a static run commits a quasi-static loading history. A new solve is recognised by the
solver object that ``SolveDynamic``/``SolveStatic`` store in ``mbs.sys`` (the coordinate
views are then renewed and the settings checked, see :func:`._dispatch.check_settings`).

Post-step chaining
------------------
All connectors of one system share a single post-step function (the dispatcher). A
post-step function that was set before :func:`add_iwan_connector` is called after the
connectors have committed, with the same arguments, and its return value (``False``
stops the simulation) is passed on to Exudyn. If a post-step function is set *after* the
connectors were added, each connector notices this at the first force evaluation of the
next run and puts the dispatcher back in front of it, so the user's function keeps
running too. Pre-step functions are not touched.

Exudyn settings to remember
---------------------------
* Newton's ``absoluteTolerance`` is a residual in force units; for stiff joints use a
  tight ``relativeTolerance`` (the default 1e-8 of the step's initial residual is fine
  for plots, use ~1e-10 or below for energy checks).
* Several solver threads are refused (``ValueError`` at the start of the run) for
  connectors with the Python force law: with two threads Exudyn 1.13.6 was observed to hang
  with about 20 or more Python-function connectors. The symbolic law is allowed.
* ODE23/DOPRI5 with automatic step size are refused (see :func:`check_settings`).
* A user-function connector reports no potential energy to Exudyn; use the connector's
  records (:attr:`IwanConnector.stored_energy_history`, ...).
* Python law with position markers: the accepted state is obtained through
  ``mbs.GetObjectOutput``, which allocates; on long runs Exudyn may then print a harmless
  "large amount of memory allocations" warning.
* A post-step function set *after* the connectors is chained at the next ``SolveDynamic``
  / ``SolveStatic``: they store their solver in ``mbs.sys``, which the connectors replace by
  a dict that re-installs the dispatcher in front of it (the Python law also re-chains at
  its first force evaluation). With ``storeSolver=False`` or a hand-made solver object only
  the Python law notices; with the symbolic law reading the records then raises
  ``RuntimeError`` instead of returning an uncommitted history.

Cost: see ``benchmarks/bench_connector.py`` and the README's performance table (the
symbolic law removes the Python force calls; what remains per step is one Python post-step
with a ``trial``/``commit`` of the joint and one variable update).
"""
from __future__ import annotations

import logging
import math
from array import array

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (ObjectConnectorCartesianSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper)

from ..core._validation import check_scalar
from ..core.joint import IwanJoint
from ..core.protocol import check_element
from . import _symbolic_connector as _symbolic
from ._dispatch import _claim, _dispatcher_for, _installed_post_step
from ._markers import (_COORDINATE_MARKERS, _ORIENTATION_MARKERS, _POSITION_MARKERS,
                       _marker_type, _node_coordinate_nodes, _unit_axis, _visualization)
from ._python_law import (_coordinate_force_function, _position_force_function,
                          _rotating_axis_force_function)

__all__ = ["add_iwan_connector", "IwanConnector"]

_log = logging.getLogger(__name__)

_FORCE = exu.OutputVariableType.Force
_NAN = math.nan
_INF = math.inf

_NCOL = 5                   # recorded per step: time, slip, force, dissipated energy, work
_BLOCK = 5 * 1024           # record values buffered in a list before moving them to the array


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

    def __init__(self, mbs, markerNumbers, joint, kind, axis, axisMarker, offset, record):
        self._mbs = mbs
        self._markers = tuple(markerNumbers)
        self._joint = joint
        self._kind = kind
        self._axis = axis
        self._axis_marker = axisMarker
        self._offset = offset
        self._record_on = record
        self._rec = array("d")      # the records, row-major, _NCOL values per row
        self._buf = []              # newest rows, moved to _rec in blocks (list.extend is
                                    # ~4x faster than array.extend with a tuple)
        self._guard = _INF          # force evaluations at t < _guard check the set-up first
        self._t_acc = -_INF         # time of the last accepted step
        self._lu = _NAN             # cache of the last trial: (u, v) -> F
        self._lv = _NAN
        self._lF = 0.0
        self._object = None
        self._dispatcher = None
        self._read = None           # (q, q_t, i0, i1) on the fast route, else None (generic)
        self._fast_nodes = None     # set for two NodeCoordinate markers; resolved in _refresh
        self._accept = self._generic_accept
        self._route = "python"
        self._state = None          # symbolic route: the law's variables
        self._overflows = []
        self._lazy_last = _no_pending   # symbolic route: () -> accepted slip not yet
                                        # committed (lazy), or None
        self._window = False        # the law's variables hold a post-Newton window
        self._risky = False         # the committed stack is deeper than the law holds
        self._snapshot = None       # copy of the joint where the records start
        self._replay = None         # cache of the replayed records
        self._slip = None           # () -> accepted slip (symbolic route)
        self._n_resolved = 0        # post-Newton re-solves of steps beyond the law's depth

    # -------------------------------------------------------------- per-step work
    def _generic_accept(self, t):
        """Post-step (generic route): Exudyn evaluates the force function at the accepted
        state, which leaves (u, F) of that state in the cache; commit and record."""
        self._mbs.GetObjectOutput(self._object, _FORCE)
        u = self._lu
        F = self._lF
        if t < self._t_acc:
            self._new_run(t, u)
        j = self._joint
        j.commit()
        self._lu = _NAN
        self._guard = t
        self._t_acc = t
        if self._record_on:
            buf = self._buf
            buf.extend((t, u, F, j.dissipated_energy, j.work))
            if len(buf) >= _BLOCK:
                self._flush()

    def _fast_accept(self, q, qt, i0, i1):
        """Post-step function for two node coordinates: reads the accepted slip and its rate
        through views ``q``, ``q_t`` of Exudyn's current system coordinates (no copy) and
        evaluates a new trial only if the last one was elsewhere."""
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
            else:                   # e.g. an explicit solver whose last call was a stage
                F = trial(u, v)[0]
            if t < conn._t_acc:
                conn._new_run(t, u)
            commit()
            conn._lu = _NAN
            conn._guard = t
            conn._t_acc = t
            if extend is not None:
                extend((t, u, F, joint.dissipated_energy, joint.work))
                if len(buf) >= _BLOCK:
                    flush()

        return accept

    def _newton_check(self, big: float) -> float:
        return _symbolic.newton_check(self, big)

    def _flush_joint(self) -> None:
        """Symbolic route: commit the joint at the last accepted slip if that was left
        pending (the joint is committed lazily along a branch)."""
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
        dynamic)."""
        held = self._joint.displacement
        if u != held:
            _log.warning(
                "Iwan connector %s: a new run starts at t=%g, before the end (t=%g) of the "
                "history the joint holds, and the slip jumps from %g to %g; call reset() "
                "before starting a fresh run", self.objectNumber, t, self._t_acc, held, u)

    def _refresh(self, mbs, lazy_until=-_INF):
        """Start of a run: resolve the global coordinate indices and take fresh views of the
        system coordinates (Assemble may have moved them); the views stay valid during a
        run (checked at every accepted step for all solvers, see the tests)."""
        if self._route == "symbolic":
            _symbolic.symbolic_refresh(self, mbs, lazy_until)
            return
        if self._fast_nodes is None:
            self._read = None
            self._accept = self._generic_accept
            return
        i0, i1 = [-1 if node is None else mbs.GetNodeODE2Index(node) + coord
                  for node, coord in self._fast_nodes]
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
        cost of one check per step."""
        d = self._dispatcher
        d.refresh(mbs)
        if not d.reachable_from(_installed_post_step(mbs)):
            _log.debug("connector %s: post-step function was replaced; chaining it behind the "
                       "connector dispatcher", self.objectNumber)
            d.install(mbs)
        self._guard = math.nextafter(t, -math.inf)     # no second check at this same time

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
        this property."""
        self._flush_joint()
        return self._joint

    @property
    def kind(self) -> str:
        """``"coordinate"`` (ObjectConnectorCoordinateSpringDamper) or ``"position"``
        (ObjectConnectorCartesianSpringDamper)."""
        return self._kind

    @property
    def axis(self):
        """Unit axis, tuple of 3 floats (global, or in the frame of :attr:`axisMarker`);
        ``None`` for coordinate markers."""
        return self._axis

    @property
    def axisMarker(self):
        """Marker whose orientation carries :attr:`axis`; ``None`` for a global axis."""
        return self._axis_marker

    @property
    def offset(self) -> float:
        """Slip at which the virgin joint is unloaded [m] (or [rad] for rotation
        coordinates)."""
        return self._offset

    # -------------------------------------------------------------- user API
    def reset(self) -> None:
        """Return the joint to its virgin state and clear the records (for a new run).

        Exudyn restarts each ``SolveDynamic`` from the initial conditions; call this before
        such a run unless the run continues from the state the joint holds (e.g. a
        dynamic run started from a static solution).
        """
        self._lazy_last = _no_pending
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

    def _check_running(self) -> None:
        """The symbolic route has no Python force function to notice a replaced post-step
        function; refuse to return records of a run in which the joint was not committed."""
        d = self._dispatcher
        if self._route == "symbolic" and d is not None \
                and not d.reachable_from(_installed_post_step(self._mbs)):
            raise RuntimeError(
                "the connector's post-step dispatcher was replaced by another post-step user "
                "function, so the joint was not committed; set your post-step function before "
                "add_iwan_connector (it is then chained) and run again")

    @property
    def route(self) -> str:
        """``"symbolic"`` (the exact Iwan law as an Exudyn symbolic expression) or
        ``"python"`` (a Python force function calling ``joint.trial``)."""
        return self._route

    @property
    def overflow_times(self) -> np.ndarray:
        """Symbolic route: times [s] of accepted steps that read an older reversal point
        than the law holds and could not be re-solved (a jump from far outside the window
        at which the re-solve is armed; not exact: raise ``depth``). Empty in a sound run."""
        return np.array(self._overflows)

    def _table(self) -> np.ndarray:
        """All records, shape (n, 5): time, slip, force, dissipated energy, work."""
        self._check_running()
        self._flush()
        if self._route == "symbolic":
            return _symbolic.replay_records(self)
        return np.array(self._rec, dtype=float).reshape(-1, _NCOL)

    def _column(self, i: int) -> np.ndarray:
        return self._table()[:, i].copy()

    @property
    def n_records(self) -> int:
        """Number of recorded rows."""
        if self._route == "symbolic":
            return len(self._rec) // 2
        return (len(self._rec) + len(self._buf)) // _NCOL

    @property
    def time(self) -> np.ndarray:
        """Times of the accepted steps [s], shape (n,)."""
        return self._column(0)

    @property
    def slip_history(self) -> np.ndarray:
        """Joint slip ``u`` at the accepted steps [m], shape (n,)."""
        return self._column(1)

    @property
    def force_history(self) -> np.ndarray:
        """Joint force at the accepted steps [N], shape (n,); positive when it pulls
        marker 1 back towards marker 0 (resists positive slip)."""
        return self._column(2)

    @property
    def dissipated_energy_history(self) -> np.ndarray:
        """Energy dissipated by the joint since the last reset [J], shape (n,)."""
        return self._column(3)

    @property
    def work_history(self) -> np.ndarray:
        """Work done on the joint, ``int F du`` since the last reset [J], shape (n,)."""
        return self._column(4)

    @property
    def stored_energy_history(self) -> np.ndarray:
        """Elastic energy stored in the joint [J], shape (n,): ``work - dissipated_energy``
        (the element protocol's identity; only these two are recorded per step)."""
        return self._column(4) - self._column(3)

    def records(self) -> dict:
        """All records as a dict of arrays of shape (n,): ``time [s], slip [m], force [N],
        stored_energy [J], dissipated_energy [J], work [J]``."""
        data = self._table()
        return {"time": data[:, 0].copy(), "slip": data[:, 1].copy(),
                "force": data[:, 2].copy(), "stored_energy": data[:, 4] - data[:, 3],
                "dissipated_energy": data[:, 3].copy(), "work": data[:, 4].copy()}

    def __repr__(self) -> str:
        return (f"IwanConnector(objectNumber={self.objectNumber}, kind={self.kind!r}, "
                f"markerNumbers={self.markerNumbers}, joint={self.joint!r}, "
                f"records={self.n_records})")


def add_iwan_connector(mbs, markerNumbers, joint, *, axis=None, axisMarker=None,
                       offset: float = 0.0, name: str = "", visualization=None,
                       record: bool = True, law: str = "auto", depth: int = 8,
                       allow_adaptive_explicit: bool = False) -> IwanConnector:
    """Add a history-dependent joint element between two markers of an Exudyn system.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system (items added, not necessarily assembled yet).
    markerNumbers : sequence of 2 marker numbers
        ``[m0, m1]``. Both coordinate markers (``MarkerNodeCoordinate``,
        ``MarkerNodeRotationCoordinate`` ...): the slip is ``u = q1 - q0 - offset``. Both
        position markers (``MarkerBodyPosition``, ``MarkerNodePosition``, ``MarkerBodyRigid``,
        ``MarkerNodeRigid`` ...): ``u = a . (p1 - p0) - offset`` with the unit axis ``a``.
        The joint force ``F = joint.trial(u, v)[0]`` acts as ``-F`` (along ``a``) on marker 1
        and ``+F`` on marker 0, i.e. it resists positive slip.
    joint : JointElement
        Any element following the package's element protocol (``trial``, ``commit``,
        ``revert``, ``reset``, energy read-outs, ``displacement`` and ``force``). It is
        used exclusively by this connector; its current state is the initial history.
    axis : array_like, shape (3,) or (2,), keyword-only
        Direction of the joint force for position markers (normalised here; a 2-vector
        gets ``z = 0``). Required for position markers, not allowed for coordinate markers.
    axisMarker : int, optional, keyword-only
        A marker with an orientation (``MarkerBodyRigid``, ``MarkerNodeRigid`` ...; also a
        rigid marker on an ``ObjectANCFCable2D``, whose frame follows the beam slope). If
        given, ``axis`` is expressed in that marker's frame and rotates with it; the force
        then stays along the current axis and the moment of the axis rotation is neglected
        (exact when the two points coincide, as for the interface points of a lap joint).
    offset : float, keyword-only
        Slip at which the joint is unloaded in its virgin state [m] (default 0); fixed at
        creation (the Exudyn object's own ``offset`` parameter is not read).
    name : str, keyword-only
        Name of the Exudyn object.
    visualization : dict, optional, keyword-only
        Keys among ``show``, ``drawSize``, ``color`` (as for Exudyn's spring-dampers).
    record : bool, keyword-only
        Record time, slip, force and energies at every accepted step (default ``True``);
        ``False`` stores nothing.
    law : {"auto", "symbolic", "python"}, keyword-only
        How the force is evaluated. ``"symbolic"``: the exact Iwan law as an Exudyn symbolic
        expression (no Python call per force evaluation; thread-safe); only for an
        :class:`~iwan_element.IwanJoint` on two ``MarkerNodeCoordinate`` markers or on
        position markers with a global axis. ``"python"``: a Python force function calling
        ``joint.trial`` (any element). ``"auto"`` (default) picks ``"symbolic"`` where it
        applies.
    depth : int, keyword-only
        Reversal points the symbolic law holds (default 8, range [2, 64]). A step that
        needs more (``depth // 2`` loop closures inside one step) is re-solved exactly
        (post-Newton discontinuous iteration, armed near the end of the held window); one
        that jumps there from far is logged and listed in
        :attr:`IwanConnector.overflow_times`.
    allow_adaptive_explicit : bool, keyword-only
        Run with ODE23/DOPRI5 and automatic step size, which are refused by default
        (a run starting with them raises ``ValueError``): a reversal inside a step is not
        seen by their error estimate and the result does not converge with the tolerance.

    Returns
    -------
    IwanConnector
        Handle with the Exudyn ``objectNumber``, the records and :meth:`IwanConnector.reset`.

    Raises
    ------
    ValueError
        For an invalid ``mbs``, markers that do not exist or do not fit together, a missing
        or zero ``axis``, an ``axisMarker`` without orientation, an element not following
        the protocol, or a joint already used by another connector of this system.

    Notes
    -----
    The force function only evaluates trials; the joint is committed once per accepted
    step by a post-step dispatcher (see the module docstring), which also chains a
    post-step user function set earlier. Run with ``parallel.numberOfThreads = 1``.

    Examples
    --------
    >>> conn = add_iwan_connector(mbs, [mGround, mMass], IwanJoint(params))   # doctest: +SKIP
    >>> mbs.Assemble(); mbs.SolveDynamic(simulationSettings)                  # doctest: +SKIP
    >>> conn.dissipated_energy_history[-1]                                    # doctest: +SKIP
    """
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    if isinstance(markerNumbers, (str, bytes)) or not hasattr(markerNumbers, "__len__") \
            or len(markerNumbers) != 2:
        raise ValueError(f"markerNumbers must be a list of two marker numbers, got {markerNumbers!r}")
    check_element(joint, name="joint")
    missing = [a for a in ("displacement", "force") if not hasattr(joint, a)]
    if missing:
        raise ValueError(f"joint must expose the committed {missing} (element protocol); "
                         f"{type(joint).__name__} does not")
    offset = check_scalar("offset", offset)
    if not isinstance(name, str):
        raise ValueError(f"name must be a str, got {type(name).__name__}")
    if not isinstance(record, bool):
        raise ValueError(f"record must be True or False, got {record!r}")
    if not isinstance(allow_adaptive_explicit, bool):
        raise ValueError(f"allow_adaptive_explicit must be True or False, got "
                         f"{allow_adaptive_explicit!r}")
    if law not in ("auto", "symbolic", "python"):
        raise ValueError(f"law must be 'auto', 'symbolic' or 'python', got {law!r}")
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not 2 <= depth <= 64:
        raise ValueError(f"depth must be an int in [2, 64], got {depth!r}")
    vis = _visualization(visualization)

    t0 = _marker_type(mbs, markerNumbers[0], "markerNumbers[0]")
    t1 = _marker_type(mbs, markerNumbers[1], "markerNumbers[1]")
    if int(markerNumbers[0]) == int(markerNumbers[1]):
        raise ValueError(f"markerNumbers must be two different markers, got {list(markerNumbers)}")
    if t0 in _COORDINATE_MARKERS and t1 in _COORDINATE_MARKERS:
        kind = "coordinate"
        if axis is not None or axisMarker is not None:
            raise ValueError("axis and axisMarker apply to position markers only; markerNumbers "
                             f"are coordinate markers ({t0}, {t1})")
    elif t0 in _POSITION_MARKERS and t1 in _POSITION_MARKERS:
        kind = "position"
        if axis is None:
            raise ValueError(f"axis is required for position markers ({t0}, {t1}): give the "
                             "direction of the joint force, e.g. axis=[1, 0, 0]")
    else:
        raise ValueError(
            f"markerNumbers must be two coordinate markers ({sorted(_COORDINATE_MARKERS)}) or two "
            f"position markers ({sorted(_POSITION_MARKERS)}); got {t0} and {t1}")

    unit = None
    axis_marker = None
    if kind == "position":
        unit = _unit_axis(axis, "axis")
        if axisMarker is not None:
            ta = _marker_type(mbs, axisMarker, "axisMarker")
            if ta not in _ORIENTATION_MARKERS:
                raise ValueError(f"axisMarker must be a marker with an orientation "
                                 f"({sorted(_ORIENTATION_MARKERS)}), got {ta}")
            axis_marker = int(axisMarker)

    dispatcher = _dispatcher_for(mbs)
    conn = IwanConnector(mbs, markerNumbers, joint, kind, unit, axis_marker, offset, record)
    _claim(joint, conn)
    conn._dispatcher = dispatcher
    conn._allow_adaptive_explicit = allow_adaptive_explicit
    if kind == "coordinate":
        conn._fast_nodes = _node_coordinate_nodes(mbs, markerNumbers)
    route = _choose_route(law, joint, kind, conn._fast_nodes, axis_marker)
    if route == "symbolic":
        conn._route = "symbolic"
        conn._lazy = True
        item = _symbolic.symbolic_item(conn, int(depth), name, vis)
        conn._dispatcher = dispatcher
        _symbolic.sync_stack(conn)
        conn._state.set_uc(joint.displacement)
    elif kind == "coordinate":
        uf = _coordinate_force_function(conn)
        item = ObjectConnectorCoordinateSpringDamper(
            name=name, markerNumbers=list(markerNumbers), stiffness=0.0, damping=0.0,
            offset=offset, springForceUserFunction=uf, visualization=vis)
    else:
        if axis_marker is None:
            uf = _position_force_function(conn)
        else:
            uf = _rotating_axis_force_function(conn)
        item = ObjectConnectorCartesianSpringDamper(
            name=name, markerNumbers=list(markerNumbers), springForceUserFunction=uf,
            visualization=vis)
    conn._object = mbs.AddObject(item)
    dispatcher.add(conn)
    _log.debug("added %r", conn)
    return conn


def _choose_route(law, joint, kind, fast_nodes, axis_marker) -> str:
    why = None
    if type(joint) is not IwanJoint:
        why = f"the joint is a {type(joint).__name__} (the symbolic law is the IwanJoint's)"
    elif kind == "coordinate" and fast_nodes is None:
        why = "the coordinate markers are not both MarkerNodeCoordinate"
    elif axis_marker is not None:
        why = "the axis rotates with axisMarker"
    if law == "symbolic" and why is not None:
        raise ValueError(f"law='symbolic' is not available here: {why}; use law='python'")
    if law == "python" or why is not None:
        return "python"
    return "symbolic"
