"""A multi-contact Iwan interface: many contact points, one commit per accepted step.

:func:`add_iwan_interface` puts one joint per pair of markers (e.g. the contact points of a
lap joint). Two routes, chosen automatically:

* **symbolic** (every joint given as :class:`~iwan_element.IwanParameters`, a global axis or
  coordinate markers): each point's force is an Exudyn symbolic expression evaluated in C++
  with no Python call and no Exudyn API call (:mod:`.laws.symbolic_law`: the Masing branch
  formula while the trial slip continues the point's branch, else the full exact law; the
  same law as the connector's). Once per accepted step one Python post-step reads the accepted
  slips of all points (one product of a view of the system coordinates; ANCF Cable2D
  surface points by :mod:`.slips.surface_slips`), commits all points at once in an
  :class:`~iwan_element.core.joint_bank.IwanJointBank`, writes the committed slips to
  one symbolic 1 x n matrix (one ``SetMatrix``), and only for the points that
  left their branch the new branch (five ``SetValue``) and, if it changed, the reversal
  stack (vectors of 6). The records keep the slips; forces
  and energies are recomputed from them when read (an exact replay of the same commits).
* **python** (joints given as elements following the protocol, e.g. effects, or a rotating
  ``axisMarker``): one :func:`~iwan_element.exudyn.add_iwan_connector` per point, with the
  same records in the handle.

Exactness of the symbolic route: the expression holds the newest ``depth`` reversal points
of each point, so it is exact for any step from a stack of at most ``depth`` points; a step
from a deeper stack that closes so many loops that it needs an older point is detected
after the exact commit (the bank walks the full stack), by evaluating the law at the
accepted slip with the previous state (only for points whose stack was deeper than
``depth`` and got shorter, i.e. that closed a loop). Such a step is logged as a warning and its
time is listed in :attr:`.IwanInterface.overflow_times`; raise ``depth`` if that happens (it needs
``depth // 2`` loop closures inside one time step).
"""

from __future__ import annotations

import logging

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (
    ObjectConnectorCartesianSpringDamper,
    ObjectConnectorCoordinateSpringDamper,
)

from ..base.validation import check_scalar
from ..core.joint_bank import IwanJointBank
from ..core.parameters import IwanParameters
from ._dispatch import _dispatcher_for
from ._markers import _COORDINATE_MARKERS, _POSITION_MARKERS, _marker_type, _unit_axis
from .connector import add_iwan_connector
from .interface_handle import IwanInterface
from .laws.interface_springs import add_builtin_springs, check_stiffness
from .laws.symbolic_law import (
    SymbolicIwanState,
    cartesian_law,
    committed_slip_matrix,
    coordinate_law,
    make_probe,
)

__all__ = ["add_iwan_interface", "IwanInterface"]

_log = logging.getLogger(__name__)
_HIDDEN = {"show": False, "drawSize": -1.0, "color": [-1.0, -1.0, -1.0, -1.0]}


