"""The Iwan joint in Exudyn's own idiom: :func:`create_iwan_connector`, the counterpart of
``mbs.CreateCartesianSpringDamper`` (markers made for the user from bodies and nodes).

The Cartesian form: one exact Iwan law on each of up to three orthogonal axes, and linear
springs and dampers (Exudyn's built-in spring-damper, which reports its potential energy to
Exudyn) on the remaining ones. Why a law per axis and not one two-dimensional tangential
law with a single slip direction: the four-parameter model (Segalman 2005) is a
one-dimensional law, identified from one-dimensional loops; its exact history is a stack of
reversal points (the Masing rules) per axis. A two-dimensional law with one slip direction
needs the directions of all its sliders as history, which the four parameters do not
define and no reversal stack represents. The cost of the per-axis form: a slip along a
diagonal of two axes with the same parameters reaches macroslip at ``sqrt(2) Fs`` instead
of ``Fs`` (the two laws do not share one friction limit); use one axis along the expected
slip direction when that matters.
"""

from __future__ import annotations

import logging
from numbers import Integral
from typing import Any

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodePosition,
    MarkerNodeRigid,
    ObjectConnectorCartesianSpringDamper,
    ObjectConnectorRigidBodySpringDamper,
)

from ..base.validation import check_scalar
from ..core.parameters import IwanParameters
from ._markers import _COORDINATE_MARKERS, _ORIENTATION_MARKERS, _marker_type
from .connector import add_iwan_connector, check_run_options

__all__ = ["create_iwan_connector", "IwanCartesianConnector"]

_log = logging.getLogger(__name__)
#: Bodies and nodes without an orientation (a rigid marker on them is refused).
_POINT_BODIES = frozenset({"MassPoint", "MassPoint2D", "Mass1D"})
_POINT_NODES = frozenset(
    {
        "Point",
        "Point2D",
        "PointGround",
        "1D",
        "GenericODE2",
        "GenericData",
        "Point2DSlope1",
        "Point3DSlope1",
        "Point3DSlope23",
    }
)


