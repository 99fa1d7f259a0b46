"""What a lap-jointed specimen is: its validated description, the published presets, the
test setup it carries, and the contact pressure and contact points of its lap.
"""

from .contact import ContactPoints, beam_contact_points, points_from_forces, pressure_field
from .effects import InterfaceEffect, SpecimenEffect
from .presets import PRESET_SETUPS, PRESETS, preset
from .setups import Clamp, PointMass, Setup, Shaker
from .specimen import Excitation, InterfaceModel, Specimen

__all__ = [
    "Specimen",
    "InterfaceModel",
    "Excitation",
    "SpecimenEffect",
    "InterfaceEffect",
    "preset",
    "PRESETS",
    "PRESET_SETUPS",
    "Setup",
    "PointMass",
    "Shaker",
    "Clamp",
    "ContactPoints",
    "pressure_field",
    "beam_contact_points",
    "points_from_forces",
]
