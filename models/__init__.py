"""Models built on iwan_element's public API; installed as ``iwan_element.models``.

* :mod:`~iwan_element.models.specimens` - two-beam lap-joint specimens and presets
  (:func:`preset`: ``"example"``, ``"brake-reuss"``, ``"two-bolt-aluminium"``);
* :mod:`~iwan_element.models.specimens.contact` - contact pressure cones and the distributed
  interface's Iwan elements;
* :mod:`~iwan_element.models.specimens.setups` - the test setup (sensor masses, shaker, clamp springs)
  that a specimen carries and every analysis includes;
* :mod:`~iwan_element.models.beam.elements` and :mod:`~iwan_element.models.beam.assembly` - the 1-D
  Timoshenko beams and the specimen's linear system (:mod:`~iwan_element.models.linear`);
* :mod:`~iwan_element.models.simulation.host` - a specimen in Exudyn: its linear system as one generic
  body, the contact points' Iwan elements on slip coordinates (the transient routes' model);
* :mod:`~iwan_element.models.modal.qsma` - quasi-static modal analysis (:func:`modal_amplitude_curve`);
  :func:`~iwan_element.models.modal.linear_modes`, :func:`natural_frequencies` (with the joint
  stuck or without it);
* :mod:`~iwan_element.models.simulation.transient` - the transient route (:func:`ringdown`, one release
  level per call, one mode or several at once through the same interface; frequency and
  damping by :func:`iwan_element.amplitude_curve`; result in
  :mod:`~iwan_element.models.simulation.ringdown_result`; the pieces the 1-D and the solid ring-down share
  in :mod:`~iwan_element.models.simulation.ringdown_records`; a solid specimen's run in
  :mod:`~iwan_element.models.solid_transient`);
* :mod:`~iwan_element.models.simulation.impact` - a hammer impact (:class:`Impact`, a half-sine force
  pulse) that :func:`ringdown` takes instead of a release;
* :mod:`~iwan_element.models.simulation.coupling` - each mode's damping with and without the other
  modes ringing through the same interface (:func:`mode_coupling`);
* :mod:`~iwan_element.models.hammer` - a whole hammer test predicted from one mode
  (:func:`predict_hammer_test`: calibrate on it, each other mode's floor from its lowest
  amplitudes, the multi-mode ring-down against every record);
* :mod:`~iwan_element.models.reduced.damping` - the linear damping floor, one ratio per mode, as the
  stuck system's modal damping matrix (the ring-down's and the stepped sine's);
* :mod:`~iwan_element.models.simulation.machine` - the joint's quasi-static test in a machine grip
  (:func:`quasi_static_test`);
* :mod:`~iwan_element.models.simulation.forced` - stepped-sine forced response at several force levels
  (:func:`forced_response`);
* :mod:`~iwan_element.models.reduced` - the one reduced model (stuck modes with their floors,
  residual flexibility, the contact points' joints) that the frequency-domain routes read;
* :mod:`~iwan_element.models.modal.frequency` - harmonic balance (:func:`harmonic_balance`),
  continuation (:func:`frequency_response`) and nonlinear modes by EPMC
  (:func:`nonlinear_mode`);
* :mod:`~iwan_element.models.solid.mesh`, :mod:`~iwan_element.models.solid.build`,
  :mod:`~iwan_element.models.solid` - solid finite-element halves (Netgen, or the user's
  mesh), contact patches and the reduced linear system QSMA reads (:func:`solid_preset`;
  extra ``iwan-element[fem]``);
* :mod:`~iwan_element.models.simulation.solver` - Exudyn solver settings shared by the runs;
* :mod:`~iwan_element.models.updating` and :mod:`~iwan_element.models.updating.update` - linear
  model updating on low-level test data (:func:`updatable`, :func:`linear_update`): material,
  boundary, setup and the stuck joint's stiffness, before any joint calibration;
* :mod:`~iwan_element.models.calibration` - interface calibration from vibration data and
  from joint / modal Iwan fits;
* ``example_test_30kN.csv`` - a SYNTHETIC quasi-static test of the seed paper's specimen
  (see ``README.md`` here and ``make_example_test.py``); :func:`example_test_path` finds it.
"""
from importlib import resources
from pathlib import Path

from .simulation import ModeCouplingResult, mode_coupling, ForcedResponseResult, forced_response
from .modal import frequency_response, harmonic_balance, nonlinear_mode
from .reduced import ReducedModel, reduced_model, reduction_error
from .hammer import HammerPrediction, predict_hammer_test
from .simulation import Impact, QuasiStaticResult, quasi_static_test
from .modal import modal_amplitude_curve, natural_frequencies
from .simulation import RingdownResult, ringdown
from .solid import SolidSpecimen, solid_preset
from .specimens import (Clamp, Excitation, InterfaceModel, PointMass, Setup, Shaker, Specimen,
                        preset)
from .updating import LinearUpdateResult, linear_update, updatable

__all__ = ["example_test_path", "preset", "modal_amplitude_curve", "natural_frequencies",
           "ringdown", "Impact", "mode_coupling", "quasi_static_test", "forced_response",
           "Specimen", "InterfaceModel", "Excitation", "RingdownResult", "ModeCouplingResult",
           "QuasiStaticResult", "ForcedResponseResult", "solid_preset", "SolidSpecimen",
           "harmonic_balance", "frequency_response", "nonlinear_mode", "reduced_model",
           "reduction_error", "ReducedModel", "predict_hammer_test", "HammerPrediction",
           "Setup", "PointMass", "Shaker", "Clamp", "linear_update", "LinearUpdateResult",
           "updatable"]


def example_test_path() -> Path:
    """Path of the shipped synthetic example test record (CSV: time [s], mm, kN)."""
    return Path(str(resources.files(__name__).joinpath("example_test_30kN.csv")))
