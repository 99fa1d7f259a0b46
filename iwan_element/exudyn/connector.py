"""Drop-in Exudyn connector for any joint element of this package.

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

* **symbolic** (an :class:`~iwan_element.IwanJoint` on two ``MarkerNodeCoordinate`` markers,
  on position markers with a global axis, or on two rigid markers with the axis fixed in
  marker 0's frame, a ``RigidBodySpringDamper``): the exact Iwan law as an Exudyn symbolic
  expression (:mod:`.laws.symbolic_law`), evaluated in C++ without Python and without Exudyn
  API calls (safe with several solver threads). Its state (the committed slip, the branch
  through it and the newest ``depth`` reversal points) lives in symbolic variables; the
  interface uses the same law. Per accepted step the
  post-step reads the slip through a view of Exudyn's coordinates and writes it to one
  variable; while the slip continues the current branch (one interval test) nothing else
  happens: the ``IwanJoint`` (the reference, holding the energies) is committed lazily, at
  the next reversal or loop closure, at the last step of the run, and when read through
  the connector (:mod:`.laws.symbolic_connector`). Records hold ``(t, u)`` per step; force and
  energies are replayed on a copy of the joint when read. A step that needs an older
  reversal point than the law holds (possible only while the stack is deeper than
  ``depth``) is re-solved exactly: near the end of the law's exact window a post-Newton
  function compares the law with the joint and, if they differ, writes a state on the
  step's path and asks Exudyn for a discontinuous iteration. A step that jumps past that
  window from far away (more than ten times the branch's step increments) is still
  detected (the law at the accepted slip against the exact force), logged, and listed in
  :attr:`IwanConnector.overflow_times`.
* **python** (any element, e.g. the effects, or an ``axisMarker`` other than marker 0): a
  Python force function calling ``joint.trial(u, v)``. For two node coordinates the
  post-step reads the accepted slip and its rate through coordinate views and evaluates a
  new trial only if the last one was elsewhere; otherwise it calls ``mbs.GetObjectOutput``,
  which evaluates the force function at the accepted state.

Exudyn calls the post-step function only after accepted steps (and once at the start of a
run, which commits the initial state: an initial slip is reached by monotone virgin
loading); rejected attempts leave no trace. ``SolveStatic`` calls it after every load step,
so a static run commits a quasi-static loading history. A new solve is recognised by the
solver object and settings that ``SolveDynamic``/``SolveStatic`` store in ``mbs.sys`` before
the solver starts: the settings are checked then (:func:`._dispatch.check_settings`; a
refusal is a ``ValueError`` out of ``SolveDynamic``), a solve that starts before the last
accepted time gives every joint of the system a fresh history, and the coordinate views are
renewed at its first step. The accepted slip is read exactly on any marker: an affine row
of the coordinates where the markers' relative position is affine (checked jointly, see
:mod:`.slips.slip_map`), else the connector object's displacement output.

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
* Several solver threads are refused (``ValueError`` before the solver starts) for
  connectors with the Python force law: with two threads Exudyn 1.13.6 was observed to hang
  with about 20 or more Python-function connectors. The symbolic law is allowed.
* ODE23/DOPRI5 with automatic step size are refused (see :func:`check_settings`).
* A user-function connector reports no potential energy to Exudyn (Exudyn 1.13.6 refuses
  ``PotentialEnergy`` for any connector whose force a user function defines); use the
  connector's records (:attr:`IwanConnector.stored_energy_history`, ...) or
  :func:`~iwan_element.exudyn.record_energy`.
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
call with an interval test, one variable update and, with records, two list appends; the
joint is committed only at reversals and loop closures).

The handle class :class:`IwanConnector` lives in :mod:`._connector_handle` (records,
read-outs, the Python law's per-step work); this module places connectors.
"""

from __future__ import annotations

import logging

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    ObjectConnectorCartesianSpringDamper,
    ObjectConnectorCoordinateSpringDamper,
)

