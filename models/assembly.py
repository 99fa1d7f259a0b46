"""Exudyn model of a :class:`~iwan_element.models.specimens.Specimen` and its linear matrices.

Beams: ``ObjectANCFCable2D`` (Bernoulli-Euler, geometrically exact; docs/equations.md
section 6: Cable2D accepts markers offset to the beam surfaces, where a lap joint acts,
whereas the geometrically exact 2-D beam acts only at its axis). Each beam has lap elements of height ``lap_thickness`` and outer elements
of height ``thickness``; beam A's axis is at ``y = 0``, beam B's at ``y = lap_thickness``, and
the interface at the surfaces ``+-lap_thickness/2``. Boundaries: ``"clamped-free"`` and
``"clamped-driven"`` clamp beam A's first node (x, y and slope); ``"clamped-driven"`` also
holds beam B's last node in the machine grip (y and slope fixed, axial displacement
prescribed by ``drive``, the quasi-static test of :mod:`~iwan_element.models.machine`).
Simplification: for stepped halves
(Brake-Reuss) the axis is kept straight through the step, so the outer part's bending
stiffness is that of the full section but the eccentricity of its axis (``thickness/4``
for the BRB) is neglected; this changes axial-bending coupling only.

Interface: at each contact point (:func:`~iwan_element.models.interface.contact_points`) a
built-in normal spring ``k_n,i`` and a tangential element: the Iwan element (``"iwan"``),
a linear spring ``KT_i`` (``"linear"``) or nothing (``"none"``, used to extract the linear
matrices without the tangential stiffness).

The Iwan elements are attached by :func:`iwan_element.exudyn.add_iwan_interface`: the exact
law of every point as a compiled (symbolic) Exudyn expression and one vectorised commit of all
points per accepted step. ``joint_elements=True`` attaches :class:`~iwan_element.IwanJoint`
elements instead (one Python connector per point; the reference route).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (CoordinateConstraint, MarkerBodyPosition, MarkerNodeCoordinate,
                                  NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D,
                                  ObjectConnectorCartesianSpringDamper, ObjectGround)

from iwan_element import IwanJoint
from iwan_element.exudyn import add_iwan_interface

from .interface import ContactPoints, contact_points
from .solid import SolidSpecimen
from .specimens import Specimen

__all__ = ["SpecimenModel", "build_specimen_model", "LinearSystem", "linear_system",
           "axis_rows"]

_OVT = exu.OutputVariableType


@dataclass
class SpecimenModel:
    """An assembled Exudyn system of a specimen and handles into it."""

    specimen: Specimen
    SC: object
    mbs: object
    points: ContactPoints
    elements: list
    nodes: list
    marker_pairs: list
    springs: list
    interface: object
    sensor_marker: int
    fixed_coordinates: list
    extra: dict = field(default_factory=dict)

    def beam_energy(self) -> tuple[float, float]:
        """(kinetic, strain) energy of the beams [J]."""
        get = self.mbs.GetObjectOutputBody
        kin = sum(get(e, _OVT.KineticEnergy, localPosition=[0, 0, 0]) for e in self.elements)
        pot = sum(get(e, _OVT.PotentialEnergy, localPosition=[0, 0, 0]) for e in self.elements)
        return float(kin), float(pot)

    def spring_energy(self) -> float:
        """Potential energy of the linear springs [J]: the built-in ones and those the
        interface's objects carry (the normal springs on the compiled route)."""
        e = float(sum(self.mbs.GetObjectOutput(s, _OVT.PotentialEnergy) for s in self.springs))
        if self.interface is not None:
            e += self.interface.linear_energy()
        return e

    def joint_energy(self) -> tuple[float, float]:
        """(stored, dissipated) energy of the interface's Iwan elements at the last accepted
        step [J] (0 before the first record or without an Iwan interface)."""
        itf = self.interface
        if itf is None or itf.n_records == 0:
            return 0.0, 0.0
        return (float(itf.stored_energy_history[-1]), float(itf.dissipated_energy_history[-1]))

    def sensor_displacement(self) -> float:
        """Current transverse displacement at the sensor point [m]."""
        return float(self.mbs.GetMarkerOutput(self.sensor_marker, _OVT.Position)[1]
                     - self.extra["sensor_y0"])

    def axis_marker(self, x: float) -> int:
        """A new marker on the beams' axis at ``x`` [m] from the clamp: on beam A up to its
        length, on beam B beyond (the sensor's and the excitation's placement)."""
        return _axis_marker(self.mbs, self.specimen, self.elements, x)

    def slips(self) -> np.ndarray:
        """Current tangential slip ``x_B - x_A`` at each contact point [m]."""
        pos = self.mbs.GetMarkerOutput
        return np.array([pos(b, _OVT.Position)[0] - pos(a, _OVT.Position)[0]
                         for a, b in self.marker_pairs])


