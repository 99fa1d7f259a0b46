"""Identification of the four Iwan parameters ``(Fs, KT, chi, beta)`` from test data.

The implementation lives in focused modules; this module keeps the historical import path:

* :mod:`.loops` - :func:`fit_loops`, the force-history fit with sensor offsets;
* :mod:`.dissipation` - :func:`fit_dissipation`, per-cycle amplitude tables (seed method and
  least squares on the closed forms);
* :mod:`.identifiability` - what the data determine, uncertainties, the verdict;
* :mod:`.result` - :class:`FitResult`;
* :mod:`.model_fit` - :func:`fit_force_model`, any force model plus offsets;
* :mod:`.noise` - :func:`estimate_noise`.
"""
from .dissipation import fit_dissipation
from .loops import fit_loops
from .result import PARAM_NAMES, FitResult, IdentifiabilityWarning, _json, _quiet
# private names other subpackages (diagnose) import from here
from ._solver import _lsq_box  # noqa: F401
from .identifiability import _BETA_MAX, _CHI_BOUNDS, _PHI_RANGE  # noqa: F401

__all__ = ["FitResult", "IdentifiabilityWarning", "fit_dissipation", "fit_loops", "PARAM_NAMES",
           "_quiet", "_json"]
