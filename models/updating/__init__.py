"""Linear model updating on low-level test data, before any joint calibration: the
parameters a specimen has (material, boundary, setup, the stuck joint's stiffness) and
their priors, the modes' sensitivities to them, the prior band, and the update.
"""

from .band import prior_band
from .parameters import GROUPS, Updatable, parameter_value, updatable, with_parameters
from .result import LinearUpdateResult
from .sensitivities import (
    ModalState,
    matrix_derivatives,
    modal_sensitivities,
    modal_state,
    pair_modes,
)
from .update import MODEL_ERROR, linear_update

__all__ = [
    "Updatable",
    "GROUPS",
    "updatable",
    "parameter_value",
    "with_parameters",
    "ModalState",
    "modal_state",
    "matrix_derivatives",
    "modal_sensitivities",
    "pair_modes",
    "prior_band",
    "MODEL_ERROR",
    "LinearUpdateResult",
    "linear_update",
]
