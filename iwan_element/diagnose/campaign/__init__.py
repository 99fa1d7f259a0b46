"""One device model over a test campaign, its parameters laws of the test conditions.

Bottom to top: :mod:`.probability` (the explanations over all records), :mod:`.model` (the
campaign model, its records, its least-squares fit), :mod:`.scatter` (the record-to-record
scatter about the laws), :mod:`.predict` (prediction at a
condition), :mod:`.holdout` (leave-one-out), :mod:`.result` (:class:`CampaignFit`),
:mod:`.assemble` (the result from a fit), :mod:`.fit` (:func:`fit_campaign`).
"""

from .fit import fit_campaign
from .holdout import LeaveOneOut
from .predict import CampaignPrediction
from .result import CampaignFit

__all__ = ["fit_campaign", "CampaignFit", "CampaignPrediction", "LeaveOneOut"]
