"""The linear system of a 1-D :class:`~iwan_element.models.specimens.specimen.Specimen`: Timoshenko
beams, the contact points' normal springs, the boundary and the test setup.

From the beams' finite elements (:mod:`~iwan_element.models.beam.elements`):

* ``Kb``, ``M``: both beams;
* ``K0 = Kb + G_n^T diag(k_n,i) G_n`` plus the setup's springs: each contact point's normal
  spring ``k_n,i`` on its normal gap (the lap cannot open or close without it), a clamp's
  springs at beam A's root (``Setup.clamp``), a shaker's stinger and suspension;
* ``G``: the tangential slips of the contact points
  (:func:`~iwan_element.models.specimens.contact.beam_contact_points`); ``S``, ``E``: the transverse
  displacement at the sensor and at the excitation point.

Boundaries: ``"free-free"`` (3 rigid-body modes); ``"clamped-free"``: beam A's root (``u, w,
theta`` of its first node) held rigidly, or by the setup's clamp springs; ``"clamped-driven"``
(the quasi-static machine test): also beam B's last node held transversely (``w, theta``),
its axial displacement the prescribed ``drive`` coordinate. The setup's masses and shaker
enter through :func:`~iwan_element.models.linear.attach_setup`. The interface's tangential
law is not in these matrices: QSMA, harmonic balance and the Exudyn host
(:mod:`~iwan_element.models.simulation.host`) add it.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..linear.system import LinearSystem, attach_setup
from ..specimens.contact import beam_contact_points
from ..specimens.specimen import Specimen
from .elements import (
    NODE_DOFS,
    beam_matrices,
    beam_mesh,
    grip_coordinates,
    interface_rows,
    point_rows,
)

__all__ = ["beam_linear_system", "beam_axis_rows"]


def _structure_key(specimen: Specimen) -> Specimen:
    """The specimen with the fields that do not change K0, G, M normalised (cache key)."""
    return specimen.replace(
        friction=1.0,
        chi=0.0,
        beta=0.0,
        damping_floor=0.0,
        modal_damping=(),
        stiffness_per_area=1.0,
        amplitude_range=(1.0, 2.0),
        calibrated_range=None,
        effects=(),
    )


def beam_linear_system(specimen: Specimen) -> LinearSystem:
    """Linear matrices of a 1-D specimen (module docstring; cached on its geometry,
    material, contact layout and setup). The analyses read
    :func:`~iwan_element.models.reduced.dispatch.linear_system`, which also takes a solid.
    """
    return _linear_system(_structure_key(specimen))


def _fixed(s: Specimen, mesh) -> list:
    """Coordinates held rigidly by the boundary (module docstring)."""
    fixed = []
    if s.boundary in ("clamped-free", "clamped-driven") and s.setup.clamp is None:
        fixed += list(range(NODE_DOFS))
    if s.boundary == "clamped-driven":
        fixed += list(grip_coordinates(mesh)[1:])
    return fixed


@lru_cache(maxsize=16)
def _linear_system(key: Specimen) -> LinearSystem:
    s = key
    mesh = beam_mesh(s)
    Kb, M = beam_matrices(s, mesh)
    pts = beam_contact_points(s)
    G, Gn = interface_rows(s, pts.x, mesh)
    K0 = Kb + Gn.T @ (pts.normal_stiffness[:, None] * Gn)
    if s.setup.clamp is not None and s.boundary != "free-free":
        c = s.setup.clamp
        K0[np.arange(NODE_DOFS), np.arange(NODE_DOFS)] += (
            c.translational,
            c.translational,
            c.rotational,
        )
    W = point_rows(s, [s.sensor_position, s.excitation.position], mesh)[1]
    n = mesh.n_coordinates
    drive = None
    if s.boundary == "clamped-driven":
        drive = np.zeros(n)
        drive[grip_coordinates(mesh)[0]] = 1.0
    free = np.setdiff1d(np.arange(n), _fixed(s, mesh))
    ix = np.ix_(free, free)
    L = LinearSystem(
        M=M[ix],
        K0=K0[ix],
        Kb=Kb[ix],
        G=G[:, free],
        S=W[0, free],
        E=W[1, free],
        Gn=Gn[:, free],
        drive=None if drive is None else drive[free],
        free=free,
        n_coordinates=n,
        rigid_body_modes=3 if s.boundary == "free-free" else 0,
    )
    L = attach_setup(L, s.setup, lambda x: tuple(r[:, free] for r in point_rows(s, x, mesh)))
    assert L.E is not None  # the excitation row given above (attach_setup keeps or pads it)
    for A in (L.M, L.K0, L.Kb, L.G, L.S, L.E):
        A.setflags(write=False)
    return L


def beam_axis_rows(specimen: Specimen, positions) -> np.ndarray:
    """Rows mapping the free coordinates to the transverse displacement [m] of the beams'
    axis at ``positions`` [m] along the assembly (a 1-D array in ``[0, total_length]``, as
    :func:`~iwan_element.models.reduced.dispatch.axis_rows` checks it; the axis of
    ``sensor_position``; beam A up to its length, beam B beyond): shape
    ``(len(positions), n_free)`` (a setup's extra coordinates read zero).
    """
    return _axis_rows(_structure_key(specimen), tuple(float(v) for v in positions))


@lru_cache(maxsize=16)
def _axis_rows(key: Specimen, positions: tuple) -> np.ndarray:
    L = _linear_system(key)
    W = point_rows(key, positions)[1][:, L.free[: L.free.size - L.n_extra]]
    D = np.concatenate([W, np.zeros((W.shape[0], L.n_extra))], axis=1)
    D.setflags(write=False)
    return D
