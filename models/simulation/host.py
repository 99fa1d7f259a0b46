"""A specimen in Exudyn: its linear system as one generic body, the joints as Iwan elements.

Every specimen (1-D Timoshenko beams and reduced solid bodies alike) is linear bodies in
small vibration: ``M``, ``K0`` (bodies, normal contact springs, the setup's springs) on the
free coordinates ``x`` of its :class:`~iwan_element.models.linear.LinearSystem`, and ``G``,
the tangential slips of the contact points. The slips, and the rows of any ports a run needs
(the excitation point a force acts on, a prescribed grip coordinate), are made coordinates:
``x = T z`` with ``T = [N, R^+]`` for the port rows ``R = [G; ports]``, ``N`` an orthonormal
basis of the null space of ``R`` and ``R^+`` its pseudo-inverse (``R T = [0 | I]``,
``T^-1 = [N^T; R]``), so ``z = (eta, u, p)``: the body coordinates no port reads, the slips
``u = G x`` and the ports ``p``. ``M' = T^T M T`` and ``K' = T^T K0 T`` (both full: the
basis is orthogonal, ``N^T R^+ = 0``, not ``M``-orthogonal). One Exudyn
``NodeGenericODE2`` carries every ``z``; one ``ObjectGenericODE2`` carries ``M'``, ``K'`` and
the floor's modal damping matrix
``C' = T^T C T`` (:mod:`~iwan_element.models.reduced.damping`), and each tangential Iwan element is
a coordinate-marker pair (the slip coordinate against a ground coordinate) of
:func:`iwan_element.exudyn.add_iwan_interface`: the compiled per-point law, one commit of all
points per accepted step and the energy records. The interface force ``-F_i`` acts on slip
coordinate ``u_i``, which is ``G^T F`` in ``x``. A force ``F(t)`` on a port coordinate ``p_j``
is the force ``F R_j^T`` in ``x`` (its virtual work is ``F dp_j``); a prescribed port is a
coordinate constraint, whose force is the reaction. With ``tangential="linear"`` a built-in
``CoordinateSpringDamper`` of stiffness ``KT_i`` replaces each Iwan element (the linear
reference of cost and decay).

The bodies' Jacobian ``f_q K' + f_v C'`` is handed to Exudyn as it is: the object carries a
``jacobianUserFunction`` (which adds nothing), because without one Exudyn takes an
``ObjectGenericODE2``'s Jacobian by finite differences, one residual of the whole object per
coordinate and per derivative (about ``4 n^3`` operations: measured 124 ms a Jacobian at
``n = 276`` against 8.5 ms with the function, on a loaded machine; ``docs/transient_cost.md``).

The energy is ``1/2 v'^T M' v'`` (kinetic), ``1/2 z^T T^T Kb T z`` (the bodies' strain) and
``1/2 z^T T^T (K0 - Kb) T z`` plus the linear tangential springs' (springs). The system
(a few hundred coordinates, a full ``K'``) is solved with Exudyn's dense LU.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import exudyn as exu
import numpy as np
import scipy.linalg as sla
from exudyn.itemInterface import (
    CoordinateConstraint,
    LoadCoordinate,
    MarkerNodeCoordinate,
    NodeGenericODE2,
    NodePointGround,
    ObjectConnectorCoordinateSpringDamper,
    ObjectGenericODE2,
)

from iwan_element import IwanJoint
from iwan_element.exudyn import IwanInterface, add_iwan_interface

from ..linear.system import LinearSystem
from ..reduced.damping import floor_damping
from ..reduced.dispatch import contact_points, linear_system
from ..solid.specimen import SolidSpecimen
from ..specimens.contact import ContactPoints
from ..specimens.specimen import Specimen

__all__ = ["port_basis", "HostModel", "build_host"]


def port_basis(R) -> tuple:
    """``(T, T_inv, n_eta)``: the basis ``T = [N, R^+]`` whose last ``R.shape[0]``
    coordinates are the rows ``R x`` (module docstring), its inverse ``[N^T; R]`` and the
    number of the other coordinates. ``R`` must have full row rank (ValueError).
    """
    R = np.asarray(R, float)
    N = sla.null_space(R)
    if N.shape[1] != R.shape[1] - R.shape[0]:
        raise ValueError(
            f"the port rows (slips and ports) must have full row rank "
            f"{R.shape[0]}, got rank {R.shape[1] - N.shape[1]}: two of them are "
            "dependent"
        )
    T = np.hstack([N, np.linalg.pinv(R)])
    return T, np.vstack([N.T, R]), N.shape[1]


@dataclass(eq=False, repr=False)
class HostModel:
    """The assembled Exudyn system of a specimen (:func:`build_host`).

    Attributes: ``specimen``, ``SC``, ``mbs``, ``L`` (its LinearSystem), ``points`` (the
    contact points), ``interface`` (the IwanInterface; None with linear springs), ``T``,
    ``T_inv``, ``n_eta`` (module docstring), ``node`` (the NodeGenericODE2), ``Mz``, ``Kb``,
    ``Ks`` (mass, bodies' and springs' stiffness in ``z``), ``floor_C`` (the floor's damping
    in ``z``, or None), ``ground`` (a ground coordinate marker), ``ports`` (name -> index of
    its coordinate in ``z``).
    """

    # eq=False, repr=False: an assembled system compares and hashes by identity, and its
    # repr does not print the matrices
    specimen: Specimen | SolidSpecimen
    SC: Any  # exudyn.SystemContainer
    mbs: Any  # exudyn.MainSystem
    L: LinearSystem
    points: ContactPoints
    interface: IwanInterface | None
    T: np.ndarray
    T_inv: np.ndarray
    n_eta: int
    node: Any  # exudyn.NodeIndex
    Mz: np.ndarray
    Kb: np.ndarray
    Ks: np.ndarray
    floor_C: np.ndarray | None
    ground: Any  # exudyn.MarkerIndex
    ports: dict[str, int]

    def port_marker(self, name: str) -> int:
        """A new marker on port ``name``'s coordinate."""
        return self.mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=self.node, coordinate=int(self.ports[name]))
        )

    def add_port_force(self, name: str, force) -> int:
        """A load ``force(t)`` [N] on port ``name`` (module docstring); returns the load."""
        return self.mbs.AddLoad(
            LoadCoordinate(
                markerNumber=self.port_marker(name),
                load=0.0,
                loadUserFunction=lambda mbs_, t, load: float(force(t)),
            )
        )

    def prescribe_port(self, name: str, motion) -> int:
        """Hold port ``name`` at ``motion(t)`` [m]; returns the constraint (its Force output
        is the reaction on the ground side).
        """
        return self.mbs.AddObject(
            CoordinateConstraint(
                markerNumbers=[self.ground, self.port_marker(name)],
                offsetUserFunction=lambda mbs_, t, item, off: float(motion(t)),
            )
        )

    def beam_energy(self) -> tuple[float, float]:
        """(kinetic, strain) energy of the bodies at the current state [J]."""
        sd = self.mbs.systemData
        z, v = sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()
        return 0.5 * float(v @ self.Mz @ v), 0.5 * float(z @ self.Kb @ z)

    def spring_energy(self) -> float:
        """Energy of the normal contact springs, the setup's springs and the linear
        tangential ones [J].
        """
        z = self.mbs.systemData.GetODE2Coordinates()
        return 0.5 * float(z @ self.Ks @ z)

    def set_state(self, x) -> None:
        """Start from the free coordinates ``x`` at rest."""
        z = self.T_inv @ np.asarray(x, float)
        for cfg in (exu.ConfigurationType.Initial, exu.ConfigurationType.Current):
            self.mbs.systemData.SetODE2Coordinates(z, configuration=cfg)

    def to_free(self, z) -> np.ndarray:
        """Free coordinates ``x = T z`` of host coordinates (one row per record)."""
        return np.asarray(z) @ self.T.T