from ..base.validation import check_scalar
from ..core.joint import IwanJoint
from ..core.parameters import IwanParameters
from ..core.protocol import check_element
from ._connector_handle import IwanConnector
from ._dispatch import _claim, _dispatcher_for
from ._markers import (
    _COORDINATE_MARKERS,
    _ORIENTATION_MARKERS,
    _POSITION_MARKERS,
    _marker_type,
    _node_coordinate_nodes,
    _unit_axis,
    _visualization,
)
from .laws import symbolic_connector as _symbolic
from .laws.python_law import (
    coordinate_force_function,
    position_force_function,
    rotating_axis_force_function,
)

__all__ = ["add_iwan_connector", "IwanConnector"]

_log = logging.getLogger(__name__)
IwanConnector.__module__ = __name__  # documented here (defined in _connector_handle)


def add_iwan_connector(
    mbs,
    markerNumbers,
    joint,
    *,
    axis=None,
    axisMarker=None,
    offset=0.0,
    damping: float = 0.0,
    name: str = "",
    visualization=None,
    record: bool = True,
    law: str = "auto",
    depth: int = 8,
    allow_adaptive_explicit: bool = False,
) -> IwanConnector:
    """Add a history-dependent joint element between two markers of an Exudyn system.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system (items added, not necessarily assembled yet).
    markerNumbers : sequence of 2 marker numbers
        ``[m0, m1]`` (``MarkerIndex`` as ``mbs.AddMarker`` returns it, or ``int``; a body's
        ``ObjectIndex`` or a ``NodeIndex`` is refused: :func:`create_iwan_connector` makes
        the markers from bodies and nodes). Both coordinate markers (``MarkerNodeCoordinate``,
        ``MarkerNodeRotationCoordinate`` ...): the slip is ``u = q1 - q0 - offset``. Both
        position markers (``MarkerBodyPosition``, ``MarkerNodePosition``, ``MarkerBodyRigid``,
        ``MarkerNodeRigid`` ...): ``u = a . (p1 - p0) - offset`` with the unit axis ``a``.
        The joint force ``F = joint.trial(u, v)[0]`` acts as ``-F`` (along ``a``) on marker 1
        and ``+F`` on marker 0, i.e. it resists positive slip.
    joint : IwanParameters or JointElement
        :class:`~iwan_element.IwanParameters` build a new exact, virgin
        :class:`~iwan_element.IwanJoint` (as :func:`add_iwan_interface` does; read it back
        as :attr:`IwanConnector.joint`). Otherwise any element following the package's
        element protocol (``trial``, ``commit``, ``revert``, ``reset``, energy read-outs,
        ``displacement`` and ``force``): it is used exclusively by this connector and its
        current state is the initial history.
    axis : array_like, shape (3,) or (2,), keyword-only
        Direction of the joint force for position markers (normalised here; a 2-vector
        gets ``z = 0``). Required for position markers, not allowed for coordinate markers.
    axisMarker : int, optional, keyword-only
        A marker with an orientation (``MarkerBodyRigid``, ``MarkerNodeRigid`` ...; also a
        rigid marker on an ``ObjectANCFCable2D``, whose frame follows the beam slope). If
        given, ``axis`` is expressed in that marker's frame and rotates with it; the force
        then stays along the current axis and the moment of the axis rotation is neglected
        (exact when the two points coincide, as for the interface points of a lap joint).
        When ``axisMarker`` is ``markerNumbers[0]`` and both markers have an orientation,
        the symbolic law runs on an ``ObjectConnectorRigidBodySpringDamper``, whose joint
        frame is that marker's; otherwise the Python law is used.
    offset : float or array_like of 3, keyword-only
        Slip at which the joint is unloaded in its virgin state [m] (default 0); for
        position markers also a vector ``d0`` as Exudyn's Cartesian spring takes it (the
        joint is unloaded at ``p1 - p0 = d0``: the slip offset is ``a . d0``). Fixed at
        creation (the Exudyn object's own ``offset`` parameter is not read).
    damping : float, keyword-only
        A dashpot in parallel with the joint along its axis [N s/m] (default 0): the force
        becomes ``F + c v`` with the slip rate ``v``; the records hold it (force,
        dissipation ``int c v du`` per step by the trapezoidal rule, work).
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
        :class:`~iwan_element.IwanJoint` on two ``MarkerNodeCoordinate`` markers, on
        position markers with a global axis, or with ``axisMarker`` = marker 0 on two
        rigid markers. ``"python"``: a Python force function calling
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
        (``SolveDynamic`` with them raises ``ValueError`` before the solver starts; the
        solver is not known when the connector is added): a reversal inside a step is not
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
    >>> conn = add_iwan_connector(mbs, [mGround, mMass], params)   # doctest: +SKIP
    >>> mbs.Assemble(); mbs.SolveDynamic(simulationSettings)                  # doctest: +SKIP
    >>> conn.dissipated_energy_history[-1]                                    # doctest: +SKIP
    """
    if isinstance(joint, IwanParameters):
        joint = IwanJoint(joint)
    _check_options(
        mbs,
        markerNumbers,
        joint,
        name=name,
        record=record,
        law=law,
        depth=depth,
        allow_adaptive_explicit=allow_adaptive_explicit,
    )
    damping = check_scalar("damping", damping, low=0.0)
    vis = _visualization(visualization)
    kind, unit, axis_marker, rigid = _classify_markers(mbs, markerNumbers, axis, axisMarker)
    offset = _slip_offset(offset, kind, unit)
    dispatcher = _dispatcher_for(mbs)
    conn = IwanConnector(
        mbs, markerNumbers, joint, kind, unit, axis_marker, offset, record, damping
    )
    _claim(joint, conn)
    conn._dispatcher = dispatcher
    conn._allow_adaptive_explicit = allow_adaptive_explicit
    if kind == "coordinate":
        conn._fast_nodes = _node_coordinate_nodes(mbs, markerNumbers)
    frame0 = axis_marker is not None and axis_marker == int(markerNumbers[0]) and rigid
    route = _choose_route(law, joint, kind, conn._fast_nodes, axis_marker, frame0)
    conn._object = mbs.AddObject(_connector_item(conn, joint, route, int(depth), name, vis))
    dispatcher.add(conn)
    _log.debug("added %r", conn)
    return conn


