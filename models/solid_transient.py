"""Transient ring-down of a solid specimen in Exudyn: the reduced bodies and the patches' Iwan
elements, the independent route to f(X), zeta(X) of the solid (:func:`~iwan_element.models.ringdown`
dispatches here for a :class:`~iwan_element.models.solid.SolidSpecimen`).

The reduced solid (:mod:`~iwan_element.models.solid_build`) is linear bodies in small
vibration: ``M`` (identity), ``K0`` (bodies and normal patch springs) on the reduced
coordinates ``x``, and ``G`` (two tangential slips per patch, full row rank). The slips are
made coordinates: ``x = T z`` with ``T = [N, G^+]``, ``N`` an orthonormal basis of the null
space of ``G`` and ``G^+`` its pseudo-inverse (``G T = [0 | I]``, ``T^-1 = [N^T; G]``), so
``z = (eta, u)``: the body coordinates that do not slip and the slips ``u = G x`` themselves.
``M' = T^T M T`` is block diagonal (``N^T G^+ = 0``), ``K' = T^T K0 T``. One Exudyn
``NodeGenericODE2`` carries every ``z``; one ``ObjectGenericODE2`` carries ``M'``, ``K'`` and the
floor's modal damping matrix ``C' = T^T C T`` (:mod:`~iwan_element.models.damping`; constant
matrices, so Exudyn's Jacobian of the bodies is exact with no differencing), and each tangential
Iwan element is a coordinate-marker pair (the slip coordinate against a ground coordinate) of
:func:`iwan_element.exudyn.add_iwan_interface`: the compiled per-point law, one commit of all
points per accepted step and the energy records, as on the 1-D beams. The interface force
``-F_i`` acts on slip coordinate ``u_i``, which is ``G^T F`` in ``x``. With
``tangential="linear"`` a built-in ``CoordinateSpringDamper`` of stiffness ``KT_i`` replaces
each Iwan element (the same bodies with the stuck interface: the linear reference of cost and
decay).

The release, the time step, the records and the result are the 1-D ring-down's
(:mod:`~iwan_element.models.ringdown_records`); the energy is ``1/2 v'^T M' v'`` (kinetic),
``1/2 z^T T^T Kb T z`` (the bodies' strain) and ``1/2 z^T T^T (K0 - Kb) T z`` plus the linear
tangential springs' (springs). The dense system (``6 + n_modes + 3 n_patches`` coordinates, a
full ``K'``) is solved with Exudyn's dense LU (10 times faster than its sparse solver here,
docs/solid.md).
"""
from __future__ import annotations

import exudyn as exu
import numpy as np
import scipy.linalg as sla
from exudyn.itemInterface import (MarkerNodeCoordinate, NodeGenericODE2, NodePointGround,
                                  ObjectConnectorCoordinateSpringDamper, ObjectGenericODE2)

from iwan_element import IwanJoint
from iwan_element.exudyn import add_iwan_interface

from .damping import FloorWork, floor_damping
from .interface import contact_points
from .qsma import linear_modes
from .ringdown_records import (Recorder, build_result, joint_records, solve_timed, step_grid,
                               virgin_joint_energy)
from .ringdown_result import with_energy_warning
from .solid import SolidSpecimen
from .solver import solver_settings

__all__ = ["slip_basis", "SolidRingdownModel", "build_solid_model", "check_solid_release",
           "solid_ringdown"]

#: Smallest share of a mode's largest z displacement along the axis that the sensor must see
#: for its release amplitude to be set there.
SENSOR_SHARE = 0.05


def slip_basis(G) -> tuple:
    """``(T, T_inv, n_eta)``: the basis ``T = [N, G^+]`` whose last ``G.shape[0]`` coordinates
    are the slips ``G x`` (module docstring), its inverse ``[N^T; G]`` and the number of
    non-slip coordinates. ``G`` must have full row rank (ValueError)."""
    G = np.asarray(G, float)
    N = sla.null_space(G)
    if N.shape[1] != G.shape[1] - G.shape[0]:
        raise ValueError(f"the slip map G must have full row rank {G.shape[0]}, got rank "
                         f"{G.shape[1] - N.shape[1]}: two patch slips are dependent")
    T = np.hstack([N, np.linalg.pinv(G)])
    return T, np.vstack([N.T, G]), N.shape[1]


