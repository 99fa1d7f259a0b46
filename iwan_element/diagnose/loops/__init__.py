"""The loop diagnosis: which effect a force-displacement record shows that the Iwan model
misses.

:mod:`.diagnosis` (:func:`diagnose`, :func:`loop_candidates`: the stages), :mod:`.prepare`
(the record as fitted), :mod:`.noise` (its noise level), :mod:`.model` (the loop model and
its Jacobian), :mod:`.fit` (the fits of every stack), :mod:`.evidence` (the explanations'
evidences and forces), :mod:`.locate` (where a misfit lies), :mod:`.report` and
:mod:`.result` (:class:`Diagnosis`), :mod:`.batch` (many records on local processes or
Dask: :func:`diagnose_many`, :class:`BatchDiagnosis`).
"""

from .batch import (
    BatchDiagnosis,
    band_misfit,
    check_options,
    check_records,
    diagnose_many,
    executor_for,
)
from .diagnosis import diagnose, loop_candidates
from .result import Diagnosis

__all__ = [
    "BatchDiagnosis",
    "band_misfit",
    "check_options",
    "check_records",
    "diagnose_many",
    "executor_for",
    "diagnose",
    "loop_candidates",
    "Diagnosis",
]