class IwanCartesianConnector:
    """Handle of a connector made by :func:`create_iwan_connector`: one
    :class:`~iwan_element.exudyn.IwanConnector` per Iwan axis and, if asked for, Exudyn's
    built-in spring-damper on the remaining axes.

    Records (one row per accepted step): :attr:`time_history` (n,), :attr:`slip_history`
    and :attr:`force_history` (n, n_axes), and the totals of the axes
    :attr:`stored_energy_history`, :attr:`dissipated_energy_history`, :attr:`work_history`
    (n,), the dashpots in parallel included.
    """

    def __init__(self, mbs, markers, axes, connectors, spring, frame):
        self._mbs = mbs
        self._markers = tuple(markers)
        self._axes = axes
        self._connectors = tuple(connectors)
        self._spring = spring
        self._frame = frame

    @property
    def markerNumbers(self) -> tuple:
        """The two markers ``(m0, m1)`` (made here for bodies and nodes)."""
        return self._markers

    @property
    def connectors(self) -> tuple:
        """The :class:`~iwan_element.exudyn.IwanConnector` of each Iwan axis."""
        return self._connectors

    @property
    def springDamper(self):
        """Exudyn's built-in spring-damper on the remaining axes (``ObjectIndex``), or
        ``None``. Exudyn reports its potential energy; :func:`record_energy` books its
        damping.
        """
        return self._spring

    @property
    def objectNumbers(self) -> list:
        """Every Exudyn object of the connector (the Iwan laws, then the spring-damper)."""
        return [c.objectNumber for c in self._connectors] + (
            [] if self._spring is None else [self._spring]
        )

    @property
    def axes(self) -> np.ndarray:
        """The Iwan axes, shape (n_axes, 3) (unit; global, or in the frame of marker 0 when
        ``useGlobalFrame=False``); empty (0, 3) for coordinate markers.
        """
        return self._axes.copy()

    @property
    def frame(self) -> str:
        """``"global"``, ``"body0"`` (turning with marker 0) or ``"coordinate"``."""
        return self._frame

    @property
    def n_records(self) -> int:
        """Number of recorded steps common to every direction's connector."""
        return min(c.n_records for c in self._connectors)

    def _stack(self, name: str) -> np.ndarray:
        cols = [getattr(c, name) for c in self._connectors]
        n = min(len(x) for x in cols)
        return np.stack([x[:n] for x in cols], axis=1)

    @property
    def time_history(self) -> np.ndarray:
        """Times of the accepted steps [s], shape (n,)."""
        return self._connectors[0].time_history[: self.n_records]

    @property
    def slip_history(self) -> np.ndarray:
        """Slip along each Iwan axis [m], shape (n, n_axes)."""
        return self._stack("slip_history")

    @property
    def force_history(self) -> np.ndarray:
        """Force of each Iwan law (and its dashpot) [N], shape (n, n_axes)."""
        return self._stack("force_history")

    @property
    def dissipated_energy_history(self) -> np.ndarray:
        """Energy dissipated by the Iwan laws and their dashpots [J], shape (n,)."""
        return self._stack("dissipated_energy_history").sum(axis=1)

    @property
    def work_history(self) -> np.ndarray:
        """Work done on the Iwan laws and their dashpots [J], shape (n,)."""
        return self._stack("work_history").sum(axis=1)

    @property
    def stored_energy_history(self) -> np.ndarray:
        """Elastic energy held by the Iwan laws [J], shape (n,)."""
        return self.work_history - self.dissipated_energy_history

    def records(self) -> dict:
        """All records: ``time`` (n,), ``slip``, ``force`` (n, n_axes), ``stored_energy``,
        ``dissipated_energy``, ``work`` (n,).
        """
        w, d = self.work_history, self.dissipated_energy_history
        return {
            "time": self.time_history,
            "slip": self.slip_history,
            "force": self.force_history,
            "stored_energy": w - d,
            "dissipated_energy": d,
            "work": w,
        }

    def reset(self) -> None:
        """Return every Iwan law to its virgin state and clear the records (a solve that
        starts before the last accepted time does this by itself).
        """
        for c in self._connectors:
            c.reset()

    def __repr__(self) -> str:
        return (
            f"IwanCartesianConnector(markerNumbers={self._markers}, frame={self._frame!r}, "
            f"n_axes={len(self._connectors)}, springDamper={self._spring}, "
            f"records={self.n_records})"
        )


