"""Force-displacement loops: fit Segalman's four parameters to a measured loop
(:func:`fit_loops`) or to dissipation per cycle (:func:`fit_dissipation`), with their
identifiability, uncertainty and verdict; fit a force model to a record
(:func:`fit_force_model`); split a record into cycles; estimate its noise; make synthetic
test records (:func:`simulate_test`).

Imports :mod:`iwan_element.base`, :mod:`iwan_element.core` and :mod:`iwan_element.fitting`
only (and :mod:`iwan_element.plotting` inside the ``plot`` methods).
"""

from .cycles import Cycle, find_reversals, split_cycles
from .dissipation import fit_dissipation
from .fit import fit_loops
from .model_fit import ModelFit, fit_force_model
from .noise import NoiseEstimate, estimate_noise
from .result import FitResult, IdentifiabilityWarning
from .testdata import TestData, simulate_test

__all__ = [
    "fit_loops",
    "fit_dissipation",
    "FitResult",
    "IdentifiabilityWarning",
    "fit_force_model",
    "ModelFit",
    "estimate_noise",
    "NoiseEstimate",
    "split_cycles",
    "find_reversals",
    "Cycle",
    "simulate_test",
    "TestData",
]
