"""Models built on iwan_element's public API; installed as ``iwan_element.models``.

The lap-jointed beams, in rooms from the bottom up (a room imports only the rooms listed
before it; ``docs/architecture.md``):

* :mod:`~iwan_element.models.specimens` - what a specimen is: the validated description
  (:class:`Specimen`, :class:`InterfaceModel`), the published presets (:func:`preset`:
  ``"example"``, ``"brake-reuss"``, ``"two-bolt-aluminium"``), the test setup it carries
  (:class:`Setup`: sensor masses, shaker, clamp springs), the contact pressure cones and the
  1-D contact points' Iwan elements;
* :mod:`~iwan_element.models.linear` - the one linear system every analysis reads, and the
  setup built into it;
* :mod:`~iwan_element.models.beam` - the 1-D Timoshenko beams and their linear system;
* :mod:`~iwan_element.models.solid` - solid finite-element halves (Netgen, or the user's
  mesh), contact patches and the reduced linear system (:func:`solid_preset`,
  :class:`SolidSpecimen`; extra ``iwan-element[fem]``);
* :mod:`~iwan_element.models.reduced` - what the analyses read of a specimen, 1-D or solid
  alike (linear system, contact points, axis rows), the stuck modes, the one reduced model
  of the frequency-domain routes (:func:`reduced_model`, :func:`reduction_error`) and the
  linear damping floor, one ratio per mode;
* :mod:`~iwan_element.models.updating` - linear model updating on low-level test data
  (:func:`updatable`, :func:`linear_update`): material, boundary, setup and the stuck
  joint's stiffness, before any joint calibration;
* :mod:`~iwan_element.models.modal` - quasi-static modal analysis
  (:func:`modal_amplitude_curve`, :func:`natural_frequencies`), harmonic balance
  (:func:`harmonic_balance`), continuation (:func:`frequency_response`) and nonlinear
  modes by EPMC (:func:`nonlinear_mode`), the vibration effects' modal form, a
  stepped-sine level's linear targets through the joint (:func:`sweep_level_targets`);
* :mod:`~iwan_element.models.simulation` - a specimen in Exudyn: the ring-down after a
  release or a hammer :class:`Impact` (:func:`ringdown`), modes ringing together
  (:func:`mode_coupling`), the stepped-sine forced response (:func:`forced_response`), the
  machine test (:func:`quasi_static_test`);
* :mod:`~iwan_element.models.calibration` - the interface from vibration data and from
  joint / modal Iwan fits, and a whole hammer test predicted from one mode
  (:func:`predict_hammer_test`);
* ``example_test_30kN.csv`` - a SYNTHETIC quasi-static test of the seed paper's specimen
  (see ``README.md`` here and ``make_example_test.py``); :func:`example_test_path` finds it.
"""

from importlib import resources
from pathlib import Path

from .calibration import (
    HammerPrediction,
    ModesDiagnosis,
    diagnose_hammer_test,
    diagnose_modes,
    predict_hammer_test,
)
from .modal import (
    frequency_response,
    harmonic_balance,
    modal_amplitude_curve,
    natural_frequencies,
    nonlinear_mode,
    resolve_interface_effects,
    sweep_level_targets,
)
from .reduced import ReducedModel, reduced_model, reduction_error
from .simulation import (
    ForcedResponseResult,
    Impact,
    ModeCouplingResult,
    QuasiStaticResult,
    RingdownResult,
    forced_response,
    mode_coupling,
    quasi_static_test,
    ringdown,
)
from .solid import SolidSpecimen, solid_preset
from .specimens import (
    Clamp,
    Excitation,
    InterfaceEffect,
    InterfaceModel,
    PointMass,
    Setup,
    Shaker,
    Specimen,
    preset,
)
from .updating import LinearUpdateResult, linear_update, updatable

__all__ = [
    "example_test_path",
    "preset",
    "modal_amplitude_curve",
    "natural_frequencies",
    "ringdown",
    "Impact",
    "mode_coupling",
    "quasi_static_test",
    "forced_response",
    "Specimen",
    "InterfaceModel",
    "InterfaceEffect",
    "resolve_interface_effects",
    "Excitation",
    "RingdownResult",
    "ModeCouplingResult",
    "QuasiStaticResult",
    "ForcedResponseResult",
    "solid_preset",
    "SolidSpecimen",
    "harmonic_balance",
    "frequency_response",
    "nonlinear_mode",
    "reduced_model",
    "reduction_error",
    "ReducedModel",
    "predict_hammer_test",
    "diagnose_modes",
    "diagnose_hammer_test",
    "ModesDiagnosis",
    "HammerPrediction",
    "Setup",
    "PointMass",
    "Shaker",
    "Clamp",
    "linear_update",
    "LinearUpdateResult",
    "updatable",
    "sweep_level_targets",
]


def example_test_path() -> Path:
    """Path of the shipped synthetic example test record (CSV: time [s], mm, kN)."""
    return Path(str(resources.files(__name__).joinpath("example_test_30kN.csv")))
