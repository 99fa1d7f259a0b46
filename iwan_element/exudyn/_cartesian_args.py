"""The arguments of :func:`.cartesian.create_iwan_connector` checked: the two items and
their local positions, the Iwan axes (orthogonal, normalised) and their parameters, the
springs beside them, the damping's two forms, and the orientation a rotating frame needs.
"""

from __future__ import annotations

from numbers import Integral

import exudyn as exu
import numpy as np

from ..base.validation import check_scalar
from ..core.parameters import IwanParameters
from ._markers import _ORIENTATION_MARKERS, _marker_type

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


def _iwan_axes(axis, parameters, stiffness):
    """``(axes, parameters, stiffness)``: the Iwan axes, one joint per axis, and the springs,
    refusing a spring along an Iwan axis.
    """
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
    return axes, params, k
