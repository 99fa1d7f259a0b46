"""The jointed beam: two identical steel beams bolted at a single lap joint, in Exudyn.

Geometry (2-D, x along the beams, y across)::

                                   beam B (axis at y = h)
                         ==========================================
      beam A (axis y = 0)      | overlap |
    ============================================
    ^ clamped at x = 0         bolt at x_b          free end (vibration) or machine grip
                                                     (quasi-static test) at x = 2L - overlap

Beams are ``ObjectANCFCable2D`` elements (geometrically exact Bernoulli-Euler beams with
axial and bending stiffness). They are chosen over ``ObjectBeamGeometricallyExact2D`` because
a lap joint acts on the beam *surfaces*: Cable2D accepts position markers offset across the
cross-section (the interface points at +-h/2), whereas the geometrically exact 2-D beam only
acts at its axis; shear deformation, which the Cable2D element neglects, is negligible for
beams of this slenderness (L/h = 20).

The bolt's contact is represented at ``n_contact_points`` points spread over
``contact_spacing`` around the bolt, on the interface (the top surface of A and the bottom
surface of B). At each point:

* the tangential (x) force is a joint element (by default the exact Iwan joint with
  ``Fs/n`` and ``KT/n``, so the points together reproduce the identified joint in an axial
  test), attached with :func:`iwan_element.exudyn.add_iwan_connector`;
* the normal (y) force is a stiff linear spring; two or more points also make the rotation
  at the bolt stiff.

Why more than one point: in bending of a clamped-free assembly, axial equilibrium of the free
beam forces the *net* tangential joint force to zero, so a single tangential point would never
slip in bending. Real lap joints dissipate in bending through composite action: patches of the
interface on either side of the bolt slip in opposite directions. Two points reproduce that.

Everything here uses only the public API of :mod:`iwan_element` and Exudyn.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (CoordinateConstraint, MarkerBodyPosition, MarkerNodeCoordinate,
                                  NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D,
                                  ObjectConnectorCartesianSpringDamper, ObjectGround)

from iwan_element import IwanJoint, IwanParameters
from iwan_element.exudyn import add_iwan_connector

__all__ = ["JointedBeamConfig", "JointedBeamModel", "build_jointed_beam", "M16_JOINT"]

#: Joint parameters of the shipped (synthetic) example test of the paper's specimen
#: (M16 10.9 bolt, 30 kN preload): Fs = 9 kN (friction ~0.3 x preload), KT = 50 kN/mm.
M16_JOINT = IwanParameters(Fs=9.0e3, KT=5.0e7, chi=-0.5, beta=0.5)

_JOINT_MODELS = ("iwan", "linear", "rigid")
_BOUNDARIES = ("clamped-free", "clamped-driven")


@dataclass(frozen=True)
class JointedBeamConfig:
    """Configuration of the jointed-beam model (SI units).

    Parameters
    ----------
    beam_length : float
        Length of each beam [m].
    width, thickness : float
        Cross-section [m] (bending about the width axis; ``thickness`` is ``h``).
    youngs_modulus : float
        [Pa].
    density : float
        [kg/m^3].
    overlap : float
        Length of the lap [m], ``< beam_length``.
    bolt_position : float
        Bolt location as a fraction of the overlap, measured from the start of beam B
        (0.5: centre of the lap).
    contact_spacing : float
        Distance between the outermost contact points around the bolt [m] (about the
        diameter of the bolt's pressure cone; 24 mm for M16).
    n_contact_points : int
        Number of interface points sharing the joint, ``>= 1`` (2 or more for bending).
    n_elements : int
        Cable2D elements per beam.
    joint : IwanParameters
        Parameters of the whole joint; each contact point gets ``Fs/n`` and ``KT/n``.
    joint_model : {"iwan", "linear", "rigid"}
        Tangential law: the Iwan joint, a linear spring ``KT/n`` per point, or a rigid
        connection (``rigid_stiffness`` per point).
    normal_stiffness : float
        Total normal contact stiffness of the joint [N/m] (shared by the points).
    rigid_stiffness : float
        Tangential stiffness per point when ``joint_model="rigid"`` [N/m].
    boundary : {"clamped-free", "clamped-driven"}
        Beam A is clamped at x = 0; beam B's far end is free (vibration) or held in the
        machine grip (transverse and rotation fixed, axial displacement prescribed).
    preload : float
        Bolt preload [N]; it is not used by the mechanics (its effect is in ``joint``) and is
        recorded in the metadata.
    rayleigh_beta : float
        Stiffness-proportional material damping of the beams [s], ``>= 0``: Cable2D bending
        and axial damping ``beta EI`` and ``beta EA``, giving a modal damping ratio
        ``beta w / 2``. Default 0, so that the joint is the only dissipation (energy checks).
    """

    beam_length: float = 0.2
    width: float = 0.04
    thickness: float = 0.01
    youngs_modulus: float = 2.1e11
    density: float = 7850.0
    overlap: float = 0.05
    bolt_position: float = 0.5
    contact_spacing: float = 0.024
    n_contact_points: int = 2
    n_elements: int = 16
    joint: IwanParameters = field(default=M16_JOINT)
    joint_model: str = "iwan"
    normal_stiffness: float = 2.0e9
    rigid_stiffness: float = 1.0e11
    boundary: str = "clamped-free"
    preload: float = 30.0e3
    rayleigh_beta: float = 0.0

    def __post_init__(self):
        for name in ("beam_length", "width", "thickness", "youngs_modulus", "density", "overlap",
                     "normal_stiffness", "rigid_stiffness", "preload"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {v!r}")
        if self.overlap >= self.beam_length:
            raise ValueError(f"overlap must be < beam_length ({self.beam_length}), got {self.overlap}")
        if not 0.0 <= self.bolt_position <= 1.0:
            raise ValueError(f"bolt_position must be in [0, 1] (fraction of the overlap), "
                             f"got {self.bolt_position}")
        if not (isinstance(self.n_contact_points, int) and self.n_contact_points >= 1):
            raise ValueError(f"n_contact_points must be an integer >= 1, got {self.n_contact_points!r}")
        if not (isinstance(self.n_elements, int) and self.n_elements >= 2):
            raise ValueError(f"n_elements must be an integer >= 2, got {self.n_elements!r}")
        if not (isinstance(self.rayleigh_beta, (int, float)) and math.isfinite(self.rayleigh_beta)
                and self.rayleigh_beta >= 0):
            raise ValueError(f"rayleigh_beta must be >= 0 [s], got {self.rayleigh_beta!r}")
        if not (isinstance(self.contact_spacing, (int, float)) and math.isfinite(self.contact_spacing)
                and self.contact_spacing >= 0):
            raise ValueError(f"contact_spacing must be >= 0, got {self.contact_spacing!r}")
        if not isinstance(self.joint, IwanParameters):
            raise ValueError(f"joint must be IwanParameters, got {type(self.joint).__name__}")
        if self.joint_model not in _JOINT_MODELS:
            raise ValueError(f"joint_model must be one of {_JOINT_MODELS}, got {self.joint_model!r}")
        if self.boundary not in _BOUNDARIES:
            raise ValueError(f"boundary must be one of {_BOUNDARIES}, got {self.boundary!r}")
        x = self.contact_x()
        lo, hi = self.beam_length - self.overlap, self.beam_length
        if x.min() < lo - 1e-12 or x.max() > hi + 1e-12:
            raise ValueError("the contact points (bolt_position +- contact_spacing/2) must lie "
                             "inside the overlap")

    # derived geometry
    @property
    def total_length(self) -> float:
        """Length of the assembly [m]."""
        return 2.0 * self.beam_length - self.overlap

    @property
    def bolt_x(self) -> float:
        """Global x of the bolt [m]."""
        return self.beam_length - self.overlap + self.bolt_position * self.overlap

    def contact_x(self) -> np.ndarray:
        """Global x of the contact points [m], shape (n_contact_points,)."""
        n = self.n_contact_points
        if n == 1:
            return np.array([self.bolt_x])
        return self.bolt_x + np.linspace(-0.5, 0.5, n) * self.contact_spacing

    @property
    def point_joint(self) -> IwanParameters:
        """Iwan parameters of one contact point (``Fs/n``, ``KT/n``)."""
        n = self.n_contact_points
        return self.joint.replace(Fs=self.joint.Fs / n, KT=self.joint.KT / n)

    @property
    def EI(self) -> float:
        """Bending stiffness of one beam [N m^2]."""
        return self.youngs_modulus * self.width * self.thickness ** 3 / 12.0

    @property
    def EA(self) -> float:
        """Axial stiffness of one beam [N]."""
        return self.youngs_modulus * self.width * self.thickness

    @property
    def mass_per_length(self) -> float:
        """[kg/m]."""
        return self.density * self.width * self.thickness

    def replace(self, **changes) -> "JointedBeamConfig":
        """A copy with some fields changed (validated again); unknown names raise ValueError."""
        names = {f.name for f in fields(self)}
        unknown = set(changes) - names
        if unknown:
            raise ValueError(f"unknown JointedBeamConfig fields {sorted(unknown)}; "
                             f"fields are {sorted(names)}")
        return replace(self, **changes)


@dataclass
class JointedBeamModel:
    """What :func:`build_jointed_beam` returns: the Exudyn system and handles into it.

    Attributes
    ----------
    config : JointedBeamConfig
    SC, mbs : exudyn SystemContainer and MainSystem (assembled)
    nodes_a, nodes_b, elements_a, elements_b : lists of int
    connectors : list of IwanConnector
        One per contact point for ``joint_model="iwan"``, else empty.
    joints : list
        The joint elements inside the connectors.
    springs : list of int
        Built-in spring connectors (normal springs; tangential too for linear/rigid).
    drive : int or None
        The CoordinateConstraint prescribing beam B's axial end displacement
        (``boundary="clamped-driven"``).
    tip_node : int
        Beam B's last node (the free end or the machine grip).
    clamped_coordinates : list of int
        ODE2 indices fixed by the boundary conditions (for eigenvalue analysis).
    marker_a, marker_b : list of int
        Interface markers (top surface of A, bottom surface of B) at the contact points.
    """

    config: JointedBeamConfig
    SC: object
    mbs: object
    nodes_a: list
    nodes_b: list
    elements_a: list
    elements_b: list
    connectors: list
    joints: list
    springs: list
    drive: int | None
    tip_node: int
    clamped_coordinates: list
    marker_a: list
    marker_b: list
    drive_function: object = None

    @property
    def elements(self) -> list:
        """All beam elements."""
        return self.elements_a + self.elements_b

    def tip_index(self, coordinate: int = 1) -> int:
        """ODE2 index of a coordinate of the tip node (0: x, 1: y, 2: x', 3: y')."""
        return self.mbs.GetNodeODE2Index(self.tip_node) + coordinate

    def beam_energy(self) -> tuple[float, float]:
        """(kinetic, strain) energy of both beams in the current state [J]."""
        ovt = exu.OutputVariableType
        get = self.mbs.GetObjectOutputBody
        kin = sum(get(e, ovt.KineticEnergy, localPosition=[0, 0, 0]) for e in self.elements)
        pot = sum(get(e, ovt.PotentialEnergy, localPosition=[0, 0, 0]) for e in self.elements)
        return float(kin), float(pot)

    def spring_energy(self) -> float:
        """Potential energy of the built-in springs (normal; tangential if linear) [J]."""
        ovt = exu.OutputVariableType
        return float(sum(self.mbs.GetObjectOutput(s, ovt.PotentialEnergy) for s in self.springs))

    def joint_energy(self) -> tuple[float, float]:
        """(stored, dissipated) energy of the Iwan joints, committed state [J]."""
        return (float(sum(j.stored_energy for j in self.joints)),
                float(sum(j.dissipated_energy for j in self.joints)))

    def total_energy(self) -> float:
        """Kinetic + strain + springs + joint stored + joint dissipated [J]."""
        kin, pot = self.beam_energy()
        st, ds = self.joint_energy()
        return kin + pot + self.spring_energy() + st + ds

    def interface_slips(self) -> np.ndarray:
        """Current tangential slip at each contact point, ``x_B - x_A`` at the interface [m]."""
        ovt = exu.OutputVariableType
        pa = [self.mbs.GetMarkerOutput(m, ovt.Position)[0] for m in self.marker_a]
        pb = [self.mbs.GetMarkerOutput(m, ovt.Position)[0] for m in self.marker_b]
        return np.array(pb) - np.array(pa)

    def reset_joints(self) -> None:
        """Return every connector (and its joint) to the virgin state."""
        for c in self.connectors:
            c.reset()


def _beam(mbs, cfg: JointedBeamConfig, x0: float, y0: float):
    n = cfg.n_elements
    Le = cfg.beam_length / n
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[x0 + i * Le, y0, 1.0, 0.0]))
             for i in range(n + 1)]
    elems = [mbs.AddObject(ObjectANCFCable2D(
        massPerLength=cfg.mass_per_length, bendingStiffness=cfg.EI,
        axialStiffness=cfg.EA, bendingDamping=cfg.rayleigh_beta * cfg.EI,
        axialDamping=cfg.rayleigh_beta * cfg.EA, length=Le, nodeNumbers=[nodes[i], nodes[i + 1]]))
        for i in range(n)]
    return nodes, elems, Le


def _surface_marker(mbs, elems, Le, x0, x, y_local):
    e = min(int((x - x0) / Le), len(elems) - 1)
    return mbs.AddMarker(MarkerBodyPosition(bodyNumber=elems[e],
                                            localPosition=[x - x0 - e * Le, y_local, 0.0]))


def build_jointed_beam(config: JointedBeamConfig | None = None, *, joint_factory=None,
                       drive_function=None, post_step=None) -> JointedBeamModel:
    """Build the jointed-beam system in a new Exudyn SystemContainer.

    Parameters
    ----------
    config : JointedBeamConfig, optional
        Defaults to ``JointedBeamConfig()``.
    joint_factory : callable, optional, keyword-only
        ``joint_factory(point_params) -> element`` makes the joint element of one contact
        point (for example an effect from :mod:`iwan_element.effects` around an
        ``IwanJoint``); default ``IwanJoint``. Only used with ``joint_model="iwan"``.
    drive_function : callable, optional, keyword-only
        ``f(t) -> u`` [m], the machine displacement for ``boundary="clamped-driven"``
        (default: none, the grip is held at zero).
    post_step : callable, optional, keyword-only
        ``post_step(mbs, t) -> bool``; installed before the joint connectors, which chain it
        (a post-step function set after them would replace their commit).

    Returns
    -------
    JointedBeamModel
    """
    cfg = JointedBeamConfig() if config is None else config
    if not isinstance(cfg, JointedBeamConfig):
        raise ValueError(f"config must be a JointedBeamConfig, got {type(cfg).__name__}")
    if drive_function is not None and cfg.boundary != "clamped-driven":
        raise ValueError("drive_function needs boundary='clamped-driven'")
    make_joint = IwanJoint if joint_factory is None else joint_factory
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    h = cfg.thickness
    xb0 = cfg.beam_length - cfg.overlap
    nodes_a, elems_a, Le = _beam(mbs, cfg, 0.0, 0.0)
    nodes_b, elems_b, _ = _beam(mbs, cfg, xb0, h)

    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    m_ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    clamped = []

    def fix(node, coordinate, **kw):
        m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=coordinate))
        return mbs.AddObject(CoordinateConstraint(markerNumbers=[m_ground, m], **kw))

    for c in (0, 1, 3):                       # clamp: x, y and the slope y' of A's first node
        fix(nodes_a[0], c)
    drive = None
    if cfg.boundary == "clamped-driven":
        for c in (1, 3):                      # grip: no transverse motion or rotation
            fix(nodes_b[-1], c)
        if drive_function is None:
            drive = fix(nodes_b[-1], 0)
        else:
            def offset(mbs_, t, itemNumber, lOffset):
                return drive_function(t)
            drive = fix(nodes_b[-1], 0, offsetUserFunction=offset)

    mbs_clamped_nodes = [(nodes_a[0], (0, 1, 3))]
    if cfg.boundary == "clamped-driven":
        mbs_clamped_nodes.append((nodes_b[-1], (0, 1, 3)))

    # interface points, springs and joints
    pj = cfg.point_joint
    n = cfg.n_contact_points
    kn = cfg.normal_stiffness / n
    kt = {"iwan": 0.0, "linear": pj.KT, "rigid": cfg.rigid_stiffness}[cfg.joint_model]
    markers_a, markers_b, springs, connectors, joints = [], [], [], [], []
    if post_step is not None:
        mbs.SetPostStepUserFunction(post_step)
    for x in cfg.contact_x():
        ma = _surface_marker(mbs, elems_a, Le, 0.0, x, +0.5 * h)
        mb = _surface_marker(mbs, elems_b, Le, xb0, x, -0.5 * h)
        markers_a.append(ma)
        markers_b.append(mb)
        springs.append(mbs.AddObject(ObjectConnectorCartesianSpringDamper(
            markerNumbers=[ma, mb], stiffness=[kt, kn, 0.0], damping=[0.0, 0.0, 0.0])))
        if cfg.joint_model == "iwan":
            j = make_joint(pj)
            connectors.append(add_iwan_connector(mbs, [ma, mb], j, axis=[1.0, 0.0, 0.0]))
            joints.append(j)
    mbs.AddObject(ObjectGround())
    mbs.Assemble()
    for node, coords in mbs_clamped_nodes:
        i0 = mbs.GetNodeODE2Index(node)
        clamped += [i0 + c for c in coords]
    return JointedBeamModel(config=cfg, SC=SC, mbs=mbs, nodes_a=nodes_a, nodes_b=nodes_b,
                            elements_a=elems_a, elements_b=elems_b, connectors=connectors,
                            joints=joints, springs=springs, drive=drive, tip_node=nodes_b[-1],
                            clamped_coordinates=clamped, marker_a=markers_a, marker_b=markers_b,
                            drive_function=drive_function)
