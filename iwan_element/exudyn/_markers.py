"""Checks of markers, axes and visualization arguments of the Exudyn adapters."""

from __future__ import annotations

import operator
from collections.abc import Mapping

import exudyn as exu
import numpy as np

__all__: list[str] = []

# Marker types (the ``markerType`` entry of ``mbs.GetMarker``) by what they provide.
_COORDINATE_MARKERS = frozenset(
    {
        "NodeCoordinate",
        "NodeRotationCoordinate",
        "BodiesRelativeTranslationCoordinate",
        "BodiesRelativeRotationCoordinate",
    }
)
_ORIENTATION_MARKERS = frozenset(
    {"BodyRigid", "NodeRigid", "SuperElementRigid", "KinematicTreeRigid"}
)
_POSITION_MARKERS = (
    frozenset({"BodyPosition", "NodePosition", "SuperElementPosition"}) | _ORIENTATION_MARKERS
)
_VISUALIZATION_KEYS = ("show", "drawSize", "color")


# ---------------------------------------------------------------------------- validation
#: Exudyn's typed indices that are not markers, and what they number.
_NOT_MARKERS = (
    (exu.ObjectIndex, "a body or object (ObjectIndex)"),
    (exu.NodeIndex, "a node (NodeIndex)"),
    (exu.LoadIndex, "a load (LoadIndex)"),
    (exu.SensorIndex, "a sensor (SensorIndex)"),
)


def _marker_type(mbs, marker, label: str) -> str:
    """The ``markerType`` of ``marker``; a ``ValueError`` naming ``label`` for anything
    else than an existing marker (an Exudyn index of another kind is refused by its type,
    as Exudyn refuses it where a ``MarkerIndex`` belongs; a plain int is a marker number).
    """
    if isinstance(marker, bool):
        raise ValueError(f"{label} must be a marker number, got {marker!r}")
    for kind, what in _NOT_MARKERS:
        if isinstance(marker, kind):
            raise ValueError(
                f"{label} = {marker!r} is {what}, but markers belong here (a MarkerIndex as "
                "mbs.AddMarker returns it): add a marker on it (MarkerBodyPosition, "
                "MarkerNodePosition, MarkerNodeCoordinate ...), or let "
                "create_iwan_connector(mbs, bodyNumbers=[...]) make the markers"
            )
    try:  # an integer or MarkerIndex; a float (1.7) is not truncated
        idx = operator.index(marker)
    except TypeError:
        raise ValueError(
            f"{label} must be a marker number (int or exudyn MarkerIndex), "
            f"got {marker!r} ({type(marker).__name__})"
        ) from None
    n = mbs.systemData.NumberOfMarkers()
    if not 0 <= idx < n:
        raise ValueError(
            f"{label} = {idx} is not a marker of this system: allowed range is [0, {n - 1}]"
            if n
            else f"{label} = {idx}: the system has no markers yet"
        )
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
        raise ValueError(
            "visualization must be a dict with keys among "
            f"{list(_VISUALIZATION_KEYS)}, got {type(visualization).__name__}"
        )
    bad = set(visualization) - set(_VISUALIZATION_KEYS)
    if bad:
        raise ValueError(
            f"unknown visualization keys {sorted(bad)}; allowed are {list(_VISUALIZATION_KEYS)}"
        )
    vis.update(visualization)
    return vis


def _node_coordinate_nodes(mbs, markerNumbers):
    """For two ``NodeCoordinate`` markers: ``[(node, coordinate), ...]`` with ``node = None``
    for a ground node (its coordinate is always 0); ``None`` for other marker types.
    """
    out = []
    for m in markerNumbers:
        mk = mbs.GetMarker(int(m))
        if mk["markerType"] != "NodeCoordinate":
            return None
        node = int(mk["nodeNumber"])
        ground = mbs.GetNode(node)["nodeType"] == "PointGround"
        out.append((None if ground else node, int(mk["coordinate"])))
    return out
