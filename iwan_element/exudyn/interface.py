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
time is listed in :attr:`IwanInterface.overflow_times`; raise ``depth`` if that happens (it needs
``depth // 2`` loop closures inside one time step).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

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
from ._dispatch import _dispatcher_for, _installed_post_step
from ._markers import _COORDINATE_MARKERS, _POSITION_MARKERS, _marker_type, _unit_axis
from .connector import add_iwan_connector
from .laws.interface_springs import add_builtin_springs, check_stiffness, linear_energy
from .laws.symbolic_law import (
    VIRGIN,
    SymbolicIwanState,
    cartesian_law,
    committed_slip_matrix,
    coordinate_law,
    make_probe,
)
from .slips.slip_map import SlipMap
from .slips.slip_records import SlipRecords
from .slips.surface_slips import SurfaceSlips

__all__ = ["add_iwan_interface", "IwanInterface"]

_log = logging.getLogger(__name__)
_HIDDEN = {"show": False, "drawSize": -1.0, "color": [-1.0, -1.0, -1.0, -1.0]}


class IwanInterface:
    """Handle of a multi-contact interface (made by :func:`add_iwan_interface`).

    Records (one row per accepted step, plus one at the start of each run):
    :attr:`time` (n,), :attr:`slip_history` and :attr:`force_history` (n, n_points), and the
    interface totals :attr:`stored_energy_history`, :attr:`dissipated_energy_history`,
    :attr:`work_history` (n,).
    """

    # set by add_iwan_interface after construction (annotations only; _axis, _uc_matrix and
    # _set_uc on the symbolic route)
    _offsets: list[float]  # slip offset of each point [m]
    _axis: tuple[float, float, float] | None  # unit axis of a position interface
    _uc_matrix: Any  # exudyn.symbolic Matrix of the committed slips
    _set_uc: Callable[[list[list[float]]], None]  # its SetMatrix

    def __init__(self, mbs, pairs, kind, route, record):
        self._mbs = mbs
        self._pairs = tuple(pairs)
        self._kind = kind
        self._route = route
        self._allow_adaptive_explicit = False
        self._rec = SlipRecords(len(pairs), record)
        self._objects = []
        self._connectors = []  # python route
        self._bank = None  # symbolic route
        self._states = []
        self._functions = []  # keep the symbolic functions alive
        self._overflows = []
        self._t_acc = -math.inf
        self._dispatcher = None
        self._read = None  # the slip map, once a run started
        self._map = None
        self._joints = ()
        self._stiffness = None  # linear springs carried by the interface, (n, 3) or None
        self._spring_objects = []  # python route: built-in springs carrying them

    # ------------------------------------------------------------------ read-only set-up
    @property
    def n_points(self) -> int:
        """Number of contact points."""
        return len(self._pairs)

    @property
    def markerPairs(self) -> tuple:
        """The marker pairs ``((m0, m1), ...)``, as given."""
        return self._pairs

    @property
    def route(self) -> str:
        """``"symbolic"`` (force law in Exudyn's symbolic expressions) or ``"python"``."""
        return self._route

    @property
    def objectNumbers(self) -> list:
        """The Exudyn connector objects, one per point."""
        return list(self._objects)

    @property
    def connectors(self) -> list:
        """The per-point :class:`IwanConnector` handles (python route; empty otherwise)."""
        return list(self._connectors)

    @property
    def overflow_times(self) -> np.ndarray:
        """Times [s] of accepted steps whose symbolic force read an older reversal point than
        the expression holds (not exact; raise ``depth``). Empty in a sound run.
        """
        return np.array(self._overflows)

    # ------------------------------------------------------------------ records
    def _check_running(self):
        d = self._dispatcher
        if d is not None and not d.reachable_from(_installed_post_step(self._mbs)):
            raise RuntimeError(
                "the interface's post-step dispatcher was replaced by another post-step user "
                "function, so its joints were not committed; set your post-step function "
                "before add_iwan_interface (it is then chained) and run again"
            )

    def _table(self):
        self._check_running()
        if self._route == "python":
            cs = self._connectors
            recs = [c.records() for c in cs]
            n = min(len(r["time"]) for r in recs)
            return {
                "time": recs[0]["time"][:n],
                "slip": np.stack([r["slip"][:n] for r in recs], axis=1),
                "force": np.stack([r["force"][:n] for r in recs], axis=1),
                "work": sum(r["work"][:n] for r in recs),
                "diss": sum(r["dissipated_energy"][:n] for r in recs),
            }
        return self._rec.table(self._bank)

    @property
    def n_records(self) -> int:
        """Number of recorded rows."""
        if self._route == "python":
            return min(c.n_records for c in self._connectors)
        return self._rec.n

    @property
    def time_history(self) -> np.ndarray:
        """Times of the accepted steps [s], shape (n,)."""
        return self._table()["time"]

    @property
    def slip_history(self) -> np.ndarray:
        """Slip of every point [m], shape (n, n_points)."""
        return self._table()["slip"]

    @property
    def force_history(self) -> np.ndarray:
        """Joint force of every point [N], shape (n, n_points) (resists positive slip)."""
        return self._table()["force"]

    @property
    def work_history(self) -> np.ndarray:
        """Total work done on the interface since the reset [J], shape (n,)."""
        return self._table()["work"]

    @property
    def dissipated_energy_history(self) -> np.ndarray:
        """Total energy dissipated by the interface since the reset [J], shape (n,)."""
        return self._table()["diss"]

    @property
    def stored_energy_history(self) -> np.ndarray:
        """Total elastic energy stored in the interface [J], shape (n,) (work - dissipated)."""
        tab = self._table()
        return tab["work"] - tab["diss"]

    def records(self) -> dict:
        """All records: ``time [s]`` (n,), ``slip [m]``, ``force [N]`` (n, n_points),
        ``stored_energy``, ``dissipated_energy``, ``work [J]`` (n,).
        """
        tab = self._table()
        return {
            "time": tab["time"],
            "slip": tab["slip"],
            "force": tab["force"],
            "stored_energy": tab["work"] - tab["diss"],
            "dissipated_energy": tab["diss"],
            "work": tab["work"],
        }

    def linear_energy(self) -> float:
        """Potential energy [J] of the linear springs given as ``stiffness`` at the current
        configuration (0 without them): Exudyn reports none for a user-function object.
        """
        return linear_energy(self._mbs, self._pairs, self._stiffness)

    def reset(self) -> None:
        """Return every joint to its virgin state and clear the records; energy recorders
        holding the interface start again. A solve that starts before the last accepted
        time does this by itself (see :meth:`IwanConnector.reset`).
        """
        if self._route == "python":
            for c in self._connectors:
                c.reset()
            return
        self._bank.reset()
        for s in self._states:
            s.set_stack([], [])
            s.set_branch(*VIRGIN)
        self._set_uc([[0.0] * self.n_points])
        self._rec.clear()
        self._overflows.clear()
        self._t_acc = -math.inf
        if self._dispatcher is not None:
            self._dispatcher.last_t = math.nan
            self._dispatcher.joint_reset(self)

    def __repr__(self) -> str:
        return (
            f"IwanInterface(n_points={self.n_points}, kind={self._kind!r}, "
            f"route={self._route!r}, records={self.n_records})"
        )

    # ------------------------------------------------------------------ per-step work
    def _refresh(self, mbs) -> None:
        """Start of a run: the affine map from the system coordinates to the slips."""
        self._map = m = SlipMap(mbs, self._pairs, self._kind, self._axis, self._offsets)
        self._read = m  # the dispatcher then checks for a re-assembly per step
        cols = np.unique(m.idx[m.coef != 0.0])
        self._cols = cols
        self._qsub = np.empty(cols.size)
        C = np.zeros((self.n_points, max(cols.size, 1)))
        for i in range(self.n_points):
            for k, cf in zip(m.idx[i], m.coef[i]):
                if cf != 0.0:
                    C[i, np.searchsorted(cols, k)] += cf
        self._C = C[:, : cols.size]
        self._ubuf = np.empty(self.n_points)
        self._surface = None
        self._generic = list(m.generic)
        if m.generic and self._kind == "position":
            sf = SurfaceSlips(mbs, self._pairs, m.generic, self._axis, self._offsets, m.q)
            if sf.points.size:
                self._surface = sf
                done = set(sf.points.tolist())
                self._generic = [i for i in m.generic if i not in done]

    def _slips(self) -> np.ndarray:
        """Accepted slips of all points (a buffer reused at every step)."""
        m, u = self._map, self._ubuf
        m.q.take(self._cols, out=self._qsub)
        np.dot(self._C, self._qsub, out=u)
        u += m.c
        sf = self._surface
        if sf is not None:
            u[sf.points] = sf.slips()
        if self._generic:
            m.marker_slips(u, self._generic)
        return u

    def _accept(self, t) -> None:
        u = self._slips()
        bank = self._bank
        if t < self._t_acc and self._rec.n:
            _log.warning(
                "Iwan interface: a new run starts at t=%g before the end (t=%g) of the "
                "history the joints hold; call reset() before a fresh run",
                t,
                self._t_acc,
            )
        events = bank.commit(u)
        if events.size:
            self._events(t, u, events)
        self._set_uc([u.tolist()])
        self._t_acc = t
        if self._rec.on:
            self._rec.append(t, u)

    def _events(self, t, u, events) -> None:
        """Points that left their branch: check the step (overflow), write their new branch
        and reversal stack to the symbolic variables.

        A walk pushes at most one reversal point and pops two per closed loop (one when it
        returns to the virgin curve or meets a reversal point within the tolerance), so a
        stack that did not get shorter means no closed loop: a plain reversal (one more
        point) or no change of the stack at all (same length). Only a step that closed a loop
        from a stack deeper than the law holds can have read a point the law does not hold,
        so only those are checked against the exact force, and an unchanged stack is not
        written again.
        """
        bank = self._bank
        states = self._states
        us_all, Fr_all = bank.us, bank.Fr
        idx = events.tolist()
        br = np.array((bank.bur, bank.bFr, bank.bc1, bank.bc2, bank.bound, bank.bdir))[:, events]
        br[2:4] *= br[5]  # s1 = c1 s, s2 = c2 s
        rest = br[5] == 0.0
        if rest.any():  # at rest: bound = u_c (see the law)
            br[4, rest] = u[events[rest]]
        br = br.T.tolist()
        for k, i in enumerate(idx):
            s = states[i]
            held = s.held
            us = us_all[i]
            n1 = len(us)
            if n1 != held:
                if n1 < held and held > s.depth and s.disagrees(float(u[i]), float(bank.force[i])):
                    self._overflows.append(t)
                    _log.warning(
                        "Iwan interface point %d at t=%g: the step closed loops beyond "
                        "the %d reversal points the symbolic law holds; that step's "
                        "force was not exact (raise depth)",
                        i,
                        t,
                        s.depth,
                    )
                s.set_stack(us, Fr_all[i])
            s.set_branch_values(br[k])


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
        :meth:`IwanInterface.linear_energy`.

    Returns
    -------
    IwanInterface
        Handle with the records and :meth:`IwanInterface.reset`.

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