def create_iwan_connector(
    mbs,
    *,
    bodyNumbers,
    localPosition0=(0.0, 0.0, 0.0),
    localPosition1=(0.0, 0.0, 0.0),
    axis=None,
    parameters,
    damping=0.0,
    stiffness=(0.0, 0.0, 0.0),
    offset=None,
    useGlobalFrame: bool = True,
    name: str = "",
    show: bool = True,
    drawSize: float = -1.0,
    color=(-1.0, -1.0, -1.0, -1.0),
    record: bool = True,
    law: str = "auto",
    depth: int = 8,
    allow_adaptive_explicit: bool = False,
) -> IwanCartesianConnector:
    """Put Iwan joints between two bodies, nodes or markers, as ``mbs.CreateCartesianSpringDamper``
    puts a spring-damper.

    Parameters
    ----------
    mbs : exudyn.MainSystem
    bodyNumbers : list of 2 items, keyword-only
        Each a body (``ObjectIndex``, or an int as Exudyn takes it) at ``localPosition0/1``,
        a node (``NodeIndex``) or a marker (``MarkerIndex``, used as it is). Bodies and nodes
        get a ``MarkerBodyPosition``/``MarkerNodePosition`` (rigid markers when
        ``useGlobalFrame=False``), named ``Marker0:name``, ``Marker1:name`` as Exudyn names
        them. Two coordinate markers (``MarkerNodeCoordinate``) make a one-dimensional joint
        on ``q1 - q0`` (no ``axis``).
    localPosition0, localPosition1 : array_like of 3, keyword-only
        Points on body 0 and body 1 [m] (body frame); ``(0, 0, 0)`` for nodes and markers.
    axis : array_like, shape (3,) or (n_axes, 3), keyword-only
        The Iwan axes (one to three, mutually orthogonal; normalised here): global, or in
        body 0's frame when ``useGlobalFrame=False``. Required for position markers.
    parameters : IwanParameters or sequence of them, keyword-only
        The joint of each axis (one for all, or one per axis).
    damping : float or array_like of 3, keyword-only
        A number ``c`` [N s/m]: a dashpot in parallel with each Iwan law along its axis, in
        the law's own object and records. Three numbers ``[dx, dy, dz]``: Exudyn's dampers
        along the frame's axes in the built-in spring-damper (along an Iwan axis they act in
        parallel with it), as ``CreateCartesianSpringDamper`` takes them.
    stiffness : array_like of 3, keyword-only
        Linear springs ``[kx, ky, kz]`` [N/m] along the frame's axes on the remaining axes,
        in the built-in spring-damper; a spring with a component along an Iwan axis is
        refused (it would stiffen the identified joint: fold it into ``KT``).
    offset : float or array_like of 3, optional, keyword-only
        Exudyn's offset ``d0`` [m]: springs and joints are unloaded at ``p1 - p0 = d0``
        (frame components); a number for coordinate markers (default 0).
    useGlobalFrame : bool, keyword-only
        ``True`` (default): ``axis``, ``stiffness``, ``damping`` and ``offset`` are global.
        ``False``: they are in the frame of marker 0 and turn with body 0 (the joint frame
        of Exudyn's ``RigidBodySpringDamper``; both items need an orientation).
    name, show, drawSize, color : keyword-only
        As Exudyn's Create functions take them.
    record, law, depth, allow_adaptive_explicit : keyword-only
        As :func:`~iwan_element.exudyn.add_iwan_connector` (per axis).

    Returns
    -------
    IwanCartesianConnector

    Raises
    ------
    ValueError
        An item that is no body, node or marker (named), a local position given for a node
        or a marker, axes that are not orthogonal, a spring along an Iwan axis, a rotating
        frame on an item without orientation, and what ``add_iwan_connector`` refuses.

    Examples
    --------
    >>> conn = create_iwan_connector(mbs, bodyNumbers=[oGround, oMass], axis=[1, 0, 0],
    ...                              parameters=params, stiffness=[0, k, k],
    ...                              damping=[d, 0, 0], offset=[L, 0, 0])  # doctest: +SKIP
    """
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    if not isinstance(useGlobalFrame, bool):
        raise ValueError(f"useGlobalFrame must be True or False, got {useGlobalFrame!r}")
    vis = {
        "show": bool(show),
        "drawSize": check_scalar("drawSize", drawSize),
        "color": [float(x) for x in color],
    }
    items = _items(bodyNumbers, localPosition0, localPosition1)
    common: dict[str, Any] = dict(
        record=record, law=law, depth=depth, allow_adaptive_explicit=allow_adaptive_explicit
    )
    check_run_options(**common)
    if not isinstance(name, str):
        raise ValueError(f"name must be a str, got {type(name).__name__}")
    if all(k == "marker" for k, _, _ in items) and all(
        _marker_type(mbs, it, f"bodyNumbers[{i}]") in _COORDINATE_MARKERS
        for i, (_, it, _) in enumerate(items)
    ):
        return _coordinate_connector(
            mbs, items, axis, parameters, damping, stiffness, offset, name, vis, common
        )
    if axis is None:
        raise ValueError(
            "axis is required: give the Iwan axis (or up to three orthogonal "
            "axes), e.g. axis=[1, 0, 0]"
        )
    axes = _axes(axis)
    params = _parameters(parameters, len(axes))
    k = _vector3("stiffness", stiffness)
    along = [i for i, a in enumerate(axes) if np.linalg.norm(k * a) > 0.0]
    if along:
        raise ValueError(
            f"stiffness = {k.tolist()} has a spring along the Iwan axis "
            f"{axes[along[0]].tolist()}: stiffness acts on the remaining axes only "
            "(a spring in parallel would stiffen the identified joint; fold it into "
            "KT)"
        )
    d0 = np.zeros(3) if offset is None else _vector3("offset", offset)
    c, dvec = _damping(damping)
    if not useGlobalFrame:
        _check_orientation(mbs, items)
    m0, m1 = (
        _marker(mbs, name, i, kind, it, pos, not useGlobalFrame)
        for i, (kind, it, pos) in enumerate(items)
    )
    conns = []
    for j, (a, p) in enumerate(zip(axes, params)):
        conns.append(
            add_iwan_connector(
                mbs,
                [m0, m1],
                p,
                axis=a,
                axisMarker=None if useGlobalFrame else m0,
                offset=float(a @ d0),
                damping=c,
                name=f"{name}:iwan{j}" if name else "",
                visualization=vis,
                **common,
            )
        )
    spring = None
    if np.any(k) or np.any(dvec):
        spring = _linear_part(mbs, m0, m1, k, dvec, d0, useGlobalFrame, name, vis)
    frame = "global" if useGlobalFrame else "body0"
    handle = IwanCartesianConnector(mbs, (m0, m1), axes, conns, spring, frame)
    _log.debug("created %r", handle)
    return handle


