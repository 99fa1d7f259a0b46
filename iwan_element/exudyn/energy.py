"""Energy balance of a user's own Exudyn model with Iwan connectors or interfaces.

:func:`record_energy` attaches a recorder to the connectors' post-step dispatcher (called
after the joints; a post-step function the user sets later does not drop it). Per accepted
step it copies the time and the ODE2 coordinates and velocities (two byte copies:
about half a microsecond a step, less than the connector itself); the
energies are evaluated from these states when :meth:`EnergyRecorder.balance` is called,
by setting each recorded state back into the system and reading what Exudyn reports
(:mod:`._energy_terms`: kinetic energy of the bodies, strain energy of reduced flexible
bodies, the work of internal forces of beams and of every connector - springs, dampers,
the user's own force functions - with their potential energy where Exudyn reports one, the
work of every load, gravity included). The joints' stored and dissipated energy come from
their own records (exact replay of the recorded slips, dashpots included). The balance

    kinetic + elastic + dissipated in dampers + work into other connectors and bodies
    + joint stored + joint dissipated - external work = its initial value

is judged against the joints' own energy: the largest of their total work and
dissipation over the run (:attr:`.EnergyBalance.scale`), not the model's total energy (a
spinning rotor's kinetic energy would hide any error). Whatever the balance cannot book
(a prescribed motion, an ODE1 object ...) is named in :attr:`.EnergyBalance.not_booked`
and the balance is then not usable; loads of another type are refused by
:func:`record_energy`, before the solve.

The works are trapezoidal sums in the coordinates, the generalized-alpha method's own
energy identity at spectral radius 1 (it closes exactly on a linear model); numerical
damping (spectral radius below 1) dissipates energy that nothing books, and the verdict
says so.
"""

from __future__ import annotations

import logging
from array import array

import exudyn as exu
import numpy as np

from ._dispatch import _dispatcher_for, _installed_post_step
from ._energy_terms import Terms, check_loads, power_work, trapezoid
from .energy_balance import BALANCE_TOLERANCE, EnergyBalance

__all__ = ["record_energy", "EnergyRecorder"]

_log = logging.getLogger(__name__)
_CUR = exu.ConfigurationType.Current


def record_energy(mbs, joints) -> EnergyRecorder:
    """Record the energy balance of a model at every accepted step.

    Call it after the joints were added (:func:`create_iwan_connector`,
    :func:`add_iwan_connector`, :func:`add_iwan_interface`) and before ``mbs.SolveDynamic``;
    read :meth:`EnergyRecorder.balance` after the run. A new run (a solve that starts
    before the last accepted time) and a joint's ``reset()`` start the recording again.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system holding the joints.
    joints : IwanCartesianConnector, IwanConnector, IwanInterface or a sequence of them
        Every joint of the model (their stored and dissipated energies enter the balance).

    Returns
    -------
    EnergyRecorder

    Raises
    ------
    ValueError
        ``mbs`` is not an Exudyn system, ``joints`` is empty or holds something else than
        joints of this system, or the model has a load the balance cannot book.
    """
    from .cartesian import IwanCartesianConnector
    from .connector import IwanConnector
    from .interface_handle import IwanInterface

    kinds = (IwanConnector, IwanInterface, IwanCartesianConnector)
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    if isinstance(joints, kinds):
        joints = [joints]
    joints = list(joints) if not isinstance(joints, (str, bytes)) else []
    if not joints or not all(isinstance(j, kinds) for j in joints):
        raise ValueError(
            "joints must be an IwanCartesianConnector, IwanConnector or "
            "IwanInterface, or a non-empty sequence of them (from "
            "create_iwan_connector / add_iwan_connector / add_iwan_interface)"
        )
    flat = []
    for j in joints:
        flat += list(j.connectors) if isinstance(j, IwanCartesianConnector) else [j]
    if any(j._mbs is not mbs for j in flat):
        raise ValueError("joints must belong to mbs (a joint of another system was given)")
    check_loads(mbs)
    return EnergyRecorder(mbs, flat)


