"""Forced response: a sine sweep (:func:`sweep_curve`) or stepped sine
(:func:`stepped_sine_curve`) to an amplitude curve, and the linear modes of FRFs and sweeps
(:func:`frf_modes`, :func:`sweep_modes`).

Imports :mod:`iwan_element.base`, :mod:`iwan_element.fitting` and :mod:`..modal` only.
"""

from .frf_modes import frf_modes, sweep_modes
from .stepped_sine import stepped_sine_curve
from .sweep import sweep_curve

__all__ = ["sweep_curve", "stepped_sine_curve", "frf_modes", "sweep_modes"]
