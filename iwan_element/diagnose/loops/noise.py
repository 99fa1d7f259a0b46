"""The diagnoses' use of the package's one noise estimator.

:func:`iwan_element.identify.loops.noise.estimate_noise` (Savitzky-Golay residual, robust scale,
AR(1) noise model matched to the residual's robust autocorrelation) is applied to the
*residual of the plain fit*, which on clean data is the noise itself. A residual's own
spectrum says nothing about the loading, so the smoothing window comes from the measured
channel: its signal window (``1/8`` of the fastest loading period, at least 25 samples, which
keeps the AR(1) model well conditioned for noise correlated over a few samples), so the smooth
part of any model error is removed (its corners are outliers for the robust scale). A large
misfit still leaks in: :func:`iwan_element.diagnose` then re-reads the noise from the
residual of the model it selected.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...identify.loops.noise import MIN_WINDOW, estimate_noise, signal_window

__all__ = ["noise_estimate", "NoiseLevel", "noise_level"]

_RESIDUAL_MIN = 25  # samples: the AR(1) match is poorly conditioned below


def noise_estimate(t, y, channel=None) -> tuple[float, float, str, tuple]:
    """``(sigma [units of y], tau [samples], method, warnings)`` of ``y``; with ``channel``
    (the measured signal ``y`` is the fit residual of) the window is the channel's.
    """
    y = np.asarray(y, float)
    tt = np.arange(y.size, dtype=float) if t is None else np.asarray(t, float)
    window = None
    if channel is not None:
        w = min(max(signal_window(np.asarray(channel, float)), _RESIDUAL_MIN), y.size // 4)
        w = w if w % 2 else w - 1
        if w >= MIN_WINDOW:
            window = w * float(np.median(np.diff(tt)))
    est = estimate_noise(tt, y, window=window)
    return float(est.sigma), est.tau, est.method, tuple(est.warnings)


def pure_noise(y, chi2_model, sigma, tau, n_eff) -> bool:
    """True when a model with misfit ``chi2_model`` explains the record ``y`` no better than
    a constant would (BIC with ``n_eff`` independent samples, residuals correlated over
    ``tau`` samples): a record that is noise identifies nothing.
    """
    chi0 = float(np.sum((y - y.mean()) ** 2)) / sigma**2
    return (chi0 - chi2_model) / tau < 4.0 * math.log(max(n_eff, 2.0))


@dataclass(frozen=True)
class NoiseLevel:
    """The force noise a diagnosis scores its fits against.

    Attributes
    ----------
    sigma : float
        Standard deviation [N] of the force as fitted.
    tau : float
        Correlation time [samples of the record].
    text : str
        Where it came from (given, estimated, reduced to the low-pass band, re-read).
    warnings : tuple of str
        What limits the estimate.
    tau_k, n_eff : float
        Correlation time in fitted samples (at least 1) and the effective number of
        independent fitted samples.
    """

    sigma: float
    tau: float
    text: str
    warnings: tuple
    tau_k: float
    n_eff: float


def noise_level(rec, r, noise) -> NoiseLevel:
    """The noise of a prepared record ``rec`` (:class:`~.prepare.PreparedRecord`) from the
    residual ``r`` [N] of a fit to the raw force (the model removes the loops' corners, the
    estimator the smooth rest of any model error), or ``noise`` [N] when given (white).
    """
    if noise is not None:
        warns: tuple[str, ...] = ()
        sigma, tau, text = noise, 1.0, "given"
    else:
        sigma, tau, method, warns = noise_estimate(rec.t, r, rec.F_raw)
        text = f"estimated from the record ({method})"
        if rec.lowpass is not None:  # white noise through the low-pass
            fs = 1.0 / float(np.median(np.diff(rec.t)))
            frac = min(2.0 * rec.lowpass / fs, 1.0)
            sigma *= math.sqrt(frac)
            tau = max(tau, 1.0 / frac)
            text += f", reduced to the {rec.lowpass:g} Hz band"
        if not sigma > 0:
            sigma = 1e-9 * float(np.max(np.abs(rec.F_raw)))
            warns = tuple(warns) + (
                "no noise found in the force: a floor of 1e-9 x max|F| is used",
            )
    tau_k = max(1.0, tau * rec.keep.size / rec.n)
    return NoiseLevel(
        sigma=float(sigma),
        tau=float(tau),
        text=text,
        warnings=tuple(warns),
        tau_k=tau_k,
        n_eff=rec.keep.size / tau_k,
    )