def _check_options(
    mbs, markerNumbers, joint, *, name, record, law, depth, allow_adaptive_explicit
) -> None:
    """The checks of :func:`add_iwan_connector`'s arguments that need no marker types."""
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    if (
        isinstance(markerNumbers, (str, bytes))
        or not hasattr(markerNumbers, "__len__")
        or len(markerNumbers) != 2
    ):
        raise ValueError(
            f"markerNumbers must be a list of two marker numbers, got {markerNumbers!r}"
        )
    try:
        check_element(joint, name="joint")
    except ValueError as err:
        raise ValueError(
            f"{err}; give IwanParameters (an exact IwanJoint is built) or a "
            "joint element such as IwanJoint(params)"
        ) from None
    missing = [a for a in ("displacement", "force") if not hasattr(joint, a)]
    if missing:
        raise ValueError(
            f"joint must expose the committed {missing} (element protocol); "
            f"{type(joint).__name__} does not"
        )
    if not isinstance(name, str):
        raise ValueError(f"name must be a str, got {type(name).__name__}")
    check_run_options(
        record=record, law=law, depth=depth, allow_adaptive_explicit=allow_adaptive_explicit
    )


def check_run_options(*, record, law, depth, allow_adaptive_explicit) -> None:
    """The options of :func:`add_iwan_connector` that do not depend on the markers (also
    checked by :func:`~iwan_element.exudyn.create_iwan_connector` before it makes any).
    """
    if not isinstance(record, bool):
        raise ValueError(f"record must be True or False, got {record!r}")
    if not isinstance(allow_adaptive_explicit, bool):
        raise ValueError(
            f"allow_adaptive_explicit must be True or False, got {allow_adaptive_explicit!r}"
        )
    if law not in ("auto", "symbolic", "python"):
        raise ValueError(f"law must be 'auto', 'symbolic' or 'python', got {law!r}")
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not 2 <= depth <= 64:
        raise ValueError(f"depth must be an int in [2, 64], got {depth!r}")


def _slip_offset(offset, kind, unit) -> float:
    """The slip offset [m]: a number, or for position markers a vector ``d0`` (Exudyn's
    Cartesian offset), projected on the axis.
    """
    if kind == "position" and np.ndim(offset) == 1:
        d0 = np.asarray(offset, dtype=float) if np.size(offset) in (2, 3) else None
        if d0 is None or not np.all(np.isfinite(d0)):
            raise ValueError(
                f"offset must be a number or a finite vector of 2 or 3 numbers [m], got {offset!r}"
            )
        return float(np.dot(np.asarray(unit)[: d0.size], d0))
    return check_scalar("offset", offset)


