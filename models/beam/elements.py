"""The 1-D lap-jointed beam as planar Timoshenko finite elements: matrices and read-out rows.

Each beam of a :class:`~iwan_element.models.specimens.specimen.Specimen` is a chain of two-node
elements with three coordinates per node, ``(u, w, theta)``: axial and transverse
displacement of the axis and the rotation of the cross-section [m, m, rad], positive
anticlockwise (``x`` along the assembly, ``y`` up, the bending direction). A point at height
``y`` above a beam's axis moves axially by ``u - y theta``.

Bending: the interdependent-interpolation element of Friedman and Kosmatka (Computers &
Structures 47:473-481, 1993), with ``Phi = 12 E I / (kappa G A l^2)``:

    N_w     = [1 + Phi - Phi s - 3 s^2 + 2 s^3,  l (s (1 + Phi/2) - s^2 (2 + Phi/2) + s^3),
               Phi s + 3 s^2 - 2 s^3,            l (-s Phi/2 - s^2 (1 - Phi/2) + s^3)] / (1 + Phi)
    N_theta = [6 (s^2 - s) / l,  1 + Phi - (4 + Phi) s + 3 s^2,
               -6 (s^2 - s) / l, -(2 - Phi) s + 3 s^2] / (1 + Phi)

(``s = x / l``): cubic deflection and quadratic rotation that solve the static Timoshenko
equations exactly, so the stiffness ``int EI theta'^2 + kappa G A (w' - theta)^2`` is the
exact one of a uniform element and the consistent mass
``int rho A N_w^T N_w + rho I N_theta^T N_theta`` carries the rotary inertia. With
``beam_theory="euler-bernoulli"``, ``Phi = 0`` (Hermite cubics, ``theta = w'``) and no rotary
inertia. Axial: linear bar elements, consistent mass. Integrals by 4-point Gauss quadrature
(exact for these polynomials). Shear modulus ``G = E / (2 (1 + nu))``, shear coefficient
``kappa`` (``Specimen.shear_coefficient``, 5/6 for a rectangle); docs/equations.md
section 12.

Geometry (as the specimens describe it): beam A's axis at ``y = 0`` from ``x = 0`` to
``beam_length``, beam B's at ``y = lap_thickness`` from ``lap_start``; elements of height
``lap_thickness`` in the lap and ``thickness`` outside. The axis is kept straight through a
step (the Brake-Reuss halves): the outer part's eccentricity (``thickness/4``) is neglected,
which changes only the coupling of axial and bending motion.

Rows (linear maps of the coordinates, exact for the interpolation): the contact points'
tangential slips ``u_B + (t/2) theta_B - (u_A - (t/2) theta_A)`` (beam B's lower face minus
beam A's upper face, ``t = lap_thickness``) and normal gaps ``w_B - w_A``; a point's
transverse displacement on the axis (beam A up to ``beam_length``, beam B beyond: the
sensor, the excitation, the attachments).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..specimens.contact import beam_contact_points
from ..specimens.specimen import Specimen

__all__ = [
    "BeamMesh",
    "beam_mesh",
    "element_matrices",
    "beam_matrices",
    "point_rows",
    "interface_rows",
    "grip_coordinates",
    "NODE_DOFS",
]

_GAUSS_S, _GAUSS_W = np.polynomial.legendre.leggauss(4)
_GAUSS_S = 0.5 * (_GAUSS_S + 1.0)
_GAUSS_W = 0.5 * _GAUSS_W
NODE_DOFS = 3  # u, w, theta


def _bending_shapes(s, l, phi):
    """``(N_w, N_theta)`` at ``s`` in [0, 1] of an element of length ``l`` [m] and shear
    parameter ``phi`` (module docstring); each shape (4,) over ``(w1, th1, w2, th2)``.
    """
    d = 1.0 + phi
    nw = (
        np.array(
            [
                1 + phi - phi * s - 3 * s * s + 2 * s**3,
                l * (s * (1 + phi / 2) - s * s * (2 + phi / 2) + s**3),
                phi * s + 3 * s * s - 2 * s**3,
                l * (-s * phi / 2 - s * s * (1 - phi / 2) + s**3),
            ]
        )
        / d
    )
    nt = (
        np.array(
            [
                6 * (s * s - s) / l,
                1 + phi - (4 + phi) * s + 3 * s * s,
                -6 * (s * s - s) / l,
                -(2 - phi) * s + 3 * s * s,
            ]
        )
        / d
    )
    return nw, nt


def _bending_derivatives(s, l, phi):
    """``(dN_w/dx, dN_theta/dx)`` at ``s`` (the strains' shapes)."""
    d = 1.0 + phi
    dw = np.array(
        [
            -phi - 6 * s + 6 * s * s,
            l * ((1 + phi / 2) - 2 * s * (2 + phi / 2) + 3 * s * s),
            phi + 6 * s - 6 * s * s,
            l * (-phi / 2 - 2 * s * (1 - phi / 2) + 3 * s * s),
        ]
    ) / (d * l)
    dt = np.array(
        [6 * (2 * s - 1) / l, -(4 + phi) + 6 * s, -6 * (2 * s - 1) / l, -(2 - phi) + 6 * s]
    ) / (d * l)
    return dw, dt


def element_matrices(
    length: float,
    *,
    E: float,
    G: float,
    kappa: float,
    rho: float,
    area: float,
    inertia: float,
    timoshenko: bool = True,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Stiffness and mass of one element, ``(K, M)``, each (6, 6) over
    ``(u1, w1, th1, u2, w2, th2)`` [N/m, N, N m; kg, kg m, kg m^2] (module docstring).
    """
    l = float(length)
    EI, GA = E * inertia, kappa * G * area
    phi = 12.0 * EI / (GA * l * l) if timoshenko else 0.0
    rot = rho * inertia if timoshenko else 0.0
    kb, mb = np.zeros((4, 4)), np.zeros((4, 4))
    for s, wq in zip(_GAUSS_S, _GAUSS_W):
        nw, nt = _bending_shapes(s, l, phi)
        dw, dt = _bending_derivatives(s, l, phi)
        gamma = dw - nt
        kb += (
            wq * l * (EI * np.outer(dt, dt) + (GA * np.outer(gamma, gamma) if timoshenko else 0.0))
        )
        mb += wq * l * (rho * area * np.outer(nw, nw) + rot * np.outer(nt, nt))
    K, M = np.zeros((6, 6)), np.zeros((6, 6))
    ia, ib = [0, 3], [1, 2, 4, 5]
    K[np.ix_(ia, ia)] = E * area / l * np.array([[1.0, -1.0], [-1.0, 1.0]])
    M[np.ix_(ia, ia)] = rho * area * l / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    K[np.ix_(ib, ib)] = 0.5 * (kb + kb.T)
    M[np.ix_(ib, ib)] = 0.5 * (mb + mb.T)
    return K, M


@dataclass(frozen=True)
class BeamMesh:
    """Nodes and elements of the two beams.

    Attributes
    ----------
    x_a, x_b : ndarray
        Node positions of beam A and beam B along the assembly [m].
    h_a, h_b : ndarray
        Height of each element [m].
    y_b : float
        Height of beam B's axis above beam A's [m] (``lap_thickness``).
    """

    x_a: np.ndarray
    x_b: np.ndarray
    h_a: np.ndarray
    h_b: np.ndarray
    y_b: float

    @property
    def n_nodes(self) -> int:
        """Number of nodes of both beams (``x_a.size + x_b.size``)."""
        return int(self.x_a.size + self.x_b.size)

    @property
    def n_coordinates(self) -> int:
        """Coordinates of the beams (3 per node)."""
        return NODE_DOFS * self.n_nodes


def beam_mesh(specimen: Specimen) -> BeamMesh:
    """Element boundaries of both beams: in the lap a node at every contact point
    (:func:`~iwan_element.models.specimens.contact.beam_contact_points`; at least 4 elements), so
    that the points' slips are independent coordinates of the Exudyn host; outside it
    ``n_elements`` minus the lap's share of them by length (at least 2).
    """
    s = specimen
    n_lap = max(4, int(round(s.n_elements * s.overlap / s.beam_length)))
    n_out = max(2, s.n_elements - n_lap)
    inner = np.unique(np.clip(beam_contact_points(s).x - s.lap_start, 0.0, s.overlap))
    lap = np.unique(np.concatenate([[0.0, s.overlap], inner]))
    lap = lap[np.concatenate([[True], np.diff(lap) > 1e-9 * s.overlap])]
    while lap.size < 5:  # at least 4 elements: halve the longest
        k = int(np.argmax(np.diff(lap)))
        lap = np.insert(lap, k + 1, 0.5 * (lap[k] + lap[k + 1]))
    out = np.linspace(0.0, s.lap_start, n_out + 1)
    x_a = np.concatenate([out, s.lap_start + lap[1:]])
    x_b = s.lap_start + np.concatenate([lap, s.overlap + out[1:]])
    n_lap = lap.size - 1
    h_a = np.array([s.thickness] * n_out + [s.lap_thickness] * n_lap)
    h_b = np.array([s.lap_thickness] * n_lap + [s.thickness] * n_out)
    return BeamMesh(x_a=x_a, x_b=x_b, h_a=h_a, h_b=h_b, y_b=s.lap_thickness)


def _phi(specimen: Specimen, h: float, l: float) -> float:
    if specimen.beam_theory != "timoshenko":
        return 0.0
    E, b = specimen.youngs_modulus, specimen.width
    G = E / (2.0 * (1.0 + specimen.poissons_ratio))
    return 12.0 * E * (b * h**3 / 12.0) / (specimen.shear_coefficient * G * b * h * l * l)


def beam_matrices(
    specimen: Specimen, mesh: BeamMesh | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Stiffness and mass of both beams on all their coordinates, ``(K, M)`` (dense,
    ``(3 n_nodes, 3 n_nodes)``; beam A's nodes first), with no boundary condition and no
    interface.
    """
    s = specimen
    mesh = beam_mesh(s) if mesh is None else mesh
    n = mesh.n_coordinates
    K, M = np.zeros((n, n)), np.zeros((n, n))
    E, b = s.youngs_modulus, s.width
    G = E / (2.0 * (1.0 + s.poissons_ratio))
    off = 0
    for x, h in ((mesh.x_a, mesh.h_a), (mesh.x_b, mesh.h_b)):
        for e, he in enumerate(h):
            ke, me = element_matrices(
                x[e + 1] - x[e],
                E=E,
                G=G,
                kappa=s.shear_coefficient,
                rho=s.density,
                area=b * he,
                inertia=b * he**3 / 12.0,
                timoshenko=s.beam_theory == "timoshenko",
            )
            i = off + NODE_DOFS * e
            K[i : i + 6, i : i + 6] += ke
            M[i : i + 6, i : i + 6] += me
        off += NODE_DOFS * x.size
    return K, M


def _beam_rows(specimen: Specimen, mesh: BeamMesh, beam: str, x: float):
    """``(row_u, row_w, row_theta)`` over all beam coordinates at ``x`` [m] on the axis of
    ``beam`` ("a" or "b").
    """
    nodes, heights = (mesh.x_a, mesh.h_a) if beam == "a" else (mesh.x_b, mesh.h_b)
    off = 0 if beam == "a" else NODE_DOFS * mesh.x_a.size
    e = int(np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, heights.size - 1))
    l = float(nodes[e + 1] - nodes[e])
    sc = min(max((x - nodes[e]) / l, 0.0), 1.0)
    nw, nt = _bending_shapes(sc, l, _phi(specimen, float(heights[e]), l))
    i = off + NODE_DOFS * e
    ru, rw, rt = (np.zeros(mesh.n_coordinates) for _ in range(3))
    ru[[i, i + 3]] = 1.0 - sc, sc
    rw[[i + 1, i + 2, i + 4, i + 5]] = nw
    rt[[i + 1, i + 2, i + 4, i + 5]] = nt
    return ru, rw, rt


def point_rows(
    specimen: Specimen, positions, mesh: BeamMesh | None = None
) -> tuple[NDArray[np.float64], ...]:
    """``(U, W, Theta)``: rows (one per position) of the axial and transverse displacement and
    the rotation on the beams' axis at ``positions`` [m] along the assembly (beam A up to
    its length, beam B beyond), over all beam coordinates.
    """
    mesh = beam_mesh(specimen) if mesh is None else mesh
    rows = [
        _beam_rows(specimen, mesh, "a" if x <= specimen.beam_length else "b", float(x))
        for x in np.atleast_1d(np.asarray(positions, float))
    ]
    return tuple(np.array([r[k] for r in rows]) for k in range(3))


def interface_rows(
    specimen: Specimen, x, mesh: BeamMesh | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(G, G_n)``: the tangential slips and normal gaps of the contact points at ``x`` [m]
    (module docstring), rows over all beam coordinates.
    """
    mesh = beam_mesh(specimen) if mesh is None else mesh
    half = 0.5 * specimen.lap_thickness
    G, Gn = [], []
    for xi in np.atleast_1d(np.asarray(x, float)):
        ua, wa, ta = _beam_rows(specimen, mesh, "a", float(xi))
        ub, wb, tb = _beam_rows(specimen, mesh, "b", float(xi))
        G.append((ub + half * tb) - (ua - half * ta))
        Gn.append(wb - wa)
    return np.array(G), np.array(Gn)


def grip_coordinates(mesh: BeamMesh) -> np.ndarray:
    """Beam B's last node's ``u, w, theta`` (the machine grip of the quasi-static test); beam
    A's first node's are ``0, 1, 2`` (the clamp).
    """
    return mesh.n_coordinates - NODE_DOFS + np.arange(NODE_DOFS)