def _mesh(specimen: Specimen):
    """Element boundaries (from the beam's own start) and heights of one beam, lap first for
    beam B and last for beam A."""
    s = specimen
    n_lap = max(4, int(round(s.n_elements * s.overlap / s.beam_length)))
    n_out = max(2, s.n_elements - n_lap)
    out = np.linspace(0.0, s.lap_start, n_out + 1)
    lap = np.linspace(0.0, s.overlap, n_lap + 1)
    a_edges = np.concatenate([out, s.lap_start + lap[1:]])
    a_h = [s.thickness] * n_out + [s.lap_thickness] * n_lap
    b_edges = np.concatenate([lap, s.overlap + out[1:]])
    b_h = [s.lap_thickness] * n_lap + [s.thickness] * n_out
    return (a_edges, a_h), (b_edges, b_h)


def _beam(mbs, s: Specimen, x0, y0, edges, heights):
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[x0 + e, y0, 1.0, 0.0]))
             for e in edges]
    elems = []
    for i, h in enumerate(heights):
        EI = s.youngs_modulus * s.width * h ** 3 / 12.0
        EA = s.youngs_modulus * s.width * h
        elems.append(mbs.AddObject(ObjectANCFCable2D(
            massPerLength=s.density * s.width * h, bendingStiffness=EI, axialStiffness=EA,
            length=float(edges[i + 1] - edges[i]),
            nodeNumbers=[nodes[i], nodes[i + 1]])))
    return nodes, elems


def _axis_marker(mbs, s: Specimen, elements, x: float) -> int:
    """A marker on the axis of beam A (``x`` up to its length) or of beam B (beyond); the
    beams' ``elements`` in build order, A's first."""
    (a_edges, a_h), (b_edges, _) = _mesh(s)
    ea, eb = elements[:len(a_h)], elements[len(a_h):]
    if x <= s.beam_length:
        return _marker_at(mbs, ea, a_edges, 0.0, x, 0.0)
    return _marker_at(mbs, eb, b_edges, s.lap_start, x, 0.0)


def _marker_at(mbs, elems, edges, x0, x, y_local):
    i = int(np.clip(np.searchsorted(edges, x - x0, side="right") - 1, 0, len(elems) - 1))
    return mbs.AddMarker(MarkerBodyPosition(bodyNumber=elems[i],
                                            localPosition=[x - x0 - edges[i], y_local, 0.0]))


