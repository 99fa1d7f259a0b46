"""A specimen's interface calibrated on test data: from a measured amplitude curve (QSMA
fitted to it, other modes' floors), from a joint or modal Iwan fit, and a whole hammer test
predicted from one calibrated mode, and the discrepancy workflow across its modes (an effect
named on one mode, placed in the joint, checked on every mode).
"""

from .hammer import mode_bands, predict_hammer_test, release_amplitudes
from .hammer_modes import diagnose_hammer_test
from .hammer_result import HammerPrediction
from .joint import interface_from_joint, interface_from_modal_iwan
from .mode_diagnosis import default_placements, diagnose_modes
from .mode_diagnosis_result import ModesDiagnosis
from .vibration import CalibrationResult, calibrate, measured_amplitude_curve, modal_floor

__all__ = [
    "calibrate",
    "CalibrationResult",
    "measured_amplitude_curve",
    "modal_floor",
    "interface_from_joint",
    "interface_from_modal_iwan",
    "predict_hammer_test",
    "HammerPrediction",
    "mode_bands",
    "release_amplitudes",
    "diagnose_modes",
    "diagnose_hammer_test",
    "ModesDiagnosis",
    "default_placements",
]
