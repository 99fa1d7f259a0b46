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

__all__ = ["check_specimen", "linear_system", "axis_rows", "contact_points"]


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
