"""The vibration diagnosis: which effect an amplitude-dependent frequency and damping curve
shows that the modal Iwan model misses.

:mod:`.diagnosis` (:func:`diagnose_vibration`, :func:`vibration_candidates`; its measurement
and noise in :mod:`._measurement`, what it reports of its fit in :mod:`._outcome`),
:mod:`.evidence` (the explanations' evidences), :mod:`.result` (:class:`VibrationDiagnosis`;
its prediction at new amplitudes in :mod:`._prediction`), :mod:`.augment` (the augmented
joint it hands on).
"""

from .diagnosis import diagnose_vibration, vibration_candidates
from .result import VibrationDiagnosis

__all__ = ["diagnose_vibration", "vibration_candidates", "VibrationDiagnosis"]
