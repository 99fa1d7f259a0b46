"""The modal Iwan model in fit coordinates: the parameter vectors of the microslip and the
full fit, the joint they stand for, and the frequency and damping curves of the model
(Segalman 2005, J. Appl. Mech. 72:752-760; the closed forms of
:func:`~iwan_element.modal_iwan_curve`).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy import special

from ...core.modal import modal_iwan_curve, viscous_floor
from ...core.parameters import IwanParameters

__all__ = ["FULL", "MICRO", "full_parameters", "harmonic_factor", "model_curve"]

MICRO = ("f0", "zeta0", "chi", "delta")
FULL = ("f0", "zeta0", "chi", "kappa", "log_phi_max", "beta")


def harmonic_factor(chi) -> float:
    """Ratio of the first-harmonic to the secant stiffness drop in microslip (n = chi+2)."""
    n = chi + 2.0
    return (
        4.0 * n * math.exp(special.gammaln(n + 0.5) - special.gammaln(n + 2.0)) / math.sqrt(math.pi)
    )


def full_parameters(theta) -> tuple[IwanParameters, float]:
    """(IwanParameters, K_inf) in sensor units with unit mass from the full parameter vector."""
    f0, _, chi, kappa, logphi, beta = theta
    w02 = (2.0 * math.pi * f0) ** 2
    KT = kappa * w02
    phimax = math.exp(logphi)
    c = beta + (chi + 1.0) / (chi + 2.0)
    return IwanParameters(KT * c * phimax / (1.0 + beta), KT, chi, beta), w02 - KT


def model_curve(
    theta, X, regime, x_ref, stiffness, floor, damping_form="energy"
) -> tuple[float | NDArray[np.float64], float | NDArray[np.float64]]:
    """Frequency [Hz] and damping ratio of the model at amplitudes ``X`` (``damping_form``: the
    energy form or the form a free decay shows, :func:`~iwan_element.modal_iwan_curve`).
    """
    f0, z0, chi = theta[0], theta[1], theta[2]
    if regime == "microslip":
        delta = theta[3]
        w02 = (2.0 * math.pi * f0) ** 2
        g = delta * (X / x_ref) ** (chi + 1.0)
        s = 1.0 if stiffness == "secant" else harmonic_factor(chi)
        w2 = w02 * np.maximum(1.0 - s * g, 1e-12)
        # energy per amplitude: w^2, or the tangent (secant drop times chi + 2) for a decay
        k_e = w2 if damping_form == "energy" else w02 * np.maximum(1.0 - (chi + 2.0) * g, 1e-12)
        zv = viscous_floor(z0, w02, w2, k_e, floor)
        zeta = zv + w02 * g * 2.0 * (chi + 1.0) / (math.pi * (chi + 3.0)) / k_e
        return np.sqrt(w2) / (2.0 * math.pi), zeta
    p, k_inf = full_parameters(theta)
    return modal_iwan_curve(
        X, p, K_inf=k_inf, zeta0=z0, stiffness=stiffness, floor=floor, damping_form=damping_form
    )


def _derived(theta, regime):
    """Reported parameters (name -> value) from the fitted vector."""
    if regime == "linear":
        return {"f0": theta[0], "zeta0": theta[1]}
    out = {"f0": theta[0], "zeta0": theta[1], "chi": theta[2]}
    if regime == "microslip":
        out["delta"] = theta[3]
        return out
    p, k_inf = full_parameters(theta)
    out.update(beta=p.beta, kappa=theta[3], phi_max=p.phi_max, KT=p.KT, K_inf=k_inf, Fs=p.Fs)
    return out
