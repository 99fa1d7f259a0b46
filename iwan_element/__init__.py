"""iwan-element: Segalman's four-parameter Iwan bolted-joint model.

The physics core (this package's top level) depends only on numpy, scipy and numba. The Exudyn
connector lives in :mod:`iwan_element.exudyn`, which is the only module importing exudyn.
"""

import importlib.abc
import importlib.util
import sys
from importlib.machinery import ModuleSpec
from importlib.metadata import version as _version
from pathlib import Path

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
from .core.discrete import DiscreteIwan, slider_distribution
from .core.joint import IwanJoint
from .core.joint_bank import IwanJointBank
from .core.modal import harmonic_stiffness, modal_iwan_curve, modal_ringdown
from .core.modal_ringdown import ModalRingdown
from .core.parameters import IwanParameters
from .core.protocol import JointElement, check_element
from .diagnose import (
    BatchDiagnosis,
    CampaignFit,
    Diagnosis,
    VibrationDiagnosis,
    diagnose,
    diagnose_many,
    diagnose_vibration,
    fit_campaign,
    loop_candidates,
    simulate_element_test,
)
from .effects import (
    EFFECTS,
    AsymmetricSlip,
    Backlash,
    BreakAway,
    Hardening,
    MacroslipOnset,
    PinningStiffness,
    SlipDegradation,
    ViscousDamping,
    base_joint,
    make_effect,
)
from .ensemble import (
    EnsembleResult,
    ParameterUncertainty,
    PredictionBands,
    SingleModeSystem,
    parameter_grid,
    parameter_samples,
    propagate_uncertainty,
    run_ensemble,
)
from .identify.decays.curve import amplitude_curve
from .identify.decays.fit import fit_decay
from .identify.decays.modes import free_decay_modes
from .identify.files.csv_input import load_test
from .identify.files.formats import UffRecord, read_sweep_csv, read_uff
from .identify.files.vibration import read_vibration_csv
from .identify.loops.cycles import Cycle, find_reversals, split_cycles
from .identify.loops.dissipation import fit_dissipation
from .identify.loops.fit import fit_loops
from .identify.loops.model_fit import ModelFit, fit_force_model
from .identify.loops.noise import NoiseEstimate, estimate_noise
from .identify.loops.result import FitResult, IdentifiabilityWarning
from .identify.loops.testdata import TestData, simulate_test
from .identify.modal.curves import AmplitudeCurve
from .identify.modal.fit import ModalIwanFit, fit_modal_iwan
from .identify.modal.mode_target import ModeTarget, mac
from .identify.modal.targets import ModalTargets
from .identify.sweeps.frf_modes import frf_modes, sweep_modes
from .identify.sweeps.stepped_sine import stepped_sine_curve
from .identify.sweeps.sweep import sweep_curve

__version__ = _version("iwan-element")


class _SourceTreeModels(importlib.abc.MetaPathFinder):
    """Finds ``iwan_element.models`` in the checkout's top-level ``models/`` folder.

    An install maps ``models/`` into the package (pyproject's ``package-dir``), but a Python
    started at the checkout's root (a notebook, ``python -c``, a REPL) imports this package from
    the source tree, which hides the installed one and has no ``models`` inside, so
    ``iwan_element.models`` was not found after a non-editable install. This finder answers that
    one name only, with the ``models/`` beside the ``iwan_element/`` actually imported, so the
    package and its models always come from the same tree; the subpackages of ``models`` then
    follow from its ``__path__`` as usual. It is installed only when the package is imported from
    a source tree (never from an installed package, which holds ``models/`` itself) and is put
    first so that an editable install of another checkout cannot pair this tree's package with
    its models. Extending this package's ``__path__`` with the checkout's root would do the same
    but also make ``tests``, ``examples`` and ``setup`` importable as ``iwan_element.*``.
    """

    def __init__(self, folder: Path) -> None:
        self.folder = folder

    def find_spec(self, fullname, path=None, target=None) -> ModuleSpec | None:
        if fullname != f"{__name__}.models":
            return None
        return importlib.util.spec_from_file_location(
            fullname, self.folder / "__init__.py", submodule_search_locations=[str(self.folder)]
        )


def _find_models_in_the_source_tree() -> None:
    here = Path(__file__).resolve().parent
    models = here.parent / "models"
    if (here / "models").exists() or not (models / "__init__.py").is_file():
        return  # an installed package (models inside) or no checkout around it
    if not (here.parent / "pyproject.toml").is_file():
        return
    if not any(isinstance(f, _SourceTreeModels) for f in sys.meta_path):
        sys.meta_path.insert(0, _SourceTreeModels(models))


_find_models_in_the_source_tree()

__all__ = [
    # the paper's closed forms, in the order of core.closed_form.__all__
    "backbone",
    "tangent_stiffness",
    "secant_stiffness",
    "force_amplitude",
    "dissipation",
    "dissipation_slope",
    "masing_loop",
    "backbone_work",
    "normalized_backbone",
    "masing_descending",
    "masing_ascending",
    "IwanParameters",
    "IwanJoint",
    "IwanJointBank",
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
    "Hardening",
    "MacroslipOnset",
    "load_test",
    "split_cycles",
    "find_reversals",
    "simulate_test",
    "TestData",
    "Cycle",
    "AmplitudeCurve",
    "estimate_noise",
    "NoiseEstimate",
    "fit_force_model",
    "ModelFit",
    "modal_iwan_curve",
    "harmonic_stiffness",
    "modal_ringdown",
    "ModalRingdown",
    "amplitude_curve",
    "fit_modal_iwan",
    "fit_decay",
    "stepped_sine_curve",
    "sweep_curve",
    "read_uff",
    "UffRecord",
    "read_sweep_csv",
    "read_vibration_csv",
    "ModalIwanFit",
    "free_decay_modes",
    "frf_modes",
    "sweep_modes",
    "ModalTargets",
    "ModeTarget",
    "mac",
    "fit_loops",
    "fit_dissipation",
    "FitResult",
    "IdentifiabilityWarning",
    "diagnose",
    "diagnose_many",
    "fit_campaign",
    "CampaignFit",
    "BatchDiagnosis",
    "diagnose_vibration",
    "Diagnosis",
    "VibrationDiagnosis",
    "simulate_element_test",
    "loop_candidates",
    "run_ensemble",
    "EnsembleResult",
    "ParameterUncertainty",
    "PredictionBands",
    "propagate_uncertainty",
    "SingleModeSystem",
    "parameter_grid",
    "parameter_samples",
]