def build_specimen_model(specimen: Specimen, *, tangential: str = "iwan", post_step=None,
                         joint_elements: bool = False, drive=None,
                         depth: int = 24) -> SpecimenModel:
    """Build and assemble the Exudyn system of a specimen.

    Parameters
    ----------
    specimen : Specimen
    tangential : {"iwan", "linear", "none"}, keyword-only
        Tangential law of the contact points (module docstring).
    post_step : callable, optional, keyword-only
        ``post_step(mbs, t) -> bool``, installed before the interface (which chains it).
    joint_elements : bool, keyword-only
        Attach :class:`~iwan_element.IwanJoint` elements (Python route) instead of the
        compiled per-point law.
    drive : callable, optional, keyword-only
        ``drive(t) -> u`` [m], the axial displacement of beam B's end in the machine grip
        (``boundary="clamped-driven"`` only; default: held at zero). The grip's axial
        constraint is ``model.extra["grip"]`` (its force is the machine force).
    depth : int, keyword-only
        Reversal points each contact point's compiled law holds (``add_iwan_interface``;
        default 24): a decaying or multi-mode response nests loops, and a step that closes
        more than ``depth // 2`` of them is not exact (warned). 24 costs no more than 8 per
        step where nothing overflows (docs/multi_mode.md section 2).
    """
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    if tangential not in ("iwan", "linear", "none"):
        raise ValueError(f"tangential must be 'iwan', 'linear' or 'none', got {tangential!r}")
    if drive is not None and (specimen.boundary != "clamped-driven" or not callable(drive)):
        raise ValueError("drive must be a callable u(t) [m], given with boundary='clamped-driven'")
    s = specimen
    pts = contact_points(s)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    (ae, ah), (be, bh) = _mesh(s)
    tl = s.lap_thickness
    na, ea = _beam(mbs, s, 0.0, 0.0, ae, ah)
    nb, eb = _beam(mbs, s, s.lap_start, tl, be, bh)
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    fixed_nodes = []
    if s.boundary in ("clamped-free", "clamped-driven"):
        fixed_nodes.append((na[0], (0, 1, 3)))
    if s.boundary == "clamped-driven":
        fixed_nodes.append((nb[-1], (0, 1, 3)))
    extra = {}
    for node, coords in fixed_nodes:
        for c in coords:
            m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=c))
            kw = {}
            if node == nb[-1] and c == 0 and drive is not None:
                kw["offsetUserFunction"] = lambda mbs_, t, item, off: float(drive(t))
            obj = mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, m], **kw))
            if node == nb[-1] and c == 0:
                extra["grip"] = obj
    # on the compiled route the interface's own objects carry the normal springs (one
    # object per point instead of two: the extra objects cost about a third of the linear
    # model, benchmarks/bench_beam.py); else built-in springs
    merged = tangential == "iwan" and not joint_elements
    pairs, springs = [], []
    for x, p, kn in zip(pts.x, pts.params, pts.normal_stiffness):
        ma = _marker_at(mbs, ea, ae, 0.0, x, +0.5 * tl)
        mb = _marker_at(mbs, eb, be, s.lap_start, x, -0.5 * tl)
        pairs.append((ma, mb))
        kt = p.KT if tangential == "linear" else 0.0
        if not merged:
            springs.append(mbs.AddObject(ObjectConnectorCartesianSpringDamper(
                markerNumbers=[ma, mb], stiffness=[kt, float(kn), 0.0], damping=[0.0, 0.0, 0.0])))
    if post_step is not None:
        mbs.SetPostStepUserFunction(post_step)
    iface = None
    if tangential == "iwan":
        joints = [IwanJoint(p) for p in pts.params] if joint_elements else list(pts.params)
        normal = [[0.0, float(kn), 0.0] for kn in pts.normal_stiffness] if merged else None
        iface = add_iwan_interface(mbs, pairs, joints, axis=[1.0, 0.0, 0.0], stiffness=normal,
                                   depth=depth)
    sm = _axis_marker(mbs, s, ea + eb, s.sensor_position)
    mbs.AddObject(ObjectGround())
    mbs.Assemble()
    fixed = []
    for node, coords in fixed_nodes:
        i0 = mbs.GetNodeODE2Index(node)
        fixed += [i0 + c for c in coords]
    model = SpecimenModel(specimen=s, SC=SC, mbs=mbs, points=pts, elements=ea + eb,
                          nodes=na + nb, marker_pairs=pairs, springs=springs, interface=iface,
                          sensor_marker=sm, fixed_coordinates=fixed, extra=extra)
    model.extra["sensor_y0"] = float(mbs.GetMarkerOutput(sm, _OVT.Position,
                                                         configuration=exu.ConfigurationType.Reference)[1])
    return model


@dataclass(frozen=True)
class LinearSystem:
    """Linear matrices of a specimen on its free coordinates (clamped ones removed).

    ``K0`` holds the beams and the normal contact springs but no tangential interface
    stiffness; ``G`` maps coordinates to the tangential slips of the contact points, ``S``
    to the sensor's transverse displacement and ``E`` to the transverse displacement at the
    excitation point (the force vector of a unit transverse force there is ``E``, by
    reciprocity); ``Kb`` is the beams' part of ``K0`` (without the contact springs).
    ``free`` are the Exudyn ODE2 indices kept.
    ``rigid_body_modes``: how many zero-frequency modes ``(K0 + G^T diag(KT) G, M)`` has (3
    for a free-free planar specimen, 6 for a free-free solid, 0 when clamped).
    """

    M: np.ndarray
    K0: np.ndarray
    Kb: np.ndarray
    G: np.ndarray
    S: np.ndarray
    free: np.ndarray
    n_coordinates: int
    rigid_body_modes: int = 0
    E: np.ndarray | None = None


def _structure_key(specimen: Specimen) -> Specimen:
    """The specimen with the fields that do not change K0, G, M normalised (cache key)."""
    return specimen.replace(friction=1.0, chi=0.0, beta=0.0, damping_floor=0.0, modal_damping=(),
                            stiffness_per_area=1.0, amplitude_range=(1.0, 2.0))


def linear_system(specimen: Specimen | SolidSpecimen) -> LinearSystem:
    """Linear matrices of a specimen (cached on its geometry, material and contact layout);
    a :class:`~iwan_element.models.solid.SolidSpecimen` carries its own (reduced)."""
    if isinstance(specimen, SolidSpecimen):
        return specimen.linear_system()
    return _linear_system(_structure_key(specimen))