def add_iwan_interface(
    mbs,
    markerPairs,
    joints,
    *,
    axis=None,
    axisMarker=None,
    offsets=None,
    record: bool = True,
    depth: int = 8,
    reversal_tol: float = 1e-12,
    name: str = "",
    allow_adaptive_explicit: bool = False,
    stiffness=None,
) -> IwanInterface:
    """Add a joint at each of many contact points, committed together once per step.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system (items added, not necessarily assembled yet).
    markerPairs : sequence of (m0, m1)
        One pair of markers per contact point: two position markers (``MarkerBodyPosition``,
        ``MarkerNodePosition`` ...; the slip is ``a . (p1 - p0) - offset``) or two coordinate
        markers (``MarkerNodeCoordinate``; the slip is ``q1 - q0 - offset``). All pairs of
        one interface are of the same kind.
    joints : sequence of IwanParameters, or of joint elements
        One per point. :class:`~iwan_element.IwanParameters` give an exact Iwan joint per
        point on the symbolic route; elements following the protocol (effects, a
        ``DiscreteIwan`` ...) use one Python connector per point.
    axis : array_like, shape (3,) or (2,), keyword-only
        Direction of the joint forces (global; required for position markers).
    axisMarker : int, optional, keyword-only
        A marker with an orientation carrying ``axis`` (the Python route is then used).
    offsets : sequence of float, optional, keyword-only
        Slip at which each virgin joint is unloaded [m] (default 0).
    record : bool, keyword-only
        Record a row per accepted step (default True); ``False`` stores nothing.
    depth : int, keyword-only
        Reversal points held by each symbolic law (default 8, range [2, 64]); see the
        module docstring.
    reversal_tol : float, keyword-only
        Relative reversal tolerance of the exact joints (as ``IwanJoint``), default 1e-12.
    name : str, keyword-only
        Prefix of the Exudyn object names.
    allow_adaptive_explicit : bool, keyword-only
        Allow ODE23/DOPRI5 with automatic step size (refused by default, as for
        :func:`~iwan_element.exudyn.add_iwan_connector`).
    stiffness : array_like, shape (n_points, 3), optional, keyword-only
        Linear springs ``[kx, ky, kz]`` [N/m] along the global axes on each pair (position
        markers), e.g. the normal contact stiffness: the same forces as a built-in
        ``CartesianSpringDamper`` on the pair, but carried by the joint's own object on the
        symbolic route (one object per point instead of two). Their potential energy is
        :meth:`.IwanInterface.linear_energy`.

    Returns
    -------
    IwanInterface
        Handle with the records and :meth:`.IwanInterface.reset`.

    Raises
    ------
    ValueError
        For mismatched lengths, markers that do not exist or are of mixed kinds, a missing
        or zero axis, a joint that is neither ``IwanParameters`` nor an element, or an element
        already attached elsewhere.
    """
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    pairs = _pairs(markerPairs)
    joints = list(joints) if not isinstance(joints, (str, bytes)) else None
    if joints is None or len(joints) != len(pairs):
        raise ValueError(
            f"joints must be a sequence of {len(pairs)} items (one per marker "
            f"pair), got {None if joints is None else len(joints)}"
        )
    if not isinstance(record, bool):
        raise ValueError(f"record must be True or False, got {record!r}")
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or not 2 <= depth <= 64:
        raise ValueError(f"depth must be an int in [2, 64], got {depth!r}")
    offs = [0.0] * len(pairs) if offsets is None else list(offsets)
    if len(offs) != len(pairs):
        raise ValueError(f"offsets must have {len(pairs)} entries, got {len(offs)}")
    offs = [check_scalar(f"offsets[{i}]", o) for i, o in enumerate(offs)]
    kind = _pair_kind(mbs, pairs, axis, axisMarker)
    springs = check_stiffness(stiffness, len(pairs), kind)
    all_params = all(isinstance(j, IwanParameters) for j in joints)
    if not all_params or axisMarker is not None:
        iface = _python_interface(
            mbs,
            pairs,
            joints,
            kind,
            axis,
            axisMarker,
            offs,
            record,
            reversal_tol,
            name,
            allow_adaptive_explicit,
        )
        if springs is not None:
            iface._stiffness = springs
            iface._spring_objects = add_builtin_springs(mbs, pairs, springs, name)
        return iface
    iface = IwanInterface(mbs, pairs, kind, "symbolic", record)
    iface._stiffness = springs
    iface._allow_adaptive_explicit = bool(allow_adaptive_explicit)
    iface._offsets = offs
    iface._axis = _unit_axis(axis, "axis") if kind == "position" else None
    bank = IwanJointBank(joints, reversal_tol=reversal_tol)
    iface._bank = bank
    dispatcher = _dispatcher_for(mbs)
    iface._dispatcher = dispatcher
    ucm = committed_slip_matrix(len(joints))
    iface._uc_matrix = ucm
    iface._set_uc = ucm.SetMatrix
    for i, p in enumerate(joints):
        st = SymbolicIwanState(p, int(depth), float(bank.tol[i]), uc=ucm.Get(0, i))
        iface._states.append(st)
        iface._objects.append(_symbolic_object(mbs, iface, i, st, f"{name}{i}" if name else ""))
    dispatcher.add(iface)
    _log.debug("added %r", iface)
    return iface


def _pairs(markerPairs):
    if isinstance(markerPairs, (str, bytes)) or not hasattr(markerPairs, "__len__"):
        raise ValueError(f"markerPairs must be a sequence of (m0, m1) pairs, got {markerPairs!r}")
    if len(markerPairs) == 0:
        raise ValueError("markerPairs must hold at least one (m0, m1) pair, got none")
    out = []
    for i, pr in enumerate(markerPairs):
        if isinstance(pr, (str, bytes)) or not hasattr(pr, "__len__") or len(pr) != 2:
            raise ValueError(f"markerPairs[{i}] must be a pair (m0, m1), got {pr!r}")
        out.append((pr[0], pr[1]))
    return out


