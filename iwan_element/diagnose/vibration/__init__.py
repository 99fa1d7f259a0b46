"""The vibration diagnosis: which effect an amplitude-dependent frequency and damping curve
shows that the modal Iwan model misses.

:mod:`.diagnosis` (:func:`diagnose_vibration`, :func:`vibration_candidates`),
:mod:`.evidence` (the explanations' evidences), :mod:`.result` (:class:`VibrationDiagnosis`),
:mod:`.augment` (the augmented joint it hands on).
"""

from .diagnosis import diagnose_vibration, vibration_candidates
from .result import VibrationDiagnosis

__all__ = ["diagnose_vibration", "vibration_candidates", "VibrationDiagnosis"]
