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
from ._cartesian_args import _check_orientation, _damping, _items, _iwan_axes, _parameters, _vector3
from ._markers import _COORDINATE_MARKERS, _marker_type
from .connector import add_iwan_connector, check_run_options

__all__ = ["create_iwan_connector", "IwanCartesianConnector"]

_log = logging.getLogger(__name__)


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
    def springDamper(self) -> Any:
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
    axes, params, k = _iwan_axes(axis, parameters, stiffness)
    d0 = np.zeros(3) if offset is None else _vector3("offset", offset)
    c, dvec = _damping(damping)
    if not useGlobalFrame:
        _check_orientation(mbs, items)
    m0, m1 = (
        _marker(mbs, name, i, kind, it, pos, not useGlobalFrame)
        for i, (kind, it, pos) in enumerate(items)
    )
    conns = _iwan_connectors(mbs, m0, m1, axes, params, d0, c, useGlobalFrame, name, vis, common)
    spring = None
    if np.any(k) or np.any(dvec):
        spring = _linear_part(mbs, m0, m1, k, dvec, d0, useGlobalFrame, name, vis)
    frame = "global" if useGlobalFrame else "body0"
    handle = IwanCartesianConnector(mbs, (m0, m1), axes, conns, spring, frame)
    _log.debug("created %r", handle)
    return handle


# ---------------------------------------------------------------------------- helpers
def _iwan_connectors(mbs, m0, m1, axes, params, d0, c, global_frame, name, vis, common):
    """One Iwan connector per axis between the markers (offset: ``d0`` along the axis)."""
    conns = []
    for j, (a, p) in enumerate(zip(axes, params)):
        conns.append(
            add_iwan_connector(
                mbs,
                [m0, m1],
                p,
                axis=a,
                axisMarker=None if global_frame else m0,
                offset=float(a @ d0),
                damping=c,
                name=f"{name}:iwan{j}" if name else "",
                visualization=vis,
                **common,
            )
        )
    return conns


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
