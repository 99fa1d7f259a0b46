"""The analyses that read a specimen's modes without a time simulation: quasi-static modal
analysis (QSMA: one mode's frequency and damping against amplitude), harmonic balance,
frequency responses and nonlinear modes on the reduced model, and the specimen's vibration
effects in their modal form and in the joint (:mod:`.interface`, :mod:`.interface_fit`), and
the linear targets of a stepped-sine level read through the specimen's own amplitude
dependence.
"""

from .effects import ZeroElement, effect_stack
from .frequency import frequency_response, harmonic_balance, nonlinear_mode, specimen_system
from .interface import InterfaceLaws, interface_laws, point_weights, stiffness_cap
from .interface_fit import map_modal_effect
from .limits import SIZE_LENGTH_FRACTION, macroslip_report, size_limit, size_warnings
from .qsma import (
    extrapolation_warnings,
    linear_modes,
    modal_amplitude_curve,
    natural_frequencies,
    resolve_interface_effects,
    static_modal_load,
)
from .sweep_targets import drive_point_modes, sweep_level_targets

__all__ = [
    "modal_amplitude_curve",
    "linear_modes",
    "natural_frequencies",
    "static_modal_load",
    "extrapolation_warnings",
    "harmonic_balance",
    "frequency_response",
    "nonlinear_mode",
    "specimen_system",
    "ZeroElement",
    "effect_stack",
    "InterfaceLaws",
    "interface_laws",
    "point_weights",
    "stiffness_cap",
    "map_modal_effect",
    "resolve_interface_effects",
    "size_limit",
    "size_warnings",
    "macroslip_report",
    "SIZE_LENGTH_FRACTION",
    "sweep_level_targets",
    "drive_point_modes",
]