@lru_cache(maxsize=16)
def _linear_system(key: Specimen) -> LinearSystem:
    model = build_specimen_model(key, tangential="none")
    mbs = model.mbs
    em = model.axis_marker(key.excitation.position)
    mbs.Assemble()
    sim = exu.SimulationSettings()
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    sim.staticSolver.verboseMode = 0          # no solver banner on stdout
    solver = exu.MainSolverStatic()
    solver.InitializeSolver(mbs, sim)
    solver.ComputeMassMatrix(mbs)
    M = np.array(solver.GetSystemMassMatrix())
    solver.ComputeJacobianODE2RHS(mbs)
    K = -np.array(solver.GetSystemJacobian())[:M.shape[0], :M.shape[0]]
    n = M.shape[0]
    # slips and sensor by central differences of the marker positions (linearisation)
    pos = mbs.GetMarkerOutput

    def read():
        a = np.array([pos(m, _OVT.Position)[:2] for m, _ in model.marker_pairs])
        b = np.array([pos(m, _OVT.Position)[:2] for _, m in model.marker_pairs])
        return np.concatenate([(b - a).T.ravel(), [pos(model.sensor_marker, _OVT.Position)[1],
                                                  pos(em, _OVT.Position)[1]]])

    D = _coordinate_jacobian(mbs, read, n)
    n_p = len(model.marker_pairs)
    G, Gn, S, E = D[:n_p], D[n_p:2 * n_p], D[2 * n_p], D[2 * n_p + 1]
    K = 0.5 * (K + K.T)
    Kb = K - Gn.T @ (model.points.normal_stiffness[:, None] * Gn)
    free = np.setdiff1d(np.arange(n), model.fixed_coordinates)
    ix = np.ix_(free, free)
    return LinearSystem(M=M[ix], K0=K[ix], Kb=Kb[ix], G=G[:, free], S=S[free], free=free,
                        n_coordinates=n, E=E[free],
                        rigid_body_modes=3 if key.boundary == "free-free" else 0)


def _coordinate_jacobian(mbs, read, n: int, eps: float = 1e-8) -> np.ndarray:
    """``d read / d q`` at ``q = 0`` by central differences over the ``n`` ODE2 coordinates
    (``read() -> 1-D array``; exact for the Cable2D positions, which are linear in the
    coordinates); the coordinates are left at zero."""
    cur = exu.ConfigurationType.Current
    out = []
    for k in range(n):
        pm = []
        for sgn in (1.0, -1.0):
            q = np.zeros(n)
            q[k] = sgn * eps
            mbs.systemData.SetODE2Coordinates(q, configuration=cur)
            pm.append(np.asarray(read(), float))
        out.append((pm[0] - pm[1]) / (2 * eps))
    mbs.systemData.SetODE2Coordinates(np.zeros(n), configuration=cur)
    return np.array(out).T


def axis_rows(specimen: Specimen | SolidSpecimen, positions) -> np.ndarray:
    """Rows mapping the free coordinates to the transverse displacement [m] of the beams'
    axis at ``positions`` [m] along the assembly (the axis of ``sensor_position``; beam A up
    to its length, beam B beyond): shape ``(len(positions), n_free)``. A
    :class:`~iwan_element.models.solid.SolidSpecimen` reads its stored rows
    (:meth:`~iwan_element.models.solid.SolidSpecimen.axis_rows`)."""
    x = np.atleast_1d(np.asarray(positions, float))
    if x.ndim != 1 or x.size == 0 or not np.all(np.isfinite(x)) or np.any(x < 0) \
            or np.any(x > specimen.total_length):
        raise ValueError(f"positions must be a non-empty sequence in [0, "
                         f"{specimen.total_length:.6g}] m, got {positions!r}")
    if isinstance(specimen, SolidSpecimen):
        return specimen.axis_rows(x)
    return _axis_rows(_structure_key(specimen), tuple(float(v) for v in x))


@lru_cache(maxsize=16)
def _axis_rows(key: Specimen, positions: tuple) -> np.ndarray:
    model = build_specimen_model(key, tangential="none")
    markers = [model.axis_marker(x) for x in positions]
    mbs = model.mbs
    mbs.Assemble()
    pos = mbs.GetMarkerOutput
    n = mbs.systemData.GetODE2Coordinates().size
    D = _coordinate_jacobian(mbs, lambda: [pos(m, _OVT.Position)[1] for m in markers], n)
    free = np.setdiff1d(np.arange(n), model.fixed_coordinates)
    D = D[:, free]
    D.setflags(write=False)
    return D