def _pair_kind(mbs, pairs, axis, axisMarker) -> str:
    kinds = set()
    for i, (m0, m1) in enumerate(pairs):
        t0 = _marker_type(mbs, m0, f"markerPairs[{i}][0]")
        t1 = _marker_type(mbs, m1, f"markerPairs[{i}][1]")
        if t0 in _COORDINATE_MARKERS and t1 in _COORDINATE_MARKERS:
            if not (t0 == t1 == "NodeCoordinate"):
                kinds.add("coordinate-other")
            else:
                kinds.add("coordinate")
        elif t0 in _POSITION_MARKERS and t1 in _POSITION_MARKERS:
            kinds.add("position")
        else:
            raise ValueError(
                f"markerPairs[{i}] must be two coordinate markers or two position "
                f"markers, got {t0} and {t1}"
            )
    if len(kinds) != 1:
        raise ValueError(
            f"all markerPairs of one interface must be of one kind, got {sorted(kinds)}"
        )
    kind = kinds.pop()
    if kind == "coordinate-other":
        raise ValueError(
            "add_iwan_interface takes MarkerNodeCoordinate pairs among the coordinate "
            "markers; use add_iwan_connector for other coordinate markers"
        )
    if kind == "position" and axis is None:
        raise ValueError(
            "axis is required for position markers: give the direction of the joint "
            "forces, e.g. axis=[1, 0, 0]"
        )
    if kind == "coordinate" and (axis is not None or axisMarker is not None):
        raise ValueError("axis and axisMarker apply to position markers only")
    return kind


def _symbolic_object(mbs, iface, i, st, name):
    m0, m1 = (int(m) for m in iface._pairs[i])
    off = iface._offsets[i]
    if iface._kind == "coordinate":
        fn = CreateSymbolicUserFunction(
            mbs,
            coordinate_law(st, off),
            "springForceUserFunction",
            itemTypeName="ObjectConnectorCoordinateSpringDamper",
        )
        item = ObjectConnectorCoordinateSpringDamper(
            name=name,
            markerNumbers=[m0, m1],
            stiffness=0.0,
            damping=0.0,
            springForceUserFunction=fn,
            visualization=_HIDDEN,
        )
    else:
        k = None if iface._stiffness is None else iface._stiffness[i]
        fn = CreateSymbolicUserFunction(
            mbs,
            cartesian_law(st, iface._axis, off, k),
            "springForceUserFunction",
            itemTypeName="ObjectConnectorCartesianSpringDamper",
        )
        item = ObjectConnectorCartesianSpringDamper(
            name=name, markerNumbers=[m0, m1], springForceUserFunction=fn, visualization=_HIDDEN
        )
    iface._functions.append(fn)
    st.probe = make_probe(
        mbs,
        fn,
        iface._kind,
        iface._axis,
        off,
        None if iface._stiffness is None else iface._stiffness[i],
    )
    return mbs.AddObject(item)


def _python_interface(
    mbs, pairs, joints, kind, axis, axisMarker, offs, record, tol, name, allow_adaptive_explicit
):
    from ..core.joint import IwanJoint

    iface = IwanInterface(mbs, pairs, kind, "python", record)
    iface._offsets = offs
    for i, ((m0, m1), j) in enumerate(zip(pairs, joints)):
        el = IwanJoint(j, reversal_tol=tol) if isinstance(j, IwanParameters) else j
        kw = {} if kind == "coordinate" else {"axis": axis, "axisMarker": axisMarker}
        try:
            c = add_iwan_connector(
                mbs,
                [m0, m1],
                el,
                offset=offs[i],
                record=record,
                name=f"{name}{i}" if name else "",
                allow_adaptive_explicit=bool(allow_adaptive_explicit),
                **kw,
            )
        except ValueError as err:
            raise ValueError(f"joints[{i}]: {err}") from None
        iface._connectors.append(c)
        iface._objects.append(c.objectNumber)
    iface._dispatcher = iface._connectors[0]._dispatcher
    return iface
