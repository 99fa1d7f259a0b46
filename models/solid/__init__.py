"""The solid (finite-element) lap-jointed specimen: the two halves meshed (Netgen, or the
user's mesh), their contact patches and reduced linear system, and the SolidSpecimen that
the 1-D analyses accept (extra ``iwan-element[fem]`` to mesh).
"""

from .build import patch_layout, solid_preset, solid_specimen
from .mesh import SolidPart, bar_part, lap_beam_parts, part_from_fem, part_from_ngsolve
from .specimen import PatchLayout, SolidModel, SolidSpecimen, clamp_stiffness, solid_contact_points

__all__ = [
    "SolidSpecimen",
    "SolidModel",
    "PatchLayout",
    "solid_contact_points",
    "clamp_stiffness",
    "solid_specimen",
    "solid_preset",
    "patch_layout",
    "SolidPart",
    "part_from_fem",
    "part_from_ngsolve",
    "lap_beam_parts",
    "bar_part",
]
