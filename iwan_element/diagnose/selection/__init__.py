"""The model-selection rule both diagnoses use and the probabilities behind it.

:mod:`.rule` (the stepwise selection rule: misfit test, information criterion, pair step),
:mod:`.probabilities` (priors, evidences, posterior probabilities of the explanations),
:mod:`.probable` (:class:`Probable`, what results say of those probabilities),
:mod:`.averaging` (the model-averaged band), :mod:`.nested` (nested sampling of the
evidences), :mod:`.lines` (the report lines both diagnoses share).
"""

from .averaging import MIN_WEIGHT, band, linear_spread, members
from .lines import effect_unit, verdict_lines
from .nested import nested_log_evidence, nested_options
from .probabilities import Explanation, check_effect_prior, key, log_model_prior, rank
from .probable import Probable
from .rule import SelectionResult, criterion_text, misfit_p, stepwise_select

__all__ = [
    "MIN_WEIGHT",
    "band",
    "linear_spread",
    "members",
    "effect_unit",
    "verdict_lines",
    "nested_log_evidence",
    "nested_options",
    "Explanation",
    "Probable",
    "check_effect_prior",
    "key",
    "log_model_prior",
    "rank",
    "SelectionResult",
    "criterion_text",
    "misfit_p",
    "stepwise_select",
]