class SolidRingdownModel:
    """The assembled Exudyn system of a solid specimen (:func:`build_solid_model`).

    Attributes: ``specimen``, ``SC``, ``mbs``, ``points`` (the patches' ContactPoints),
    ``interface`` (the IwanInterface, None with linear springs), ``T``, ``T_inv`` (module
    docstring), ``node`` (the NodeGenericODE2), ``Kb``, ``Ks`` (bodies' and springs' stiffness
    in ``z``, the springs holding the linear tangential ones), ``Mz`` (mass in ``z``).
    """

    def __init__(self, specimen, SC, mbs, points, interface, T, T_inv, node, Mz, Kb, Ks):
        self.specimen, self.SC, self.mbs, self.points = specimen, SC, mbs, points
        self.interface, self.T, self.T_inv, self.node = interface, T, T_inv, node
        self.Mz, self.Kb, self.Ks = Mz, Kb, Ks

    def beam_energy(self) -> tuple[float, float]:
        """(kinetic, strain) energy of the bodies at the current state [J]."""
        sd = self.mbs.systemData
        z, v = sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()
        return 0.5 * float(v @ self.Mz @ v), 0.5 * float(z @ self.Kb @ z)

    def spring_energy(self) -> float:
        """Energy of the normal patch springs (and the linear tangential ones) [J]."""
        z = self.mbs.systemData.GetODE2Coordinates()
        return 0.5 * float(z @ self.Ks @ z)

    def set_state(self, x) -> None:
        """Start from the reduced coordinates ``x`` at rest."""
        z = self.T_inv @ np.asarray(x, float)
        for cfg in (exu.ConfigurationType.Initial, exu.ConfigurationType.Current):
            self.mbs.systemData.SetODE2Coordinates(z, configuration=cfg)


def build_solid_model(specimen: SolidSpecimen, *, tangential: str = "iwan", post_step=None,
                      joint_elements: bool = False, depth: int = 24,
                      floor: bool = True) -> SolidRingdownModel:
    """Build and assemble the Exudyn system of a solid specimen (module docstring).

    Parameters
    ----------
    specimen : SolidSpecimen
    tangential : {"iwan", "linear"}, keyword-only
        The patches' tangential law: the Iwan elements, or linear springs ``KT_i``.
    post_step : callable, optional, keyword-only
        ``post_step(mbs, t) -> bool``, installed before the interface (which chains it).
    joint_elements : bool, keyword-only
        One Python ``IwanJoint`` connector per element (reference route).
    depth : int, keyword-only
        Reversal points each compiled law holds (``add_iwan_interface``; 24 as the beams':
        a decaying or multi-mode response nests loops).
    floor : bool, keyword-only
        Add the specimen's damping floor (``Specimen.floor`` per stuck mode).
    """
    if not isinstance(specimen, SolidSpecimen):
        raise ValueError(f"specimen must be a SolidSpecimen, got {type(specimen).__name__}")
    if tangential not in ("iwan", "linear"):
        raise ValueError(f"tangential must be 'iwan' or 'linear', got {tangential!r}")
    L, pts = specimen.linear_system(), contact_points(specimen)
    T, T_inv, n_eta = slip_basis(L.G)
    n, m = T.shape[1], len(pts)

    def sym(A):
        A = T.T @ A @ T
        return 0.5 * (A + A.T)
    Mz, K0, Kb = sym(L.M), sym(L.K0), sym(L.Kb)
    Ks = K0 - Kb
    fl = floor_damping(specimen) if floor else None
    C = sym(fl.C) if fl is not None and fl.active else np.zeros((n, n))
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * n,
                                       initialCoordinates=[0.0] * n,
                                       initialCoordinates_t=[0.0] * n,
                                       numberOfODE2Coordinates=n))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=Mz, stiffnessMatrix=K0,
                                    dampingMatrix=C))
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    pairs = [(mg, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=n_eta + i)))
             for i in range(m)]
    if post_step is not None:
        mbs.SetPostStepUserFunction(post_step)
    iface = None
    if tangential == "iwan":
        joints = [IwanJoint(p) for p in pts.params] if joint_elements else list(pts.params)
        iface = add_iwan_interface(mbs, pairs, joints, depth=depth)
    else:
        for pair, kt in zip(pairs, pts.KT):
            mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                markerNumbers=list(pair), stiffness=float(kt), damping=0.0))
        Ks = Ks.copy()
        Ks[n_eta:, n_eta:] += np.diag(pts.KT)
    mbs.Assemble()
    model = SolidRingdownModel(specimen, SC, mbs, pts, iface, T, T_inv, node, Mz, Kb, Ks)
    model.floor_C = C if fl is not None and fl.active else None
    return model


