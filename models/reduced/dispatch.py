"""What every analysis reads of a specimen, for the 1-D beams and the solid bodies alike.

The analyses (QSMA, the reduced model, harmonic balance, updating, the Exudyn host) accept a
1-D :class:`~iwan_element.models.specimens.specimen.Specimen` or a
:class:`~iwan_element.models.solid.specimen.SolidSpecimen` and read it through these four
functions, which hand each kind to its own room: the 1-D beams' linear system and axis rows
(:mod:`~iwan_element.models.beam.assembly`) and the pressure strips' contact points
(:mod:`~iwan_element.models.specimens.contact`), or the solid's reduced system, stored axis
rows and patches (:mod:`~iwan_element.models.solid.specimen`).
"""

from __future__ import annotations

import numpy as np

from ..beam.assembly import beam_axis_rows, beam_linear_system
from ..linear.system import LinearSystem
from ..solid.specimen import SolidSpecimen
from ..specimens.contact import ContactPoints, beam_contact_points
from ..specimens.specimen import Specimen

__all__ = [
    "check_specimen",
    "linear_system",
    "axis_rows",
    "contact_points",
    "kept_modes",
    "check_kept_mode",
    "bolt_groups",
]


def check_specimen(specimen) -> Specimen | SolidSpecimen:
    """``specimen`` if it is a 1-D :class:`Specimen` or a :class:`SolidSpecimen` (what every
    analysis of the beam model accepts), else ValueError naming it.
    """
    if not isinstance(specimen, (Specimen, SolidSpecimen)):
        raise ValueError(
            f"specimen must be a Specimen or SolidSpecimen, got {type(specimen).__name__}"
        )
    return specimen


def linear_system(specimen: Specimen | SolidSpecimen) -> LinearSystem:
    """Linear matrices of a specimen: the 1-D beams'
    (:func:`~iwan_element.models.beam.assembly.beam_linear_system`, cached on its geometry,
    material, contact layout and setup), or the reduced system a
    :class:`~iwan_element.models.solid.specimen.SolidSpecimen` carries.
    """
    if isinstance(specimen, SolidSpecimen):
        return specimen.linear_system()
    return beam_linear_system(specimen)


def axis_rows(specimen: Specimen | SolidSpecimen, positions) -> np.ndarray:
    """Rows mapping the free coordinates to the transverse displacement [m] of the beams'
    axis at ``positions`` [m] along the assembly (the axis of ``sensor_position``; beam A up
    to its length, beam B beyond): shape ``(len(positions), n_free)`` (a setup's extra
    coordinates read zero). A :class:`~iwan_element.models.solid.specimen.SolidSpecimen`
    reads its stored rows (:meth:`~iwan_element.models.solid.specimen.SolidSpecimen.axis_rows`).
    """
    x = np.atleast_1d(np.asarray(positions, float))
    if (
        x.ndim != 1
        or x.size == 0
        or not np.all(np.isfinite(x))
        or np.any(x < 0)
        or np.any(x > specimen.total_length)
    ):
        raise ValueError(
            f"positions must be a non-empty sequence in [0, "
            f"{specimen.total_length:.6g}] m, got {positions!r}"
        )
    if isinstance(specimen, SolidSpecimen):
        rows = specimen.axis_rows(x)
        return np.concatenate(
            [rows, np.zeros((rows.shape[0], linear_system(specimen).n_extra))], axis=1
        )
    return beam_axis_rows(specimen, x)


def contact_points(specimen: Specimen | SolidSpecimen) -> ContactPoints:
    """Contact points, normal forces and Iwan elements of a specimen's interface: the 1-D
    pressure strips (:func:`~iwan_element.models.specimens.contact.beam_contact_points`) or
    a solid's patches (two elements each,
    :meth:`~iwan_element.models.solid.specimen.SolidSpecimen.contact_points`).
    """
    if isinstance(specimen, SolidSpecimen):
        return specimen.contact_points()
    return beam_contact_points(specimen)


def kept_modes(specimen: Specimen | SolidSpecimen) -> int | None:
    """How many of the specimen's lowest stuck modes (rigid-body ones included) its linear
    system holds as modes: ``None`` for the 1-D beams (every mode of their finite elements);
    for a :class:`~iwan_element.models.solid.specimen.SolidSpecimen` the rigid-body modes and
    the ``n_modes`` elastic modes its reduction kept
    (:func:`~iwan_element.models.solid.solid_specimen`). The rest of a solid's reduced basis
    are the patches' static attachment shapes: their Ritz frequencies are not the
    structure's (2.7-2.9 x too high on the Brake-Reuss beam kept with 4 modes against 12).
    """
    if not isinstance(specimen, SolidSpecimen):
        return None
    n = specimen.model.info.get("n_modes")
    return None if n is None else int(n) + _rigid(specimen)


def _rigid(solid: SolidSpecimen) -> int:
    """Rigid-body modes of a solid's reduced system (6 free-free, 0 clamped)."""
    return int(solid.model.system.rigid_body_modes)


def check_kept_mode(
    specimen: Specimen | SolidSpecimen, index: int, *, name: str, value, offset: int
) -> None:
    """ValueError naming ``name`` (= ``value``) when the stuck mode of 0-based ``index``
    (rigid-body modes counted) lies beyond :func:`kept_modes`; ``value`` counts the modes
    from ``offset`` (0 for a count of modes, the modes below the first elastic one for an
    elastic mode number), so the largest it may be is ``kept_modes - offset``.
    """
    kept = kept_modes(specimen)
    if kept is None or index < kept or not isinstance(specimen, SolidSpecimen):
        return
    limit = kept - offset
    rigid = _rigid(specimen)
    raise ValueError(
        f"{name} must be <= {limit} for this solid, got {value}: its reduction kept its "
        f"{kept} lowest modes ({rigid} rigid-body, {kept - rigid} elastic: n_modes="
        f"{kept - rigid} of solid_specimen / solid_preset); the rest of its reduced basis are "
        "the contact patches' attachment shapes, not modes of the structure (their "
        f"frequencies are too high): build the solid with n_modes >= "
        f"{index + 1 - rigid} for this"
    )


def bolt_groups(specimen: Specimen | SolidSpecimen) -> tuple:
    """The contact points around each bolt, ``((label, indices), ...)``: each point with the
    bolt nearest to it along the lap (for a solid only its patches' ``x`` elements, the
    slip of the height-bending modes: a patch's ``y`` element barely slips in them). The
    groups the frequency-domain and QSMA results name when a bolt's contact is fully
    slipped (:func:`iwan_element.harmonic.macroslip_lines`).
    """
    pts = contact_points(specimen)
    idx = np.arange(len(pts))
    if isinstance(specimen, SolidSpecimen):
        idx = idx[0::2]
    xb = specimen.lap_start + np.asarray(specimen.bolt_positions)
    near = np.argmin(np.abs(pts.x[idx, None] - xb[None, :]), axis=1)
    return tuple(
        (f"bolt {k + 1} (x = {xb[k]:.4g} m)", tuple(int(i) for i in idx[near == k]))
        for k in range(xb.size)
        if np.any(near == k)
    )
