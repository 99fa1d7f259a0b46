"""The fitting engine every fit of the package uses (docs/fitting.md).

* :class:`Parameter` and :class:`ParameterTable`: a fitted parameter with its standard
  error, bounds, unit and verdict, and the ordered, immutable table a fit result carries as
  ``params``;
* :func:`covariance`: the one covariance routine, ``tau s^2 (J^T J)^-1`` with column
  scaling and degenerate-direction detection, the optional block sandwich for time-series
  residuals and the optional delta method to physical parameters;
* :func:`verdict` and :func:`fit_success`: the one rule that says whether a parameter is
  identified (with its warning text, :func:`noise_dof_warning` when the noise level rests
  on too few degrees of freedom) and the one ``success`` rule (docs/guards.md);
* :func:`minimize`: the least-squares entry over scipy's ``least_squares(method="trf")`` and
  :func:`box_lm`, the box-bounded Levenberg-Marquardt of the loop fit.

The residuals' correlation time and the second-difference noise formula have their one home
in :mod:`iwan_element.identify.loops.noise` (``integrated_time``, ``difference_sigma``); the
covariance takes the correlation time as an argument. This subpackage imports only
:mod:`iwan_element.core`.
"""

from .covariance import Covariance, covariance, normal_inverse
from .minimize import MinimizeResult, box_lm, minimize
from .parameters import Parameter, ParameterTable
from .verdict import MIN_NOISE_DOF, fit_success, noise_dof_warning, verdict

__all__ = [
    "Covariance",
    "MIN_NOISE_DOF",
    "MinimizeResult",
    "Parameter",
    "ParameterTable",
    "box_lm",
    "covariance",
    "fit_success",
    "minimize",
    "noise_dof_warning",
    "normal_inverse",
    "verdict",
]
