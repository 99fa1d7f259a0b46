"""The frequency domain: harmonic balance with the exact Iwan kernel, continuation, nonlinear modes.

A structure in modal form seen at its ports (:class:`ModalSystem`), the alternating
frequency-time evaluation of its joints on their exact steady loops
(:mod:`iwan_element.core.periodic`), Newton's method with the exact Jacobian
(:func:`harmonic_balance`), pseudo-arclength continuation through turning points
(:func:`trace`), and nonlinear modes by the extended periodic motion concept
(:func:`nonlinear_mode`). Equations: ``docs/harmonic_balance.md``.
"""

from .continuation import trace
from .response import harmonic_balance
from .result import FrequencyResponse, macroslip_lines, slip_ratio
from .system import ModalSystem

__all__ = [
    "ModalSystem",
    "FrequencyResponse",
    "harmonic_balance",
    "trace",
    "macroslip_lines",
    "slip_ratio",
]
