"""Energy balance of a user's own Exudyn model with Iwan connectors or interfaces.

:func:`record_energy` attaches a recorder behind the connectors' post-step dispatcher: at
every accepted step, after the joints are committed, it reads

* the kinetic energy of every body that reports one (Exudyn's ``KineticEnergy`` output:
  mass points, ``Mass1D``, rigid bodies, beam elements);
* the elastic energy of every object that reports one (``PotentialEnergy``: springs,
  spring-dampers, beams), except the joints' own objects (a user-function or symbolic
  connector reports none), plus the linear springs an interface carries
  (:meth:`IwanInterface.linear_energy`);
* the power of every load (``LoadCoordinate``: load times the coordinate's rate;
  ``LoadForceVector``: force dot the marker's velocity), integrated by the trapezoidal rule
  (exact for the generalized-alpha method at spectral radius 1 on a linear model).

The joints' stored and dissipated energy come from the connectors' own records (exact
replay of the recorded slips). The balance (``docs/equations.md`` section 5 for the joint's
energies) is

    kinetic + elastic + joint stored + joint dissipated - external work = initial energy,

and :class:`EnergyBalance` reports its error relative to the largest energy level of the
run. Damping of the user's own spring-dampers and the work of prescribed motions are not
booked: they appear as an error, so a model with them will not balance.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import exudyn as exu
import numpy as np

from ..core.result_shape import ResultShape, panels, table_lines
from ._dispatch import _dispatcher_for, _installed_post_step

__all__ = ["record_energy", "EnergyRecorder", "EnergyBalance"]

_log = logging.getLogger(__name__)
_OVT = exu.OutputVariableType
_ORIGIN = [0.0, 0.0, 0.0]

#: Largest relative balance error of a run that is a success (the connectors' own tests
#: close the balance of a 1-DOF model to 1e-4 at about 190 steps per period).
BALANCE_TOLERANCE = 1e-3


def _probe(call) -> bool:
    try:
        call()
    except Exception:      # noqa: BLE001  (Exudyn raises RuntimeError or SystemError)
        return False
    return True


def record_energy(mbs, joints) -> "EnergyRecorder":
    """Record the energy balance of a model at every accepted step.

    Call it after the joints were added (:func:`add_iwan_connector`,
    :func:`add_iwan_interface`) and before ``mbs.SolveDynamic``; read
    :meth:`EnergyRecorder.balance` after the run.

    Parameters
    ----------
    mbs : exudyn.MainSystem
        The system holding the joints.
    joints : IwanConnector, IwanInterface or a sequence of them
        Every joint of the model (their stored and dissipated energies enter the balance).

    Returns
    -------
    EnergyRecorder

    Raises
    ------
    ValueError
        ``mbs`` is not an Exudyn system, ``joints`` is empty or holds something else than
        connectors and interfaces of this system.
    """
    from .connector import IwanConnector
    from .interface import IwanInterface
    if not isinstance(mbs, exu.MainSystem):
        raise ValueError(f"mbs must be an exudyn.MainSystem, got {type(mbs).__name__}")
    if isinstance(joints, (IwanConnector, IwanInterface)):
        joints = [joints]
    joints = list(joints) if not isinstance(joints, (str, bytes)) else []
    if not joints or not all(isinstance(j, (IwanConnector, IwanInterface)) for j in joints):
        raise ValueError("joints must be an IwanConnector or IwanInterface, or a non-empty "
                         "sequence of them (from add_iwan_connector / add_iwan_interface)")
    if any(j._mbs is not mbs for j in joints):
        raise ValueError("joints must belong to mbs (a connector of another system was given)")
    return EnergyRecorder(mbs, joints)


class EnergyRecorder:
    """Reads the model's energies at every accepted step (made by :func:`record_energy`)."""

    def __init__(self, mbs, joints):
        self._mbs = mbs
        self._joints = tuple(joints)
        self._rows = []               # (t, kinetic, elastic, external power)
        self._bodies = self._springs = self._loads = None
        disp = _dispatcher_for(mbs)
        if not disp.reachable_from(_installed_post_step(mbs)):
            disp.install(mbs)
        previous = disp.chained

        def energy_post_step(mbs_, t):
            if not self._rows or t != self._rows[-1][0]:
                self._rows.append(self._read(t))
            return True if previous is None else previous(mbs_, t)

        disp.chained = energy_post_step
        self._n0 = [j.n_records for j in self._joints]

    def _classify(self) -> None:
        """Which objects report kinetic or elastic energy, which loads do work (once)."""
        mbs = self._mbs
        own = set()
        for j in self._joints:
            own.update(j.objectNumbers if hasattr(j, "objectNumbers") else [j.objectNumber])
        objs = [o for o in range(mbs.systemData.NumberOfObjects()) if o not in own]
        self._bodies = [o for o in objs if _probe(lambda o=o: mbs.GetObjectOutputBody(
            o, _OVT.KineticEnergy, localPosition=_ORIGIN))]
        self._springs = [o for o in objs if _probe(lambda o=o: mbs.GetObjectOutput(
            o, _OVT.PotentialEnergy))]
        self._loads = []
        for n in range(mbs.systemData.NumberOfLoads()):
            kind = mbs.GetLoad(n)["loadType"]
            if kind not in ("Coordinate", "ForceVector"):
                raise ValueError(f"load {n} is a {kind} load; the energy balance books the "
                                 "work of Coordinate and ForceVector loads only")
            self._loads.append((n, mbs.GetLoad(n)["markerNumber"], kind))

    def _read(self, t) -> tuple:
        mbs = self._mbs
        if self._bodies is None:
            self._classify()
        kin = sum(float(mbs.GetObjectOutputBody(o, _OVT.KineticEnergy, localPosition=_ORIGIN))
                  for o in self._bodies)
        ela = sum(float(mbs.GetObjectOutput(o, _OVT.PotentialEnergy)) for o in self._springs)
        ela += sum(j.linear_energy() for j in self._joints if hasattr(j, "linear_energy"))
        power = 0.0
        for n, m, kind in self._loads:
            value = np.asarray(mbs.GetLoadValues(n), dtype=float)
            rate = _OVT.Coordinates_t if kind == "Coordinate" else _OVT.Velocity
            power += float(np.dot(value.ravel(),
                                  np.asarray(mbs.GetMarkerOutput(m, rate)).ravel()))
        return (float(t), kin, ela, power)

    def balance(self, *, tolerance: float = BALANCE_TOLERANCE) -> "EnergyBalance":
        """The energy balance of what was recorded so far.

        Parameters
        ----------
        tolerance : float, keyword-only
            Largest relative error [-] of a balance that is a success (default 1e-3).

        Raises
        ------
        RuntimeError
            Nothing was recorded, or the joints' records are not in step with the recorder
            (a joint was reset, or recorded before the recorder was attached).
        """
        if not self._rows:
            raise RuntimeError("nothing recorded: run mbs.SolveDynamic after record_energy")
        if not (np.isfinite(tolerance) and 0 < tolerance < 1):
            raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
        rows = np.array(self._rows)
        t = rows[:, 0]
        stored = np.zeros(len(t))
        dissipated = np.zeros(len(t))
        for j, n0 in zip(self._joints, self._n0):
            tj = j.time_history[n0:]
            if len(tj) != len(t) or not np.allclose(tj, t, rtol=0, atol=1e-12 * max(1, t[-1])):
                raise RuntimeError("the joints' records are not in step with the energy "
                                   "recorder (a joint was reset or run without it)")
            stored += j.stored_energy_history[n0:]
            dissipated += j.dissipated_energy_history[n0:]
        power = rows[:, 3]
        work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
        return EnergyBalance(t=t, kinetic=rows[:, 1], elastic=rows[:, 2], joint_stored=stored,
                             joint_dissipated=dissipated, external_work=work,
                             tolerance=float(tolerance))


