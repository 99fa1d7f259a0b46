"""Solid finite-element parts of a lap-jointed beam: meshed with Netgen, or the user's own.

A :class:`SolidPart` is one body's linear finite-element data as ``exudyn.FEM.FEMinterface``
holds it: node positions, sparse mass and stiffness matrices with the nodal ``x, y, z`` of
each node together (exudyn's order; ``ImportMeshFromNGsolve`` reorders NGsolve's all-x,
all-y, all-z itself), and the triangles of its contact face (from the surface triangles all
of whose nodes lie in the contact node set).

Routes:

* :func:`lap_beam_parts` - the two halves of a specimen's lap-jointed beam from its
  dimensions (:class:`~iwan_element.models.specimens.specimen.Specimen`): Netgen OCC boxes,
  second-order tetrahedra, the lap faces named ``"lap"`` and meshed finer (``lap_mesh_size``);
* :func:`part_from_ngsolve` - an NGsolve mesh the user already has, the contact face given
  by its boundary name;
* :func:`part_from_fem` - any ``FEMinterface`` (``ImportFromAbaqusInputFile`` with
  ``ReadMassMatrixFromAbaqus``/``ReadStiffnessMatrixFromAbaqus``, ANSYS matrices, ...), the
  contact face given by a node set.

Frame (every route): ``x`` along the assembly from beam A's end, ``y`` across the width
(centred), ``z`` the height (bending direction), the lap plane at ``z = 0``; beam A below
it, beam B above. :func:`lap_beam_parts` cuts the bolt holes (``holes=True``); bolts and
washers are not meshed (the cone pressure is zero inside the holes).
NGsolve is the optional extra ``iwan-element[fem]``; it is imported only when meshing.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from iwan_element.base.validation import plain_number

from ..specimens.specimen import Specimen

__all__ = ["SolidPart", "part_from_fem", "part_from_ngsolve", "lap_beam_parts", "bar_part"]


@dataclass(frozen=True, eq=False)
class SolidPart:
    """One body's linear FE data (SI units).

    Attributes
    ----------
    name : str
    positions : ndarray, shape (n_nodes, 3)
        Node positions [m] in the assembly frame (module docstring).
    M, K : scipy.sparse.csr_matrix, shape (3 n_nodes, 3 n_nodes)
        Mass [kg] and stiffness [N/m] matrices, coordinates ``x, y, z`` per node.
    face_triangles : ndarray of int, shape (n_tri, 3)
        Linear triangles (node indices) of the contact face; empty for a part without one.
    fem : object
        The ``exudyn.FEM.FEMinterface`` it came from (for Exudyn's reduced bodies).
    """

    name: str
    positions: np.ndarray
    M: sp.csr_matrix
    K: sp.csr_matrix
    face_triangles: np.ndarray
    fem: object = field(default=None, repr=False)

    def __post_init__(self):
        n = 3 * len(self.positions)
        if self.M.shape != (n, n) or self.K.shape != (n, n):
            raise ValueError(
                f"M and K must be ({n}, {n}) for {n // 3} nodes (x, y, z per node), "
                f"got {self.M.shape} and {self.K.shape}"
            )

    @property
    def n_coordinates(self) -> int:
        """Coordinates of the mesh: ``x, y, z`` per node (``3 * len(positions)``)."""
        return 3 * len(self.positions)

    def face_areas(self) -> tuple[np.ndarray, np.ndarray]:
        """Centroids (n_tri, 3) [m] and areas (n_tri,) [m^2] of the contact face's triangles."""
        p = self.positions[self.face_triangles]
        area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        return p.mean(axis=1), area


def part_from_fem(fem, *, contact_nodes, name: str = "part") -> SolidPart:
    """A part from an ``exudyn.FEM.FEMinterface`` that holds nodes, mass and stiffness
    matrices and surface triangles (``VolumeToSurfaceElements`` makes them for an Abaqus
    import).

    Parameters
    ----------
    fem : exudyn.FEM.FEMinterface
    contact_nodes : sequence of int, keyword-only
        Node indices (0-based) of the contact face; the face is every surface triangle with
        all three nodes in the set.
    name : str, keyword-only
    """
    pos = np.asarray(fem.GetNodePositionsAsArray(), float)
    nodes = np.unique(np.asarray(contact_nodes, dtype=int))
    if nodes.size < 3 or nodes.min() < 0 or nodes.max() >= len(pos):
        raise ValueError(
            f"contact_nodes must hold >= 3 node indices in [0, {len(pos)}), "
            f"got {nodes.size} (range {nodes.min() if nodes.size else None}.."
            f"{nodes.max() if nodes.size else None})"
        )
    trigs = np.asarray(fem.GetSurfaceTriangles(), dtype=int).reshape(-1, 3)
    inset = np.zeros(len(pos), bool)
    inset[nodes] = True
    face = trigs[inset[trigs].all(axis=1)]
    if face.size == 0:
        raise ValueError(
            "contact_nodes span no surface triangle of the FE model (call "
            "fem.VolumeToSurfaceElements() after an Abaqus/ANSYS import)"
        )
    return SolidPart(
        name=name,
        positions=pos,
        M=sp.csr_matrix(fem.GetMassMatrix()),
        K=sp.csr_matrix(fem.GetStiffnessMatrix()),
        face_triangles=face,
        fem=fem,
    )


def part_from_ngsolve(
    mesh,
    *,
    contact_face: str,
    youngs_modulus: float,
    poissons_ratio: float,
    density: float,
    name: str = "part",
) -> SolidPart:
    """A part from an NGsolve mesh through ``FEMinterface.ImportMeshFromNGsolve`` (second
    order: the mesh is made second order in place, as exudyn does).

    Parameters
    ----------
    mesh : ngsolve.Mesh
    contact_face : str, keyword-only
        Boundary name of the contact face in the mesh.
    youngs_modulus, poissons_ratio, density : float, keyword-only
        [Pa], [-] in (-1, 0.5), [kg/m^3].
    name : str, keyword-only
    """
    from exudyn.FEM import FEMinterface

    if contact_face not in set(mesh.GetBoundaries()):
        raise ValueError(
            f"contact_face must be a boundary name of the mesh, one of "
            f"{sorted(set(mesh.GetBoundaries()))}, got {contact_face!r}"
        )
    for label, v, lo, hi in (
        ("youngs_modulus", youngs_modulus, 0.0, np.inf),
        ("poissons_ratio", poissons_ratio, -1.0, 0.5),
        ("density", density, 0.0, np.inf),
    ):
        v = plain_number(v)
        if not (isinstance(v, (int, float)) and lo < v < hi):
            raise ValueError(f"{label} must be a number in ({lo}, {hi}), got {v!r}")
    fem = FEMinterface()
    fem.ImportMeshFromNGsolve(
        mesh,
        density=float(density),
        youngsModulus=float(youngs_modulus),
        poissonsRatio=float(poissons_ratio),
        meshOrder=2,
        boundaryNamesList=[contact_face],
    )
    nodes = next(s["NodeNumbers"] for s in fem.nodeSets if s["Name"] == contact_face)
    return part_from_fem(fem, contact_nodes=nodes, name=name)


def _mesh_boxes(boxes, *, face_z, face_sign, mesh_size, face_mesh_size, holes=()):
    """Netgen mesh of the union of axis-aligned boxes ((x0,y0,z0), (x1,y1,z1)) less the
    vertical through-holes ``holes`` ((x, y, radius) [m]); the horizontal faces at
    ``z = face_z`` whose outward normal is ``face_sign * z`` named ``"lap"`` and meshed at
    ``face_mesh_size``.
    """
    try:
        import ngsolve as ngs
        from netgen.occ import Box, Cylinder, OCCGeometry, Pnt, Z
    except ImportError as err:
        raise ImportError(
            "meshing a solid specimen needs NGsolve: pip install "
            '"iwan-element[fem]" (or pip install ngsolve)'
        ) from err
    shape = None
    for lo, hi in boxes:
        b = Box(Pnt(*lo), Pnt(*hi))
        shape = b if shape is None else shape + b
    z0 = min(lo[2] for lo, _ in boxes)
    height = max(hi[2] for _, hi in boxes) - z0
    for x, y, r in holes:
        shape = shape - Cylinder(Pnt(x, y, z0 - height), Z, r=r, h=3 * height)
    zmid = np.mean([0.5 * (lo[2] + hi[2]) for lo, hi in boxes])
    for f in shape.faces:
        lo, hi = f.bounding_box  # OCC pads it by about 1e-7 m
        flat = abs(lo[2] - face_z) < 1e-6 and abs(hi[2] - face_z) < 1e-6
        if flat and np.sign(face_z - zmid) == face_sign:
            f.name = "lap"
            f.maxh = face_mesh_size
    return ngs.Mesh(OCCGeometry(shape).GenerateMesh(maxh=mesh_size))


def _check_sizes(specimen, mesh_size, lap_mesh_size):
    for label, v in (("mesh_size", mesh_size), ("lap_mesh_size", lap_mesh_size)):
        v = plain_number(v)
        if (
            isinstance(v, bool)
            or not isinstance(v, (int, float))
            or not 0 < v <= specimen.beam_length
        ):
            raise ValueError(
                f"{label} must be a length in (0, beam_length={specimen.beam_length}] m, got {v!r}"
            )


def lap_beam_parts(
    specimen: Specimen,
    *,
    mesh_size: float,
    lap_mesh_size: float,
    poissons_ratio: float = 0.3,
    holes: bool = True,
) -> tuple[SolidPart, SolidPart]:
    """The two halves of a specimen's lap-jointed beam, meshed (second-order tetrahedra).

    Beam A: ``x`` in ``[0, L]``, height ``thickness`` outside the lap, ``lap_thickness``
    inside it (``z`` in ``[-lap_thickness, 0]``); beam B mirrored above the lap plane
    (module docstring). For the Brake-Reuss halves (``lap_thickness = thickness/2``) the
    assembly is a straight bar of height ``thickness``; for plain stacked bars the halves'
    outer parts are offset by one thickness.

    Parameters
    ----------
    specimen : Specimen
    mesh_size, lap_mesh_size : float, keyword-only
        Largest element size [m] overall and on the lap faces.
    poissons_ratio : float, keyword-only
        [-] (the Specimen carries no Poisson's ratio; 0.3 for steel).
    holes : bool, keyword-only
        Cut the bolt holes (diameter ``bolt_diameter``, the hole of the cone pressure) through
        both lap halves; ``False`` meshes them solid. On the Brake-Reuss beam the holes
        remove a third of the width at the lap's centre line: they lower the height-bending
        modes and raise the in-plane one (docs/solid.md).

    Returns
    -------
    (SolidPart, SolidPart)
        Beam A and beam B, each with its lap face as contact face.
    """
    if not isinstance(specimen, Specimen):
        raise TypeError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    _check_sizes(specimen, mesh_size, lap_mesh_size)
    s = specimen
    L, ls, w, T, tl = s.beam_length, s.lap_start, 0.5 * s.width, s.thickness, s.lap_thickness
    end = 2 * L - s.overlap
    a_boxes = [((0.0, -w, -tl), (ls, w, T - tl)), ((ls, -w, -tl), (L, w, 0.0))]
    b_boxes = [((ls, -w, 0.0), (L, w, tl)), ((L, -w, tl - T), (end, w, tl))]
    if not isinstance(holes, bool):
        raise TypeError(f"holes must be True or False, got {holes!r}")
    cut = [(ls + xb, 0.0, 0.5 * s.bolt_diameter) for xb in s.bolt_positions] if holes else []
    parts = []
    for name, boxes, sign in (("A", a_boxes, +1), ("B", b_boxes, -1)):
        mesh = _mesh_boxes(
            boxes,
            face_z=0.0,
            face_sign=sign,
            mesh_size=mesh_size,
            face_mesh_size=lap_mesh_size,
            holes=cut,
        )
        parts.append(
            part_from_ngsolve(
                mesh,
                contact_face="lap",
                name=name,
                youngs_modulus=s.youngs_modulus,
                poissons_ratio=poissons_ratio,
                density=s.density,
            )
        )
    return parts[0], parts[1]


def bar_part(
    length: float,
    width: float,
    height: float,
    *,
    youngs_modulus: float,
    poissons_ratio: float,
    density: float,
    mesh_size: float,
) -> SolidPart:
    """A jointless rectangular bar ``[0, length] x [-width/2, width/2] x [-height/2,
    height/2]`` [m], second-order tetrahedra (the Euler-Bernoulli check); its top face is the
    contact face.
    """
    for label, v in (
        ("length", length),
        ("width", width),
        ("height", height),
        ("mesh_size", mesh_size),
    ):
        v = plain_number(v)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
            raise ValueError(f"{label} must be a length > 0 [m], got {v!r}")
    mesh = _mesh_boxes(
        [((0.0, -0.5 * width, -0.5 * height), (length, 0.5 * width, 0.5 * height))],
        face_z=0.5 * height,
        face_sign=+1,
        mesh_size=mesh_size,
        face_mesh_size=mesh_size,
    )
    return part_from_ngsolve(
        mesh,
        contact_face="lap",
        name="bar",
        youngs_modulus=youngs_modulus,
        poissons_ratio=poissons_ratio,
        density=density,
    )
