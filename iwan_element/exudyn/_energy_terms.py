"""What the energy balance books for each item of a user's Exudyn model, and its evaluation
from recorded states (see :mod:`iwan_element.exudyn.energy`).

Exudyn's equations of motion are ``M q'' + L(q, q') = f``: ``L`` (``ComputeItem(...,
ODE2LHS)``) holds the internal forces of bodies and connectors, ``f`` the loads. So the
energy that flows into a connector or into a body's internal forces over a step is
``(L_n + L_n+1) / 2 . (q_n+1 - q_n)`` (the trapezoidal rule in the coordinates, which for
the average-acceleration scheme - generalized-alpha at spectral radius 1 - is the
integrator's own discrete energy identity: it closes exactly on linear models), and the
work of a load likewise ``(f_n + f_n+1) / 2 . (p_n+1 - p_n)`` at its point (torques: the
trapezoidal rule of their power).

Per item:

* bodies with a ``KineticEnergy`` output: kinetic energy; rigid ones hold no other;
* bodies whose internal forces are elastic and dissipative only (a constant mass matrix:
  ANCF cables and beams, the 2-D geometrically exact beam, ``ObjectGenericODE2``): the work
  of ``L`` (strain energy and internal damping together, not split: Exudyn reports no
  strain energy for them);
* reduced flexible bodies (``ObjectFFRFreducedOrder``): strain energy ``q_m^T K q_m / 2``
  and the dissipation of the modal damping matrix, from the object's reduced matrices;
* connectors and contacts (springs, dampers, the user's own force functions): the work of
  ``L``; where Exudyn reports a ``PotentialEnergy`` the work splits into it and a
  dissipation;
* loads (``Coordinate``, ``ForceVector``, ``TorqueVector``, ``MassProportional``; with or
  without user functions, evaluated at each recorded time): their work;
* constraints: no work, unless their motion is prescribed (a user function): named;
* everything else (ODE1 objects, full FFRF bodies, kinematic trees, the 3-D geometrically
  exact beam, user functions of flexible bodies ...): named as not booked.
"""

from __future__ import annotations

import exudyn as exu
import numpy as np

__all__: list[str] = []

_OVT = exu.OutputVariableType
_CIT = exu.ComputeItemType
_CUR = exu.ConfigurationType.Current
_ORIGIN = [0.0, 0.0, 0.0]

RIGID = frozenset(
    {"Mass1D", "MassPoint", "MassPoint2D", "RigidBody", "RigidBody2D", "RotationalMass1D"}
)
LHS_BODIES = frozenset(
    {
        "ANCFCable2D",
        "ANCFCable",
        "ANCFBeam",
        "ANCFThinPlate",
        "BeamGeometricallyExact2D",
        "GenericODE2",
    }
)
LOADS = ("Coordinate", "ForceVector", "TorqueVector", "MassProportional")
#: Parameters of constraints whose motion is prescribed when set (a user function).
_PRESCRIBED = ("offsetUserFunction", "offsetUserFunction_t", "constraintUserFunction")


def _set(value) -> bool:
    """A user-function parameter as ``GetObject`` returns it: 0 when none is set."""
    return not (value is None or (isinstance(value, (int, float)) and value == 0))


def check_loads(mbs) -> None:
    """Refuse, when the recorder is attached, loads the balance cannot book."""
    for n in range(mbs.systemData.NumberOfLoads()):
        kind = mbs.GetLoad(n)["loadType"]
        if kind not in LOADS:
            raise ValueError(
                f"load {n} is a {kind} load; the energy balance books the work of "
                f"{', '.join(LOADS)} loads only"
            )


