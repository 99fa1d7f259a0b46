"""Amplitude-dependent modal data and what is fitted to it: the frequency and damping
curve of one mode against amplitude (:class:`AmplitudeCurve`, whatever test it came from),
the modal Iwan fit (:func:`fit_modal_iwan`, :class:`ModalIwanFit`), the linear modal targets
of a test (:class:`ModalTargets`) and the generic damped-sinusoid poles the decay and sweep
routes share (:mod:`.poles`).

Imports :mod:`iwan_element.base`, :mod:`iwan_element.core`, :mod:`iwan_element.fitting`,
:mod:`..loops` (the identifiability rule and warning) and :mod:`..files` (unit checks).
"""

from .curves import DECAY_METHODS, AmplitudeCurve
from .fit import fit_modal_iwan
from .mode_target import ModeTarget, mac
from .result import ModalIwanFit
from .targets import ModalTargets

__all__ = [
    "AmplitudeCurve",
    "DECAY_METHODS",
    "fit_modal_iwan",
    "ModalIwanFit",
    "ModalTargets",
    "ModeTarget",
    "mac",
]
