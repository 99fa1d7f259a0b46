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
methods, and attempts that an adaptive solver rejects. The force user function therefore
only calls ``joint.trial(u, v)`` (which never changes the joint's history). Once per
*accepted* step a post-step dispatcher brings every joint to the accepted state, calls
``joint.commit()`` and appends a row to the connector's record. For two node coordinates
it reads the accepted slip and its rate through views of Exudyn's coordinate vectors (no
copy; renewed at the start of every run and when an ``Assemble`` changed the number of
coordinates) and evaluates a new trial only if the last one was elsewhere; otherwise it
calls ``mbs.GetObjectOutput``, which evaluates the force function at the accepted state. Exudyn calls the post-step
function only after accepted steps (and once at the start of a run, which commits the
initial state: an initial slip is reached by monotone virgin loading); rejected attempts
leave no trace. ``SolveStatic`` calls it after every load step, so a static run commits
a quasi-static loading history.

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
* For position markers the accepted state is obtained through ``mbs.GetObjectOutput``,
  which allocates; on long runs Exudyn may then print a harmless "large amount of memory
  allocations" warning.

Cost (``benchmarks/bench_connector.py``, one mass, generalized-alpha with default settings,
100k steps; ratios to Exudyn's built-in linear connector, measured side by side): with an
:class:`~iwan_element.IwanJoint` about 3.3 us per step, 12 times; the connector machinery
with a zero-cost element 7 times. A stateless Python *nonlinear* law with an empty post-step
function already costs 4.5 times: Exudyn's modified Newton keeps the Jacobian from the
start of the run, so any nonlinear law takes two iterations, i.e. three Python force calls
per step (a linear one two). On top of that floor come three ``trial`` calls (about
0.22 us each on a branch, more in the solver loop), one ``commit`` (about 0.35 us), the
post-step dispatcher reading the accepted state through coordinate views, and the records.
"""
from __future__ import annotations

import logging
import math
import weakref
from array import array
from collections.abc import Mapping

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (ObjectConnectorCartesianSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper)

from ..core._validation import check_scalar
from ..core.joint import IwanJoint
from ..core.protocol import check_element
from . import _symbolic_connector as _symbolic

__all__ = ["add_iwan_connector", "IwanConnector"]

_log = logging.getLogger(__name__)

_FORCE = exu.OutputVariableType.Force
_ROTATION_MATRIX = exu.OutputVariableType.RotationMatrix
_NAN = math.nan
_INF = math.inf

# Marker types (the ``markerType`` entry of ``mbs.GetMarker``) by what they provide.
_COORDINATE_MARKERS = frozenset({
    "NodeCoordinate", "NodeRotationCoordinate",
    "BodiesRelativeTranslationCoordinate", "BodiesRelativeRotationCoordinate",
})
_ORIENTATION_MARKERS = frozenset({"BodyRigid", "NodeRigid", "SuperElementRigid", "KinematicTreeRigid"})
_POSITION_MARKERS = frozenset({"BodyPosition", "NodePosition", "SuperElementPosition"}) | _ORIENTATION_MARKERS
_VISUALIZATION_KEYS = ("show", "drawSize", "color")
_NCOL = 5                   # recorded per step: time, slip, force, dissipated energy, work
_BLOCK = 5 * 1024           # record values buffered in a list before moving them to the array


# ---------------------------------------------------------------------------- dispatcher
def _installed_post_step(mbs):
    """The Python object currently set as post-step user function, or ``None``.

    Exudyn 1.13.6 returns ``0`` when none is set and a dict ``{'function': f, 'type': ...}``
    otherwise (older versions returned ``f`` itself); both forms are accepted.
    """
    got = mbs.GetPostStepUserFunction()
    if isinstance(got, dict):
        got = got.get("function", 0)
    if got is None or (isinstance(got, int) and got == 0):
        return None
    return got


class _PostStepDispatcher:
    """Commits every connector of one system once per accepted step, then calls the
    previously installed post-step function (``chained``)."""

    def __init__(self, chained, mbs):
        self.chained = chained
        self.connectors = []       # in creation order
        self.last_t = _NAN
        self.running = False
        self.solvers = (None, None)    # the solver objects of the run the views belong to
        conns = self.connectors
        disp = self
        sysd = mbs.sys             # Exudyn's SolveDynamic/SolveStatic store their solver here

        def post_step_dispatcher(mbs, t):
            if disp.running:       # re-entered through a user function that calls us by hand
                return True
            disp.running = True
            try:
                solvers = (sysd.get("dynamicSolver"), sysd.get("staticSolver"))
                if solvers[0] is not disp.solvers[0] or solvers[1] is not disp.solvers[1]:
                    disp.solvers = solvers     # a new solve (maybe after an Assemble)
                    disp.new_solve(mbs)
                if t > disp.last_t:            # the usual case: the next accepted step
                    disp.last_t = t
                    for c in conns:
                        c._accept(t)
                elif t != disp.last_t:         # a new run (never commit twice at one time)
                    disp.last_t = t
                    disp.refresh(mbs)
                    for c in conns:
                        c._accept(t)
                else:                          # a run continuing from the last accepted time
                    disp.refresh(mbs)
                f = disp.chained
                return True if f is None else f(mbs, t)
            finally:
                disp.running = False

        post_step_dispatcher._iwan_dispatcher = self
        self.callback = post_step_dispatcher

    def add(self, connector: "IwanConnector") -> None:
        self.connectors.append(connector)

    def refresh(self, mbs) -> None:
        """Let every connector take fresh views of the system coordinates.

        Exudyn keeps its coordinate vectors in place during a run and across runs; only an
        ``Assemble`` that makes them longer moves them (exudyn 1.13.6). So the views are
        renewed at the start of every run: a new solver object in ``mbs.sys`` (each
        ``SolveDynamic``/``SolveStatic`` stores one), or an accepted time not after the last.
        """
        for c in self.connectors:
            c._refresh(mbs)

    def new_solve(self, mbs) -> None:
        """Start of a solve: refuse settings the connectors cannot serve, then refresh."""
        settings = mbs.sys.get("simulationSettings")
        if settings is not None:
            check_settings(settings, self.connectors)
        self.refresh(mbs)

    @staticmethod
    def of(obj):
        """The dispatcher whose callback ``obj`` is, else ``None``."""
        return getattr(obj, "_iwan_dispatcher", None)

    def reachable_from(self, fn) -> bool:
        """True if this dispatcher runs when ``fn`` is the installed post-step function."""
        seen = 0
        while fn is not None and seen < 1000:
            d = _PostStepDispatcher.of(fn)
            if d is None:
                return False
            if d is self:
                return True
            fn = d.chained
            seen += 1
        return False

    def install(self, mbs) -> None:
        """Put this dispatcher in front of whatever post-step function is installed now."""
        current = _installed_post_step(mbs)
        if current is self.callback:
            return
        self.chained = current
        mbs.SetPostStepUserFunction(self.callback)


def check_settings(settings, connectors) -> None:
    """Refuse, before the first step, solver settings the joints cannot serve exactly.

    * more than one solver thread with a Python force law: with two threads Exudyn 1.13.6
      was seen to hang with about 20 or more Python-function connectors (the symbolic law
      runs without Python and is allowed);
    * an explicit solver with automatic step size (ODE23, DOPRI5): the joint's history is
      committed once per accepted step, so a reversal inside a step is not seen by the
      solver's error estimate; measured on the 1-DOF free-decay model (tests), DOPRI5 at
      tolerances 1e-6, 1e-8 and 1e-10 missed the converged implicit result by 7e-3, 1e-4 and
      8e-3 of the amplitude. Fixed-step explicit methods converge as the step falls and are
      allowed; pass ``allow_adaptive_explicit=True`` to the connector to run anyway.
    """
    python = [c for c in connectors if getattr(c, "_route", "python") == "python"]
    threads = settings.parallel.numberOfThreads
    if python and threads > 1:
        raise ValueError(
            f"simulationSettings.parallel.numberOfThreads = {threads}: {len(python)} Iwan "
            "connector(s) use a Python force law, which is not safe with several solver "
            "threads (Exudyn was seen to hang); set numberOfThreads = 1, or use IwanJoint "
            "elements (symbolic law, law='auto') or add_iwan_interface")
    ti = settings.timeIntegration
    if ti.solverType in ADAPTIVE_EXPLICIT and ti.automaticStepSize:
        strict = [c for c in connectors if not getattr(c, "_allow_adaptive_explicit", False)]
        if strict:
            raise ValueError(
                f"solverType {ti.solverType} with automaticStepSize = True is refused for Iwan "
                "joints: a reversal inside a step is invisible to its error estimate, and the "
                "result does not converge with the tolerance (errors of 1e-4 to 1e-2 of the "
                "amplitude were measured); use GeneralizedAlpha, or a fixed step "
                "(automaticStepSize = False), or pass allow_adaptive_explicit=True")


ADAPTIVE_EXPLICIT = frozenset({exu.DynamicSolverType.ODE23, exu.DynamicSolverType.DOPRI5})


def _dispatcher_for(mbs) -> _PostStepDispatcher:
    current = _installed_post_step(mbs)
    d = _PostStepDispatcher.of(current)
    if d is not None:
        return d
    d = _PostStepDispatcher(current, mbs)
    mbs.SetPostStepUserFunction(d.callback)
    return d


# ---------------------------------------------------------------------------- ownership
_ATTACHED: dict = {}        # id(element) -> (weakref to its connector, the element)


def _claim(joint, handle) -> None:
    """Refuse an element that a live connector (of any system) already uses: its history
    would be shared by two force laws."""
    key = id(joint)
    got = _ATTACHED.get(key)
    if got is not None and got[1] is joint:
        owner = got[0]()
        if owner is not None:
            raise ValueError(
                f"joint is already attached to {owner!r} (possibly in another system); its "
                "history would be shared: give every connector its own element instance")
    _ATTACHED[key] = (weakref.ref(handle), joint)
    for k in [k for k, (ref, _) in _ATTACHED.items() if ref() is None]:
        del _ATTACHED[k]


# ---------------------------------------------------------------------------- validation
def _marker_type(mbs, marker, label: str) -> str:
    if isinstance(marker, bool):
        raise ValueError(f"{label} must be a marker number, got {marker!r}")
    try:
        idx = int(marker)
    except (TypeError, ValueError):
        raise ValueError(f"{label} must be a marker number (int or exudyn MarkerIndex), "
                         f"got {marker!r}") from None
    n = mbs.systemData.NumberOfMarkers()
    if not 0 <= idx < n:
        raise ValueError(f"{label} = {idx} is not a marker of this system: allowed range is "
                         f"[0, {n - 1}]" if n else f"{label} = {idx}: the system has no markers yet")
    return mbs.GetMarker(idx)["markerType"]


def _unit_axis(axis, name: str) -> tuple[float, float, float]:
    try:
        a = np.array(axis, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a vector of 2 or 3 numbers, got {axis!r}") from None
    if a.size == 2:
        a = np.append(a, 0.0)
    if a.size != 3 or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite vector of 2 or 3 numbers, got {axis!r}")
    norm = float(np.linalg.norm(a))
    if norm == 0.0:
        raise ValueError(f"{name} must be a non-zero vector, got {axis!r}")
    a = a / norm
    return float(a[0]), float(a[1]), float(a[2])


def _visualization(visualization) -> dict:
    vis = {"show": True, "drawSize": -1.0, "color": [-1.0, -1.0, -1.0, -1.0]}
    if visualization is None:
        return vis
    if not isinstance(visualization, Mapping):
        raise ValueError("visualization must be a dict with keys among "
                         f"{list(_VISUALIZATION_KEYS)}, got {type(visualization).__name__}")
    bad = set(visualization) - set(_VISUALIZATION_KEYS)
    if bad:
        raise ValueError(f"unknown visualization keys {sorted(bad)}; allowed are "
                         f"{list(_VISUALIZATION_KEYS)}")
    vis.update(visualization)
    return vis


def _node_coordinate_nodes(mbs, markerNumbers):
    """For two ``NodeCoordinate`` markers: ``[(node, coordinate), ...]`` with ``node = None``
    for a ground node (its coordinate is always 0); ``None`` for other marker types."""
    out = []
    for m in markerNumbers:
        mk = mbs.GetMarker(int(m))
        if mk["markerType"] != "NodeCoordinate":
            return None
        node = int(mk["nodeNumber"])
        ground = mbs.GetNode(node)["nodeType"] == "PointGround"
        out.append((None if ground else node, int(mk["coordinate"])))
    return out


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

    def _flush(self) -> None:
        """Move the buffered record rows to the array."""
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

    def _refresh(self, mbs):
        """Start of a run: resolve the global coordinate indices and take fresh views of the
        system coordinates (Assemble may have moved them); the views stay valid during a
        run (checked at every accepted step for all solvers, see the tests)."""
        if self._route == "symbolic":
            _symbolic.symbolic_refresh(self, mbs)
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
        """The joint element; its committed state is the state at the last accepted step."""
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
        than the law holds (not exact; raise ``depth``). Empty in a sound run."""
        return np.array(self._overflows)

    def _column(self, i: int) -> np.ndarray:
        self._check_running()
        self._flush()
        return np.array(self._rec[i::_NCOL], dtype=float)

    @property
    def n_records(self) -> int:
        """Number of recorded rows."""
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
        self._check_running()
        self._flush()
        data = np.array(self._rec, dtype=float).reshape(-1, _NCOL)
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
        Reversal points the symbolic law holds (default 8, range [2, 64]); a step that
        needs more (``depth // 2`` loop closures inside one step) is logged and listed in
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
    >>> conn.dissipated_energy[-1]                                            # doctest: +SKIP
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
        item = _symbolic.symbolic_item(conn, int(depth), name, vis)
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


# ---------------------------------------------------------------------------- force functions
# These closures are the hot path: they run at every force evaluation of the solver. They
# read the connector's small state by attribute access and call the bound trial method;
# no numpy and no allocation beyond the return value.
def _coordinate_force_function(conn: IwanConnector):
    trial = conn._joint.trial
    off = conn._offset               # fixed at creation (the object's own offset is not read)

    def iwan_coordinate_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        u = deltaL - off
        if t <= conn._guard:
            conn._check(mbs, t, u)
        if u == conn._lu and deltaL_t == conn._lv:
            return conn._lF
        F = trial(u, deltaL_t)[0]
        conn._lu = u
        conn._lv = deltaL_t
        conn._lF = F
        return F

    return iwan_coordinate_force


def _position_force_function(conn: IwanConnector):
    trial = conn._joint.trial
    a0, a1, a2 = conn._axis
    off = conn._offset

    def iwan_position_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        u = displacement[0] * a0 + displacement[1] * a1 + displacement[2] * a2 - off
        if t <= conn._guard:
            conn._check(mbs, t, u)
        v = velocity[0] * a0 + velocity[1] * a1 + velocity[2] * a2
        if u == conn._lu and v == conn._lv:
            F = conn._lF
        else:
            F = trial(u, v)[0]
            conn._lu = u
            conn._lv = v
            conn._lF = F
        return [F * a0, F * a1, F * a2]

    return iwan_position_force


def _rotating_axis_force_function(conn: IwanConnector):
    trial = conn._joint.trial
    l0, l1, l2 = conn._axis
    off = conn._offset
    marker = conn._axis_marker
    get = conn._mbs.GetMarkerOutput

    def iwan_rotating_axis_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping,
                                 offset):
        A = get(marker, _ROTATION_MATRIX).tolist()      # row-major 3x3, current configuration
        a0 = A[0] * l0 + A[1] * l1 + A[2] * l2
        a1 = A[3] * l0 + A[4] * l1 + A[5] * l2
        a2 = A[6] * l0 + A[7] * l1 + A[8] * l2
        u = displacement[0] * a0 + displacement[1] * a1 + displacement[2] * a2 - off
        if t <= conn._guard:
            conn._check(mbs, t, u)
        v = velocity[0] * a0 + velocity[1] * a1 + velocity[2] * a2
        if u == conn._lu and v == conn._lv:
            F = conn._lF
        else:
            F = trial(u, v)[0]
            conn._lu = u
            conn._lv = v
            conn._lF = F
        return [F * a0, F * a1, F * a2]

    return iwan_rotating_axis_force
