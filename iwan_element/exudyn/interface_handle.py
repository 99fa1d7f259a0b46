"""The handle of a multi-contact Iwan interface (:func:`.interface.add_iwan_interface`): its
set-up, its records (slips per accepted step; forces and energies replayed from them), its
reset, and the per-step work of the symbolic route (the accepted slips of all points, one
commit of the joint bank, the symbolic variables of the points that left their branch).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..core.joint_bank import IwanJointBank
from ._dispatch import _installed_post_step
from .laws.interface_springs import linear_energy
from .laws.symbolic_law import VIRGIN
from .slips.slip_map import SlipMap
from .slips.slip_records import SlipRecords
from .slips.surface_slips import SurfaceSlips

__all__ = ["IwanInterface"]

_log = logging.getLogger(__name__)


class IwanInterface:
    """Handle of a multi-contact interface (made by :func:`.interface.add_iwan_interface`).

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
    def bank(self) -> IwanJointBank | None:
        """The points' committed state, an :class:`~iwan_element.IwanJointBank` (symbolic
        route; None on the python route). Read it, never commit to it: the interface commits
        once per accepted step.
        """
        return self._bank

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
