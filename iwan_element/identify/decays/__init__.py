"""Free decays (a ring-down after a hammer blow or a release): the amplitude curve of one
mode (:func:`amplitude_curve`: band-pass, analytic signal or peaks, windows, drift and
filter-gain corrections, report), the direct fit of the modal Iwan model to the decay
(:func:`fit_decay`), the linear modes of a multi-sensor decay (:func:`free_decay_modes`),
clipping and flattened peaks (:mod:`.saturation`), and the package's one band-pass + Hilbert
envelope (:func:`analytic_signal`, :func:`mode_envelope`).

Imports :mod:`iwan_element.base`, :mod:`iwan_element.fitting` and :mod:`..modal` only.
"""

from .curve import amplitude_curve
from .envelope import analytic_signal, mode_envelope
from .fit import fit_decay
from .modes import free_decay_modes
from .saturation import cut_clipping, cut_flattened_peaks, find_clipping

__all__ = [
    "amplitude_curve",
    "fit_decay",
    "free_decay_modes",
    "analytic_signal",
    "mode_envelope",
    "find_clipping",
    "cut_clipping",
    "cut_flattened_peaks",
]
