"""Model-discrepancy diagnosis: which physical effect the Iwan model misses.

Rooms: :mod:`.loops` (force-displacement records, one or many: :func:`diagnose`,
:func:`diagnose_many`), :mod:`.vibration` (amplitude-dependent frequency and damping:
:func:`diagnose_vibration`), :mod:`.selection` (the one selection rule both use, the
probabilities, evidences and model averaging), :mod:`.campaign` (one device model over a
campaign, its parameters laws of the test conditions: :func:`fit_campaign`), and
:mod:`.generator` (the synthetic test generator).
"""

from .campaign import CampaignFit, fit_campaign
from .generator import simulate_element_test
from .loops import BatchDiagnosis, Diagnosis, diagnose, diagnose_many, loop_candidates
from .vibration import VibrationDiagnosis, diagnose_vibration

__all__ = [
    "BatchDiagnosis",
    "CampaignFit",
    "fit_campaign",
    "Diagnosis",
    "VibrationDiagnosis",
    "diagnose",
    "diagnose_many",
    "diagnose_vibration",
    "loop_candidates",
    "simulate_element_test",
]