class EnergyRecorder:
    """Records the states of a run and books its energy balance (made by
    :func:`record_energy`).
    """

    def __init__(self, mbs, joints):
        self._mbs = mbs
        self._joints = tuple(joints)
        self._t = array("d")
        self._q = array("d")
        self._v = array("d")
        self._n = None  # coordinates per recorded state
        self._views = None
        ts, qs, vs = self._t, self._q, self._v

        def record(t):
            if not ts or t != ts[-1]:
                views = self._views
                if views is None:
                    views = self._refresh(mbs)
                ts.append(t)
                qs.frombytes(views[0].tobytes())
                vs.frombytes(views[1].tobytes())

        self._record = record
        disp = _dispatcher_for(mbs)
        if not disp.reachable_from(_installed_post_step(mbs)):
            disp.install(mbs)
        disp.add_recorder(self)
        self._n0 = [j.n_records for j in self._joints]

    def _refresh(self, mbs):
        """Views of the system coordinates (taken at the start of every run; an ``Assemble``
        may move them); a run with another number of coordinates starts the recording
        again.
        """
        sd = mbs.systemData
        q = sd.GetODE2Coordinates(_CUR, copy=False)
        if self._n is not None and q.size != self._n and len(self._t):
            _log.warning(
                "the system now has %d ODE2 coordinates instead of %d: the energy "
                "recording starts again",
                q.size,
                self._n,
            )
            self._clear()
        self._n = q.size
        self._views = (q, sd.GetODE2Coordinates_t(_CUR, copy=False))
        return self._views

    def _clear(self) -> None:
        for a in (self._t, self._q, self._v):
            del a[:]
        self._n0 = [j.n_records for j in self._joints]

    def _joint_reset(self, joint) -> None:
        """A joint was reset (by the user or by a new run): start again."""
        mine = [j for j in self._joints if j is joint or joint in getattr(j, "connectors", ())]
        inner = getattr(joint, "connectors", ())
        if mine or any(c in self._joints for c in inner):
            self._clear()

    @property
    def n_records(self) -> int:
        """Recorded states."""
        return len(self._t)

    def balance(self, *, tolerance: float = BALANCE_TOLERANCE) -> EnergyBalance:
        """The energy balance of what was recorded so far (see the module docstring).

        Parameters
        ----------
        tolerance : float, keyword-only
            Largest balance error [-], relative to the joints' own energy, of a usable run
            (default 1e-3).

        Raises
        ------
        RuntimeError
            Nothing was recorded, or the joints' records are not in step with the recorder.
        """
        if not len(self._t):
            raise RuntimeError("nothing recorded: run mbs.SolveDynamic after record_energy")
        if not (np.isfinite(tolerance) and 0 < tolerance < 1):
            raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
        t = np.array(self._t)
        stored, dissipated = self._joint_energies(t)
        own: set[int] = set()  # booked by the joints themselves
        for j in self._joints:
            own.update(
                int(o)
                for o in (j.objectNumbers if hasattr(j, "objectNumbers") else [j.objectNumber])
            )
            own.update(int(o) for o in getattr(j, "_spring_objects", ()))  # linear_energy
        terms = Terms(self._mbs, own)
        levels = self._evaluate(terms, t)
        return EnergyBalance(
            t=t,
            joint_stored=stored,
            joint_dissipated=dissipated,
            not_booked=tuple(terms.missing),
            notes=self._notes(),
            tolerance=float(tolerance),
            **levels,
        )

    def _joint_energies(self, t):
        stored = np.zeros(len(t))
        dissipated = np.zeros(len(t))
        for j, n0 in zip(self._joints, self._n0):
            tj = j.time_history[n0:]
            if len(tj) != len(t) or not np.allclose(tj, t, rtol=0, atol=1e-12 * max(1, t[-1])):
                raise RuntimeError(
                    "the joints' records are not in step with the energy "
                    "recorder (a joint recorded without it: record=False?)"
                )
            stored += j.stored_energy_history[n0:]
            dissipated += j.dissipated_energy_history[n0:]
        return stored, dissipated

    def _evaluate(self, terms, t) -> dict:
        """Every term at every recorded state (set into the system, then restored)."""
        mbs = self._mbs
        sd = mbs.systemData
        n = self._n
        Q = np.frombuffer(self._q, dtype=float).reshape(-1, n)
        V = np.frombuffer(self._v, dtype=float).reshape(-1, n)
        keep = (sd.GetODE2Coordinates(_CUR), sd.GetODE2Coordinates_t(_CUR), sd.GetTime())
        linear = [j.linear_energy for j in self._joints if hasattr(j, "linear_energy")]
        states = []
        try:
            for k in range(len(t)):
                sd.SetODE2Coordinates(Q[k], _CUR)
                sd.SetODE2Coordinates_t(V[k], _CUR)
                sd.SetTime(float(t[k]))
                st = terms.state()
                st["elastic"] += sum(f() for f in linear)
                states.append(st)
        finally:
            sd.SetODE2Coordinates(keep[0], _CUR)
            sd.SetODE2Coordinates_t(keep[1], _CUR)
            sd.SetTime(keep[2])
        return _assemble(states, t)

    def _notes(self) -> tuple:
        """What the last solve's settings say about the balance (numerical damping), as the
        dispatcher saw them when the solve started (``SolveDynamic`` sets its ``solverType``
        into the settings only while it runs).
        """
        info = _dispatcher_for(self._mbs).solve_info
        if info is None:
            return ()
        kind, solver, rho = info
        if (
            kind == "dynamicSolver"
            and solver == exu.DynamicSolverType.GeneralizedAlpha
            and rho < 1.0
        ):
            return (
                f"the solver damps numerically (generalized-alpha, spectralRadius "
                f"{rho:g} < 1): energy that no item books; set 1 (or use "
                "TrapezoidalIndex2) for a balance",
            )
        return ()


def _assemble(states, t) -> dict:
    """The per-step states stacked into the balance's histories."""
    n = len(states)
    kinetic = np.array([s["kinetic"] for s in states])
    elastic = np.array([s["elastic"] for s in states])
    internal = np.zeros(n)
    dampers = np.zeros(n)
    connectors = np.zeros(n)
    c = 0  # connectors in the order of their pairs
    for i, (tag, _, _) in enumerate(states[0]["pairs"]):
        f = np.array([s["pairs"][i][1] for s in states])
        x = np.array([s["pairs"][i][2] for s in states])
        w = trapezoid(f, x)
        if tag == "internal":
            internal += w
        elif tag == "damping":
            dampers += w
        else:
            pe = np.array([s["potential"][c] for s in states])
            c += 1
            if np.any(pe):
                elastic += pe
                dampers += w - (pe - pe[0])
            else:
                connectors += w
    external = np.zeros(n)
    for i in range(len(states[0]["loads"])):
        f = np.array([np.atleast_1d(s["loads"][i][0]) for s in states])
        if states[0]["loads"][i][1] is None:
            external += power_work(np.array([s["loads"][i][2] for s in states]), t)
        else:
            external += trapezoid(f, np.array([np.atleast_1d(s["loads"][i][1]) for s in states]))
    return {
        "kinetic": kinetic,
        "elastic": elastic,
        "internal_work": internal,
        "damper_dissipation": dampers,
        "connector_work": connectors,
        "external_work": external,
    }