def _classify_markers(mbs, markerNumbers, axis, axisMarker):
    """``(kind, unit axis or None, axis marker or None, both markers have an orientation)``
    of two coordinate or position markers.
    """
    t0 = _marker_type(mbs, markerNumbers[0], "markerNumbers[0]")
    t1 = _marker_type(mbs, markerNumbers[1], "markerNumbers[1]")
    if int(markerNumbers[0]) == int(markerNumbers[1]):
        raise ValueError(f"markerNumbers must be two different markers, got {list(markerNumbers)}")
    if t0 in _COORDINATE_MARKERS and t1 in _COORDINATE_MARKERS:
        if axis is not None or axisMarker is not None:
            raise ValueError(
                "axis and axisMarker apply to position markers only; markerNumbers "
                f"are coordinate markers ({t0}, {t1})"
            )
        return "coordinate", None, None, False
    if not (t0 in _POSITION_MARKERS and t1 in _POSITION_MARKERS):
        raise ValueError(
            f"markerNumbers must be two coordinate markers ({sorted(_COORDINATE_MARKERS)}) or two "
            f"position markers ({sorted(_POSITION_MARKERS)}); got {t0} and {t1}"
        )
    if axis is None:
        raise ValueError(
            f"axis is required for position markers ({t0}, {t1}): give the "
            "direction of the joint force, e.g. axis=[1, 0, 0]"
        )
    unit = _unit_axis(axis, "axis")
    rigid = t0 in _ORIENTATION_MARKERS and t1 in _ORIENTATION_MARKERS
    if axisMarker is None:
        return "position", unit, None, rigid
    ta = _marker_type(mbs, axisMarker, "axisMarker")
    if ta not in _ORIENTATION_MARKERS:
        raise ValueError(
            f"axisMarker must be a marker with an orientation "
            f"({sorted(_ORIENTATION_MARKERS)}), got {ta}"
        )
    return "position", unit, int(axisMarker), rigid


def _connector_item(conn, joint, route, depth, name, vis):
    """The Exudyn object of the connector: the symbolic law, or a Python user function on a
    coordinate or Cartesian spring-damper.
    """
    if route == "symbolic":
        conn._route = "symbolic"
        conn._lazy = True
        dispatcher = conn._dispatcher
        item = _symbolic.symbolic_item(conn, depth, name, vis)
        conn._dispatcher = dispatcher
        _symbolic.sync_stack(conn)
        conn._state.set_uc(joint.displacement)
        return item
    if conn.kind == "coordinate":
        return ObjectConnectorCoordinateSpringDamper(
            name=name,
            markerNumbers=list(conn.markerNumbers),
            stiffness=0.0,
            damping=0.0,
            offset=conn.offset,
            springForceUserFunction=coordinate_force_function(conn),
            visualization=vis,
        )
    uf = (
        position_force_function(conn)
        if conn.axisMarker is None
        else rotating_axis_force_function(conn)
    )
    return ObjectConnectorCartesianSpringDamper(
        name=name,
        markerNumbers=list(conn.markerNumbers),
        springForceUserFunction=uf,
        visualization=vis,
    )


def _choose_route(law, joint, kind, fast_nodes, axis_marker, frame0) -> str:
    why = None
    if type(joint) is not IwanJoint:
        why = f"the joint is a {type(joint).__name__} (the symbolic law is the IwanJoint's)"
    elif kind == "coordinate" and fast_nodes is None:
        why = "the coordinate markers are not both MarkerNodeCoordinate"
    elif axis_marker is not None and not frame0:
        why = (
            "the axis rotates with an axisMarker that is not markerNumbers[0], or a "
            "marker has no orientation (the symbolic law turns with marker 0's frame)"
        )
    if law == "symbolic" and why is not None:
        raise ValueError(f"law='symbolic' is not available here: {why}; use law='python'")
    if law == "python" or why is not None:
        return "python"
    return "symbolic"