# ---------------------------------------------------------------------------- helpers
def _items(bodyNumbers, p0, p1):
    """``[(kind, item, localPosition), ...]`` with kind ``body``, ``node`` or ``marker``."""
    if (
        isinstance(bodyNumbers, (str, bytes))
        or not hasattr(bodyNumbers, "__len__")
        or len(bodyNumbers) != 2
    ):
        raise ValueError(
            f"bodyNumbers must be a list of two items (bodies, nodes or markers), "
            f"got {bodyNumbers!r}"
        )
    out = []
    for i, (it, pos) in enumerate(zip(bodyNumbers, (p0, p1))):
        pos = _vector3(f"localPosition{i}", pos)
        if isinstance(it, exu.MarkerIndex):
            kind = "marker"
        elif isinstance(it, exu.NodeIndex):
            kind = "node"
        elif isinstance(it, exu.ObjectIndex) or (
            isinstance(it, Integral) and not isinstance(it, bool)
        ):
            kind = "body"
        else:
            raise ValueError(
                f"bodyNumbers[{i}] must be a body (ObjectIndex or int), a node "
                f"(NodeIndex) or a marker (MarkerIndex), got {it!r} "
                f"({type(it).__name__})"
            )
        if kind != "body" and np.any(pos):
            raise ValueError(
                f"localPosition{i} must be (0, 0, 0) for a {kind} "
                f"(bodyNumbers[{i}]); got {pos.tolist()}"
            )
        out.append((kind, it, pos))
    return out


