"""Model-discrepancy diagnosis: which physical effect the Iwan model misses.

Modules: :mod:`.loops` (force-displacement records), :mod:`.vibration` (amplitude-dependent
frequency and damping), :mod:`.selection` (the one selection rule both use),
:mod:`.results` (result objects), :mod:`.generator` (the synthetic test generator),
:mod:`.batch` (many records on local processes or Dask), :mod:`.campaign` (one device
model over a campaign, its parameters laws of the test conditions).
"""
from .batch import BatchDiagnosis, diagnose_many
from .campaign import CampaignFit, fit_campaign
from .generator import simulate_element_test
from .loops import diagnose, loop_candidates
from .results import Diagnosis
from .vibration_result import VibrationDiagnosis
from .vibration import diagnose_vibration

__all__ = ["BatchDiagnosis", "CampaignFit", "fit_campaign", "Diagnosis", "VibrationDiagnosis",
           "diagnose", "diagnose_many", "diagnose_vibration", "loop_candidates",
           "simulate_element_test"]