class Terms:
    """The bookkeeping of one assembled system: what is read for each item (resolved from
    the items' types and parameters; ``own``: the joints' objects, booked by their records).

    Attributes
    ----------
    missing : list of str
        The energies the balance cannot book, named.
    """

    def __init__(self, mbs, own):
        check_loads(mbs)
        self.mbs = mbs
        self.kinetic, self.lhs_bodies, self.reduced = [], [], []
        self.connectors = []  # (object, ODE2 indices, reports PotentialEnergy)
        self.missing = []
        sd = mbs.systemData
        for o in range(sd.NumberOfObjects()):
            if o not in own:
                self._classify(o, mbs.GetObject(o))
        self.loads = [self._load(n) for n in range(sd.NumberOfLoads())]

    def _classify(self, o, item) -> None:
        kind = item["objectType"]
        mbs = self.mbs
        what = f"object {o} ({kind}{', ' + item['name'] if item.get('name') else ''})"
        if kind == "Ground":
            return
        try:
            can = set(mbs.ComputeItem(exu.ObjectIndex(o)))
        except Exception:  # noqa: BLE001  (an item Exudyn computes nothing for)
            can = set()
        if _CIT.AlgebraicEquations in can or _CIT.ReactionForces in can:
            if any(_set(item.get(p, 0)) for p in _PRESCRIBED):
                self.missing.append(f"the work of the prescribed motion of {what}")
            return
        if kind.startswith(("Connector", "Contact")):
            if _CIT.ODE2LHS in can:
                self.connectors.append((o, _ltg(mbs, o), _reports(mbs, o)))
            else:
                self.missing.append(f"the energy of {what} (no ODE2 force to integrate)")
            return
        if kind in RIGID | LHS_BODIES | {"FFRFreducedOrder"} and _has_kinetic(mbs, o):
            self.kinetic.append(o)
        elif kind in RIGID | LHS_BODIES | {"FFRFreducedOrder"}:
            self.missing.append(f"the kinetic energy of {what}")
        if kind in LHS_BODIES:
            if kind == "GenericODE2" and _set(item.get("massMatrixUserFunction", 0)):
                self.missing.append(f"the internal energy of {what} (mass matrix user function)")
            else:
                self.lhs_bodies.append((o, _ltg(mbs, o)))
        elif kind == "FFRFreducedOrder":
            self.reduced.append(_reduced(mbs, o, item))
            for uf in ("forceUserFunction", "massMatrixUserFunction"):
                if _set(item.get(uf, 0)):
                    self.missing.append(f"the work of the {uf} of {what}")
        elif kind not in RIGID:
            self.missing.append(f"the energy of {what} (a {kind} is not booked)")

    def _load(self, n):
        mbs = self.mbs
        ld = mbs.GetLoad(n)
        kind, m = ld["loadType"], int(ld["markerNumber"])
        body = None
        if kind == "MassProportional":
            body = int(mbs.GetMarker(m)["bodyNumber"])
        return n, kind, m, bool(ld.get("bodyFixed", False)), body

    # ------------------------------------------------------------------ evaluation
    def state(self) -> dict:
        """Every energy quantity at the current state of the system (set by the caller):
        levels (kinetic, elastic) and the generalized forces and displacements whose
        trapezoidal products give the works.
        """
        mbs = self.mbs
        q = mbs.systemData.GetODE2Coordinates(_CUR)
        qt = mbs.systemData.GetODE2Coordinates_t(_CUR)
        kin = sum(
            float(mbs.GetObjectOutputBody(o, _OVT.KineticEnergy, localPosition=_ORIGIN))
            for o in self.kinetic
        )
        ela, pairs = 0.0, []  # pairs (force, displacement) for trapezoidal works
        for o, idx in self.lhs_bodies:
            pairs.append(("internal", _lhs(mbs, o), q[idx]))
        for qi, K, D in self.reduced:
            qm = q[qi]
            ela += 0.5 * float(qm @ (K @ qm))
            if D is not None:
                pairs.append(("damping", D @ qt[qi], qm))
        pot = []
        for o, idx, pe in self.connectors:
            pairs.append((o, _lhs(mbs, o), q[idx]))
            pot.append(float(mbs.GetObjectOutput(o, _OVT.PotentialEnergy)) if pe else 0.0)
        ext = [
            self._load_pair(n, kind, m, fixed, body, q, qt)
            for n, kind, m, fixed, body in self.loads
        ]
        return {"kinetic": kin, "elastic": ela, "pairs": pairs, "potential": pot, "loads": ext}

    def _load_pair(self, n, kind, m, fixed, body, q, qt):
        """``(force, displacement, power?)`` of a load at the current state."""
        mbs = self.mbs
        value = np.atleast_1d(np.asarray(mbs.GetLoadValues(n), dtype=float))
        if kind == "Coordinate":
            return value, np.atleast_1d(mbs.GetMarkerOutput(m, _OVT.Coordinates)), None
        if kind == "ForceVector":
            if fixed:
                A = np.asarray(mbs.GetMarkerOutput(m, _OVT.RotationMatrix)).reshape(3, 3)
                value = A @ value
            return value, np.asarray(mbs.GetMarkerOutput(m, _OVT.Position)), None
        if kind == "TorqueVector":
            w = mbs.GetMarkerOutput(m, _OVT.AngularVelocityLocal if fixed else _OVT.AngularVelocity)
            return value, None, float(value @ np.asarray(w))
        J = np.asarray(mbs.ComputeItem(exu.ObjectIndex(body), _CIT.MassWeightedPositionJacobian))
        idx = _ltg(mbs, body)
        return J.T @ value[: J.shape[0]], q[idx], None


def _ltg(mbs, o):
    return np.array(list(mbs.systemData.GetObjectLTGODE2(o)), dtype=np.intp)


def _lhs(mbs, o):
    return np.asarray(mbs.ComputeItem(exu.ObjectIndex(o), _CIT.ODE2LHS), dtype=float)


def _reports(mbs, o) -> bool:
    try:
        mbs.GetObjectOutput(o, _OVT.PotentialEnergy)
    except Exception:  # noqa: BLE001  (Exudyn raises RuntimeError or SystemError)
        return False
    return True


def _has_kinetic(mbs, o) -> bool:
    try:
        mbs.GetObjectOutputBody(o, _OVT.KineticEnergy, localPosition=_ORIGIN)
    except Exception:  # noqa: BLE001
        return False
    return True


def _reduced(mbs, o, item):
    """(modal coordinate indices, reduced stiffness, reduced damping or None) of a reduced
    flexible body: its second node holds the modal coordinates.
    """
    node = int(item["nodeNumbers"][1])
    idx = np.array(list(mbs.systemData.GetNodeLTGODE2(node)), dtype=np.intp)
    K, D = (_dense(item[k], idx.size) for k in ("stiffnessMatrixReduced", "dampingMatrixReduced"))
    return idx, K, (D if np.any(D) else None)


def _dense(m, n) -> np.ndarray:
    """A matrix parameter as an (n, n) array (Exudyn returns a ``MatrixContainer``)."""
    if isinstance(m, exu.MatrixContainer):
        m = m.Convert2DenseMatrix()
    a = np.asarray(m, dtype=float)
    return a if a.size else np.zeros((n, n))


def trapezoid(f, x) -> np.ndarray:
    """Cumulative ``sum (f_k + f_k+1) / 2 . (x_k+1 - x_k)`` over rows (shape (n,))."""
    if len(f) < 2:
        return np.zeros(len(f))
    inc = np.einsum("ij,ij->i", 0.5 * (f[1:] + f[:-1]), np.diff(x, axis=0))
    return np.concatenate([[0.0], np.cumsum(inc)])


def power_work(p, t) -> np.ndarray:
    """Cumulative trapezoidal integral of a power ``p`` over times ``t``."""
    if len(p) < 2:
        return np.zeros(len(p))
    return np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))])
