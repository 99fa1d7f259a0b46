"""Noise of a measured signal for the diagnoses: a thin adapter over the package's estimator.

The estimator is :func:`iwan_element.identify.noise.estimate_noise` (needs no repeated cycles;
see its docstring for the method). The diagnoses want ``(sigma, tau, method, warnings)``
with ``tau`` the residual's integrated correlation time in samples, so that ``n / tau``
samples count as independent.
"""
from __future__ import annotations

import numpy as np

from ..identify.noise import estimate_noise

__all__ = ["noise_estimate"]


def noise_estimate(t, y) -> tuple[float, float, str, tuple]:
    """``(sigma, tau, method, warnings)``: noise RMS [units of y], correlation time [samples]."""
    y = np.asarray(y, float)
    est = estimate_noise(np.arange(y.size, dtype=float) if t is None else t, y)
    tau = float(est.n) / float(est.n_eff) if est.n_eff else 1.0
    return float(est.sigma), max(tau, 1.0), str(est.method), tuple(est.warnings)