@dataclass(frozen=True, eq=False, kw_only=True)
class EnergyBalance(ResultShape):
    """Energies of a run [J] at the accepted steps (from :meth:`EnergyRecorder.balance`).

    Attributes
    ----------
    t : ndarray
        Times [s].
    kinetic, elastic, joint_stored, joint_dissipated, external_work : ndarray
        Kinetic energy of the bodies, elastic energy of the other objects, the joints'
        stored and dissipated energy, and the work of the loads since the first step [J].
    tolerance : float
        Largest relative error [-] of a successful balance.
    """

    t: np.ndarray
    kinetic: np.ndarray
    elastic: np.ndarray
    joint_stored: np.ndarray
    joint_dissipated: np.ndarray
    external_work: np.ndarray
    tolerance: float

    @property
    def total(self) -> np.ndarray:
        """Energy held or dissipated minus the external work [J] (constant when balanced)."""
        return (self.kinetic + self.elastic + self.joint_stored + self.joint_dissipated
                - self.external_work)

    @property
    def scale(self) -> float:
        """The run's energy level [J]: the largest of the energies' magnitudes."""
        parts = (self.kinetic, self.elastic, self.joint_stored, self.joint_dissipated,
                 self.external_work)
        return float(max(np.max(np.abs(p)) for p in parts))

    def error(self) -> np.ndarray:
        """Relative balance error over time [-]: ``(total - total[0]) / scale``."""
        scale = self.scale
        return (self.total - self.total[0]) / scale if scale > 0 else np.zeros(len(self.t))

    @property
    def max_error(self) -> float:
        """Largest relative balance error [-]."""
        return float(np.max(np.abs(self.error())))

    @property
    def success(self) -> bool:
        """True when the balance closes within ``tolerance``."""
        return bool(self.max_error <= self.tolerance)

    def failure_reasons(self) -> tuple:
        if self.success:
            return ()
        return (f"the energy balance is off by {self.max_error:.2e} of the run's energy "
                f"(tolerance {self.tolerance:.0e}): a step too large, a damper or a "
                "prescribed motion that is not booked",)

    def _final(self) -> dict:
        return {"kinetic": self.kinetic[-1], "elastic": self.elastic[-1],
                "joint_stored": self.joint_stored[-1],
                "joint_dissipated": self.joint_dissipated[-1],
                "external_work": self.external_work[-1]}

    def _tables(self) -> list:
        history = ("energies over time", ("t [s]", "kinetic [J]", "elastic [J]",
                                          "joint_stored [J]", "joint_dissipated [J]",
                                          "external_work [J]", "error [-]"),
                   list(zip(*(map(float, a) for a in (
                       self.t, self.kinetic, self.elastic, self.joint_stored,
                       self.joint_dissipated, self.external_work, self.error())))))
        rows = [(k.replace("_", " "), "J", v) for k, v in self._final().items()]
        stats = [("steps", "-", len(self.t)), ("energy level", "J", self.scale),
                 ("largest balance error", "-", self.max_error),
                 ("tolerance", "-", self.tolerance)]
        return [history, ("energies at the end", ("quantity", "unit", "value"), rows),
                ("balance", ("quantity", "unit", "value"), stats)]

    def report(self) -> str:
        lines = [self.verdict(), f"Energy balance over {len(self.t)} steps, "
                 f"t = {self.t[0]:.4g} to {self.t[-1]:.4g} s"]
        lines += table_lines([("at the end", "<20"), ("[J]", "12.5g")],
                             [(k.replace("_", " "), v) for k, v in self._final().items()])
        lines.append(f"  largest balance error {self.max_error:.2e} [-] of "
                     f"{self.scale:.4g} J (tolerance {self.tolerance:.0e})")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"success": self.success, "max_error": self.max_error, "scale": self.scale,
                "tolerance": self.tolerance, "n_steps": len(self.t),
                "final": {k: float(v) for k, v in self._final().items()},
                "warnings": list(self.warnings)}

    def plot(self, ax=None) -> list:
        (a,) = panels(ax, 1)
        out = []
        for name in ("kinetic", "elastic", "joint_stored", "joint_dissipated", "external_work"):
            out += a.plot(self.t, getattr(self, name), label=name.replace("_", " "))
        out += a.plot(self.t, self.total, "k--", label="balance")
        a.set_xlabel("t [s]")
        a.set_ylabel("energy [J]")
        a.legend(fontsize="small")
        return out

