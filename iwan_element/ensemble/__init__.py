"""Ensembles: many model runs on local processes or a Dask cluster, uncertainty propagation
from a fit's covariance, and parameter studies.

* :func:`run_ensemble` - one function over many parameter sets, reproducible on any executor;
* :class:`ParameterUncertainty`, :func:`propagate_uncertainty`, :class:`PredictionBands` -
  prediction bands of f(X), zeta(X) and a transient peak response from a fit's covariance;
* :class:`SingleModeSystem`, :func:`modal_curve`, :func:`peak_response` -
  the single-mode jointed structure the bands are computed for;
* :func:`parameter_grid`, :func:`parameter_samples` - the parameter sets of a study
  (ready-made tasks for the lap-jointed beams: :mod:`iwan_element.models.studies`).
"""

from .bands import PredictionBands, propagate_uncertainty, response_task
from .oscillator import SingleModeSystem, modal_curve, peak_response
from .runner import EnsembleResult, TaskError, run_ensemble
from .sweep import parameter_grid, parameter_samples
from .uncertainty import ParameterUncertainty

__all__ = [
    "run_ensemble",
    "EnsembleResult",
    "TaskError",
    "ParameterUncertainty",
    "PredictionBands",
    "propagate_uncertainty",
    "response_task",
    "SingleModeSystem",
    "modal_curve",
    "peak_response",
    "parameter_grid",
    "parameter_samples",
]
