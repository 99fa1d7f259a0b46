"""One device model over a test campaign, its parameters laws of the test conditions.

Bottom to top: :mod:`.probability` (the explanations over all records), :mod:`.model` (the
campaign model, its records, its least-squares fit), :mod:`.predict` (prediction at a
condition, leave-one-out), :mod:`.result` (:class:`CampaignFit`), :mod:`.assemble` (the
result from a fit), :mod:`.fit` (:func:`fit_campaign`).
"""

from .fit import fit_campaign
from .predict import CampaignPrediction, LeaveOneOut
from .result import CampaignFit

__all__ = ["fit_campaign", "CampaignFit", "CampaignPrediction", "LeaveOneOut"]