def check_solid_release(specimen: SolidSpecimen, modes, impact) -> None:
    """Refuse what the solid ring-down cannot do: an impact, vibration effects, and a mode
    the sensor barely sees (its release amplitude at the sensor could not set it)."""
    if impact is not None:
        raise ValueError("impact is not available on a SolidSpecimen; release it from "
                         "amplitude={mode: X}")
    if specimen.effects:
        raise ValueError("a SolidSpecimen's ring-down takes no vibration effects; give the "
                         "solid without effects (specimen.replace(effects=()))")
    if specimen.model.axis is None:
        raise ValueError("specimen.model holds no axis rows (SolidModel.axis): build the solid "
                         "with solid_build.solid_specimen")
    for r in modes:
        _, phi, _, L, _ = linear_modes(specimen, mode=r)
        along = np.max(np.abs(specimen.model.axis[1] @ phi))
        share = abs(float(L.S @ phi)) / along
        if share < SENSOR_SHARE:
            raise ValueError(
                f"mode {r} moves the sensor's z displacement by {share:.1e} of its largest "
                "z displacement along the axis (an in-plane or torsion mode): its release "
                "amplitude at the sensor cannot set it. The solid numbers its stuck modes "
                "as natural_frequencies does (the Brake-Reuss solid: 1 first height bending, "
                "2 in-plane bending, 3 second height bending); release height-bending modes")


def solid_ringdown(specimen: SolidSpecimen, amp: dict, rel: dict, rows, positions,
                   opts: dict):
    """The ring-down of a solid specimen from the release ``rel`` of the modes ``amp`` (the
    1-D rule, :func:`~iwan_element.models.ringdown`'s ``_release``), its sensors' reduced
    ``rows`` at ``positions`` [m]; ``opts``: ringdown's checked options (with ``tangential``).
    Returns a
    :class:`~iwan_element.models.RingdownResult` with the 1-D fields."""
    w0 = rel["omega0"]
    fw = FloorWork(None)
    rec = Recorder(slice(None), [], fw, opts["record_energy"])
    tangential = opts["tangential"]
    model = build_solid_model(specimen, tangential=tangential, post_step=rec,
                              joint_elements=opts["joint_elements"])
    fw.C = model.floor_C
    rec.model = model
    model.set_state(rel["x"])
    kin0, pot0 = model.beam_energy()
    e0 = pot0 + model.spring_energy() + (
        virgin_joint_energy(rel["slip"], model.points.params) if tangential == "iwan" else 0.0)
    h, n = step_grid(w0, opts["steps_per_period"], duration=opts["duration"],
                     cycles=opts["cycles"])
    z0 = model.T_inv @ rel["x"]
    sim = solver_settings(force_scale=float(np.max(np.abs((model.Kb + model.Ks) @ z0))))
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    solve = solve_timed(model.mbs, sim, rec, n, opts["progress"])
    quad = joint_records(model.interface, rec.energy, e0) if opts["record_energy"] else None
    X = np.array(rec.coords) @ model.T.T
    return with_energy_warning(build_result(specimen, amp, rec, X, rel, rows, positions, h, n, {
        "n_periods": opts["n_periods"], "steps_per_period": opts["steps_per_period"],
        "solve": solve, "e0": e0, "kin0": kin0, "quad": quad, "n_points": len(model.points),
        "overflow": len(getattr(model.interface, "overflow_times", ())), "effects": (),
        "impact": None, "extra": {"n_coordinates": int(model.T.shape[1]),
                                  "tangential": tangential}}))
