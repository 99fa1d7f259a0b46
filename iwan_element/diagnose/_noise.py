"""Noise of a measured signal without repeated cycles: the estimator used by the diagnoses.

The diagnoses estimate the noise from the *residual of the plain fit*, which on clean data
is the noise itself. :func:`iwan_element.identify.noise.estimate_noise` is made for a measured
channel (signal plus noise) and smooths over a fraction of the loading period; on a residual
that is mostly coloured noise it reads the correlation time too short (AR(1) noise of lag-one
correlation 0.5: tau 1.0 instead of 3), so clean coloured records were named an effect. This
estimator models the residual's noise as AR(1) instead.

Method (``"local-polynomial"``): the residual ``r`` of a cubic Savitzky-Golay smoother over
9 samples (scipy.signal) removes any signal that is smooth over 9 samples, whatever the
protocol (constant, ramped, swept or random amplitude). Its robust scale (MAD, insensitive
to the few samples at sharp corners) and its lag-one correlation are matched to those the
same filter produces from AR(1) noise, ``r = (I - H) e``: that gives the noise's standard
deviation ``sigma`` and lag-one correlation ``rho`` together (white noise: ``rho = 0``), and
its integrated correlation time ``tau = (1 + rho)/(1 - rho)`` samples, so coloured noise
counts ``n / tau`` independent samples.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq
from scipy.signal import savgol_coeffs, savgol_filter

__all__ = ["noise_estimate"]

_W = 9


@dataclass(frozen=True)
class NoiseEstimate:
    """Noise level of a signal: ``sigma`` [signal units], ``method``, ``tau`` [samples],
    ``n_eff`` (independent samples) and ``warnings``."""

    sigma: float
    method: str
    tau: float = 1.0
    n_eff: float = 0.0
    warnings: tuple = field(default_factory=tuple)


def _ar1_moments(rho: float) -> tuple[float, float]:
    """Variance and lag-one autocovariance of ``(I - H) e`` for unit AR(1) noise ``e``."""
    c = -savgol_coeffs(_W, 3)
    c[_W // 2] += 1.0
    lag = np.arange(-(_W + 1), _W + 2)
    acf = rho ** np.abs(lag)
    full = np.convolve(np.convolve(c, c[::-1]), np.ones(1))   # autocorrelation of c
    mid = full.size // 2
    var = sum(full[mid + k] * acf[np.abs(lag) == abs(k)][0] for k in range(-mid, mid + 1))
    cov1 = sum(full[mid + k] * rho ** abs(k + 1) for k in range(-mid, mid + 1))
    return float(var), float(cov1)


def _fallback(t, y) -> NoiseEstimate:
    y = np.asarray(y, float)
    if y.size < 4 * _W:
        raise ValueError(f"y has {y.size} samples: at least {4 * _W} are needed to estimate "
                         "its noise; pass the noise level explicitly")
    r = y - savgol_filter(y, _W, 3)
    s = 1.4826 * float(np.median(np.abs(r - np.median(r))))
    warns = []
    if s == 0.0:
        return NoiseEstimate(0.0, "local-polynomial", 1.0, float(y.size),
                             ("the signal is smooth to machine precision (no noise found)",))
    # robust lag-one correlation from the MAD scales of sums and differences (a corner of
    # the signal is an outlier for both and moves neither median)
    mad = lambda x: float(np.median(np.abs(x - np.median(x))))  # noqa: E731
    S, D = mad(r[1:] + r[:-1]) ** 2, mad(r[1:] - r[:-1]) ** 2
    c1 = (S - D) / (S + D) if S + D > 0 else 0.0

    def mismatch(rho):
        v, c = _ar1_moments(rho)
        return c / v - c1
    lo, hi = -0.9, 0.995
    if mismatch(lo) > 0:
        rho = lo
    elif mismatch(hi) < 0:
        rho = hi
        warns.append("the noise is strongly correlated (lag-one correlation near 1); its level "
                     "is uncertain")
    else:
        rho = brentq(mismatch, lo, hi)
    var, _ = _ar1_moments(rho)
    sigma = s / math.sqrt(var)
    tau = max((1.0 + rho) / (1.0 - rho), 1.0)
    return NoiseEstimate(float(sigma), "local-polynomial", float(tau), y.size / tau, tuple(warns))


def noise_estimate(t, y) -> tuple[float, float, str, tuple]:
    """``(sigma [units of y], tau [samples], method, warnings)`` of a fit residual."""
    y = np.asarray(y, float)
    est = _fallback(t, y)
    if getattr(est, "n_eff", None) and getattr(est, "n", None):
        tau = float(est.n) / float(est.n_eff)          # helper fit's estimator: samples
    else:
        tau = float(getattr(est, "tau", None) or 1.0)
    return float(est.sigma), max(tau, 1.0), str(getattr(est, "method", "auto")), \
        tuple(getattr(est, "warnings", ()))
