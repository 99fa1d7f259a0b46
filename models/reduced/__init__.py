"""The analyses' view of a specimen, 1-D or solid: the dispatch over the two bodies' rooms,
the stuck-interface modes and the one reduced model the frequency-domain routes read, and
the linear damping floor as a modal damping matrix.
"""

from .damping import FloorDamping, FloorWork, floor_damping
from .dispatch import (
    axis_rows,
    bolt_groups,
    check_kept_mode,
    check_specimen,
    contact_points,
    kept_modes,
    linear_system,
)
from .model import ReducedModel, reduced_model, reduction_error, stuck_key, stuck_modes

__all__ = [
    "check_specimen",
    "linear_system",
    "axis_rows",
    "contact_points",
    "kept_modes",
    "check_kept_mode",
    "bolt_groups",
    "ReducedModel",
    "reduced_model",
    "reduction_error",
    "stuck_modes",
    "stuck_key",
    "FloorDamping",
    "floor_damping",
    "FloorWork",
]