def _add_bodies(mbs, n: int, Mz, K0, C):
    """The bodies as one generic ODE2 object on ``n`` coordinates (mass ``Mz``, stiffness
    ``K0``, damping ``C`` or none); returns its node.
    """
    node = mbs.AddNode(
        NodeGenericODE2(
            referenceCoordinates=[0.0] * n,
            initialCoordinates=[0.0] * n,
            initialCoordinates_t=[0.0] * n,
            numberOfODE2Coordinates=n,
        )
    )
    zero = np.zeros((n, n))

    def no_more(mbs_, t, item, q, q_t, f_q, f_v):
        return zero  # Exudyn adds f_q K' + f_v C' itself

    mbs.AddObject(
        ObjectGenericODE2(
            nodeNumbers=[node],
            massMatrix=Mz,
            stiffnessMatrix=K0,
            dampingMatrix=zero if C is None else C,
            jacobianUserFunction=no_more,
        )
    )
    return node


def build_host(
    specimen,
    *,
    tangential: str = "iwan",
    post_step=None,
    joint_elements: bool = False,
    depth: int = 24,
    floor: bool = True,
    ports: dict | None = None,
    assemble: bool = True,
) -> HostModel:
    """Build the Exudyn system of a specimen (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    tangential : {"iwan", "linear"}, keyword-only
        The contact points' tangential law: the Iwan elements, or linear springs ``KT_i``.
    post_step : callable, optional, keyword-only
        ``post_step(mbs, t) -> bool``, installed before the interface (which chains it).
    joint_elements : bool, keyword-only
        One Python ``IwanJoint`` connector per element (reference route).
    depth : int, keyword-only
        Reversal points each compiled law holds (``add_iwan_interface``; 24: a decaying or
        multi-mode response nests loops, docs/multi_mode.md section 2).
    floor : bool, keyword-only
        Add the specimen's damping floor (``Specimen.floor`` per stuck mode).
    ports : dict, optional, keyword-only
        ``{name: row}``: rows over the free coordinates made coordinates, for
        :meth:`HostModel.add_port_force` and :meth:`HostModel.prescribe_port`.
    assemble : bool, keyword-only
        Assemble the system (pass False to add loads or constraints first, then call
        ``model.mbs.Assemble()``).
    """
    if tangential not in ("iwan", "linear"):
        raise ValueError(f"tangential must be 'iwan' or 'linear', got {tangential!r}")
    L: LinearSystem = linear_system(specimen)
    pts = contact_points(specimen)
    rows = ports or {}
    names = list(rows)
    extra = [np.asarray(rows[k], dtype=np.float64) for k in names]
    T, T_inv, n_eta = port_basis(np.vstack([L.G] + extra) if extra else L.G)
    n, m = T.shape[1], len(pts)

    def sym(A):
        A = T.T @ A @ T
        return 0.5 * (A + A.T)

    Mz, K0, Kb = sym(L.M), sym(L.K0), sym(L.Kb)
    Ks = K0 - Kb
    fl = floor_damping(specimen) if floor else None
    C = sym(fl.C) if fl is not None and fl.active else None
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = _add_bodies(mbs, n, Mz, K0, C)
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    pairs = [
        (mg, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=n_eta + i)))
        for i in range(m)
    ]
    if post_step is not None:
        mbs.SetPostStepUserFunction(post_step)
    iface = None
    if tangential == "iwan":
        joints = [IwanJoint(p) for p in pts.params] if joint_elements else list(pts.params)
        iface = add_iwan_interface(mbs, pairs, joints, depth=depth)
    else:
        for pair, kt in zip(pairs, pts.KT):
            mbs.AddObject(
                ObjectConnectorCoordinateSpringDamper(
                    markerNumbers=list(pair), stiffness=float(kt), damping=0.0
                )
            )
        Ks = Ks.copy()
        Ks[n_eta : n_eta + m, n_eta : n_eta + m] += np.diag(pts.KT)
    if assemble:
        mbs.Assemble()
    return HostModel(
        specimen=specimen,
        SC=SC,
        mbs=mbs,
        L=L,
        points=pts,
        interface=iface,
        T=T,
        T_inv=T_inv,
        n_eta=n_eta,
        node=node,
        Mz=Mz,
        Kb=Kb,
        Ks=Ks,
        floor_C=C,
        ground=mg,
        ports={k: n_eta + m + j for j, k in enumerate(names)},
    )
