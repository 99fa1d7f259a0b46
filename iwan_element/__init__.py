"""iwan-element: Segalman's four-parameter Iwan bolted-joint model.

The physics core (this package's top level) depends only on numpy and scipy. The Exudyn
connector lives in :mod:`iwan_element.exudyn`, which is the only module importing exudyn.
"""
from .core.closed_form import (
    backbone,
    backbone_work,
    dissipation,
    dissipation_slope,
    force_amplitude,
    masing_ascending,
    masing_descending,
    masing_loop,
    normalized_backbone,
    secant_stiffness,
    tangent_stiffness,
)
from .diagnose import (CANDIDATES, Diagnosis, VibrationDiagnosis, diagnose, diagnose_vibration,
                        simulate_element_test)
from .core.discrete import DiscreteIwan, slider_distribution
from .effects import (EFFECTS, AsymmetricSlip, Backlash, BreakAway, PinningStiffness,
                      SlipDegradation, ViscousDamping, base_joint, make_effect)
from .identify.fit import FitResult, IdentifiabilityWarning, fit_dissipation, fit_loops
from .core.joint import IwanJoint
from .core.parameters import IwanParameters
from .core.protocol import JointElement, check_element
from .identify.curves import AmplitudeCurve
from .identify.testdata import Cycle, TestData, find_reversals, load_test, simulate_test, split_cycles

__version__ = "0.1.0"

__all__ = [
    "IwanParameters",
    "IwanJoint",
    "DiscreteIwan",
    "slider_distribution",
    "JointElement",
    "check_element",
    "EFFECTS",
    "make_effect",
    "base_joint",
    "ViscousDamping",
    "PinningStiffness",
    "Backlash",
    "SlipDegradation",
    "AsymmetricSlip",
    "BreakAway",
    "backbone",
    "backbone_work",
    "tangent_stiffness",
    "secant_stiffness",
    "force_amplitude",
    "dissipation",
    "dissipation_slope",
    "masing_loop",
    "normalized_backbone",
    "masing_descending",
    "masing_ascending",
    "load_test",
    "split_cycles",
    "find_reversals",
    "simulate_test",
    "TestData",
    "Cycle",
    "AmplitudeCurve",
    "fit_loops",
    "fit_dissipation",
    "FitResult",
    "IdentifiabilityWarning",
    "diagnose",
    "diagnose_vibration",
    "Diagnosis",
    "VibrationDiagnosis",
    "simulate_element_test",
    "CANDIDATES",
]