def _vector3(label, value) -> np.ndarray:
    try:
        v = np.array(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise ValueError(f"{label} must be a vector of 3 numbers, got {value!r}") from None
    if v.size != 3 or not np.all(np.isfinite(v)):
        raise ValueError(f"{label} must be a finite vector of 3 numbers, got {value!r}")
    return v


def _axes(axis) -> np.ndarray:
    try:
        a = np.array(axis, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"axis must be a vector of 3 numbers or up to three of them, got {axis!r}"
        ) from None
    a = a.reshape(1, -1) if a.ndim == 1 else a
    if a.ndim != 2 or a.shape[1] != 3 or not 1 <= a.shape[0] <= 3 or not np.all(np.isfinite(a)):
        raise ValueError(
            f"axis must be a finite vector of 3 numbers or up to three of them, got {axis!r}"
        )
    n = np.linalg.norm(a, axis=1)
    if np.any(n == 0.0):
        raise ValueError(f"axis must hold non-zero vectors, got {axis!r}")
    a = a / n[:, None]
    gram = a @ a.T - np.eye(len(a))
    if np.max(np.abs(gram)) > 1e-9:
        raise ValueError(f"the Iwan axes must be mutually orthogonal, got {a.tolist()}")
    return a


def _parameters(parameters, n) -> list:
    if isinstance(parameters, IwanParameters):
        return [parameters] * n
    ps = list(parameters) if isinstance(parameters, (list, tuple)) else None
    if ps is None or len(ps) != n or not all(isinstance(p, IwanParameters) for p in ps):
        raise ValueError(
            f"parameters must be IwanParameters or a list of {n} of them "
            f"(one per axis), got {parameters!r}"
        )
    return ps


def _damping(damping):
    """``(c, [dx, dy, dz])``: the dashpot along the Iwan axes, or Exudyn's dampers."""
    if np.ndim(damping) == 0:
        return check_scalar("damping", damping, low=0.0), np.zeros(3)
    d = _vector3("damping", damping)
    if np.any(d < 0):
        raise ValueError(f"damping must be >= 0 [N s/m], got {d.tolist()}")
    return 0.0, d


def _check_orientation(mbs, items) -> None:
    """useGlobalFrame=False: refuse items without an orientation before any marker is made
    (Exudyn would refuse a rigid marker on them only at ``Assemble``).
    """
    for i, (kind, item, _) in enumerate(items):
        if kind == "marker":
            if _marker_type(mbs, item, f"bodyNumbers[{i}]") not in _ORIENTATION_MARKERS:
                raise ValueError(
                    f"bodyNumbers[{i}] is a marker without orientation; "
                    "useGlobalFrame=False needs rigid markers (MarkerBodyRigid ...)"
                )
            continue
        what = (
            mbs.GetObject(item)["objectType"] if kind == "body" else mbs.GetNode(item)["nodeType"]
        )
        if what in (_POINT_BODIES if kind == "body" else _POINT_NODES):
            raise ValueError(
                f"bodyNumbers[{i}] = {item!r} has no orientation (a {what}): "
                "useGlobalFrame=False turns the frame with body 0 and needs an "
                "orientation on both items"
            )


def _marker(mbs, name, i, kind, item, pos, rigid):
    """The marker of item ``i`` (made for a body or a node; named as Exudyn names them)."""
    label = f"Marker{i}:{name}" if name else ""
    if kind == "marker":
        return item
    if kind == "body":
        cls = MarkerBodyRigid if rigid else MarkerBodyPosition
        return mbs.AddMarker(cls(name=label, bodyNumber=item, localPosition=list(pos)))
    cls = MarkerNodeRigid if rigid else MarkerNodePosition
    return mbs.AddMarker(cls(name=label, nodeNumber=item))


def _linear_part(mbs, m0, m1, k, d, d0, global_frame, name, vis):
    """Exudyn's built-in spring-damper on the remaining axes (global, or in marker 0's
    frame as a RigidBodySpringDamper with no rotational stiffness).
    """
    label = f"{name}:springDamper" if name else ""
    if global_frame:
        return mbs.AddObject(
            ObjectConnectorCartesianSpringDamper(
                name=label,
                markerNumbers=[m0, m1],
                stiffness=k.tolist(),
                damping=d.tolist(),
                offset=d0.tolist(),
                visualization=vis,
            )
        )
    K = np.zeros((6, 6))
    D = np.zeros((6, 6))
    K[:3, :3] = np.diag(k)
    D[:3, :3] = np.diag(d)
    return mbs.AddObject(
        ObjectConnectorRigidBodySpringDamper(
            name=label,
            markerNumbers=[m0, m1],
            stiffness=K,
            damping=D,
            offset=list(d0) + [0.0, 0.0, 0.0],
            visualization=vis,
        )
    )


def _coordinate_connector(
    mbs, items, axis, parameters, damping, stiffness, offset, name, vis, common
):
    """Two coordinate markers: one joint on ``q1 - q0``."""
    if axis is not None:
        raise ValueError(
            "axis applies to position markers; bodyNumbers are two coordinate "
            "markers (the joint acts on q1 - q0)"
        )
    if np.ndim(damping) != 0 or np.any(np.asarray(stiffness, dtype=float)):
        raise ValueError(
            "coordinate markers take a number as damping and no stiffness "
            "(there are no remaining axes)"
        )
    (params,) = _parameters(parameters, 1)
    m0, m1 = items[0][1], items[1][1]
    conn = add_iwan_connector(
        mbs,
        [m0, m1],
        params,
        damping=damping,
        offset=0.0 if offset is None else offset,
        name=f"{name}:iwan0" if name else "",
        visualization=vis,
        **common,
    )
    return IwanCartesianConnector(mbs, (m0, m1), np.zeros((0, 3)), [conn], None, "coordinate")
