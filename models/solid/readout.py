"""Where a solid specimen is read along its axis: the z displacement of a section at a point
(the sensor's and the excitation's rows of a :class:`~iwan_element.models.solid.SolidSpecimen`)
from a least-squares fit over the nodes of the section slab there, and the reduced rows of
it every millimetre along the assembly (a ring-down's sensors).
"""

from __future__ import annotations

import numpy as np

from ..specimens.specimen import Specimen
from .mesh import SolidPart

AXIS_STEP = 1e-3  # grid of the stored sensor rows along the axis [m]


#: Nodes of the section slab that the z read-out at a point is fitted over.
SLAB_NODES = 24


def _point_weights(specimen: Specimen, a: SolidPart, b: SolidPart, xs: float):
    """``(idx, w)``: the z coordinates (in the coordinates [A's, B's], x, y, z per node) and
    weights whose sum ``w . u[idx]`` reads the section's z displacement at ``xs`` [m] along
    the assembly: a least-squares fit ``u_z = c0 + c1 dx + c2 dx^2 + c3 y`` over the
    :data:`SLAB_NODES` nodes of the section slab nearest ``xs`` (``dx = x - xs``; the ``y``
    term takes out a twist's z motion), evaluated at ``dx = 0``, ``y = 0``. A bending
    mode's z displacement is uniform over the section, so this is the beam's deflection
    there, wherever a face accelerometer sits; the nearest node alone is up to half an
    element off in x (2.3 mm at acc3 on a 12 mm mesh, 13 % of the second height-bending
    mode's reading there).
    """
    s = specimen
    on_b = xs > s.beam_length
    part, off = (b, 3 * len(a.positions)) if on_b else (a, 0)
    P = part.positions
    dx = P[:, 0] - xs
    near = np.argsort(np.abs(dx), kind="stable")[:SLAB_NODES]
    h = max(float(np.max(np.abs(dx[near]))), 1e-12)
    u = dx[near] / h
    V = np.column_stack([np.ones(near.size), u, u * u, P[near, 1] / h])
    w = np.linalg.pinv(V)[0]
    return off + 3 * near + 2, w


def _point_row(specimen: Specimen, a: SolidPart, b: SolidPart, xs: float) -> np.ndarray:
    """Row reading the z displacement at ``xs`` [m] along the assembly
    (:func:`_point_weights`): the sensor's, or the excitation's (a unit force there has
    this row as its load vector: its work is the force times that displacement).
    """
    S = np.zeros(3 * (len(a.positions) + len(b.positions)))
    idx, w = _point_weights(specimen, a, b, xs)
    np.add.at(S, idx, w)
    return S


def _axis_grid(specimen: Specimen, a: SolidPart, b: SolidPart, T, free):
    """``(x, rows)``: the reduced rows of the z displacement read as :func:`_point_row` reads
    the sensor's, at every millimetre ``x`` [m] along the assembly (where a ring-down's
    sensors are read).
    """
    x = np.arange(0.0, specimen.total_length + 0.5 * AXIS_STEP, AXIS_STEP)
    rows = np.zeros((x.size, T.shape[1]))
    for k, v in enumerate(x):
        idx, w = _point_weights(specimen, a, b, v)
        pos = np.minimum(np.searchsorted(free, idx), free.size - 1)
        ok = free[pos] == idx  # a clamped node reads zero
        rows[k] = w[ok] @ T[pos[ok]]
    return x, rows
