"""Seeded amplitude curves of one jointed mode with a hidden vibration effect.

The truth is made by a route independent of the modal forms the diagnosis fits: the
time-domain elements (``make_effect(name, IwanJoint(P))``) driven from rest into a steady
sinusoidal cycle at each amplitude, first-harmonic stiffness and loop area by quadrature of
the simulated force (harmonic balance of one mass-normalised mode, ``m = 1``, slip = modal
amplitude). Only the *size* of each hidden effect is set with the modal form: the size at
which the effect changes the curves by ``size`` times "noticeable", noticeable meaning an RMS
change over the points, in units of each curve's noise, of ``NOTICEABLE`` (module constant).
Noise: relative, log-normal, frequency ``F_NOISE`` and damping ``Z_NOISE`` by default.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from iwan_element import IwanJoint, IwanParameters, make_effect
from iwan_element.effects import EFFECTS

F_NOISE, Z_NOISE, NOTICEABLE = 1e-4, 0.03, 4.0
K_INF, ZETA0 = 1.4212e5, 1e-3


def element_curve(X, P, name=None, n=720, **values):
    """Frequency [Hz] and damping ratio [-] at amplitudes ``X`` [m] of the mode
    ``q'' + 2 zeta0 w0 q' + K_INF q + F(q) = 0`` with ``F`` the element (joint ``P`` wrapped
    in effect ``name`` with joint parameters ``values``), by harmonic balance on simulated
    steady cycles."""
    th = np.linspace(0.0, 0.5 * np.pi + 2 * np.pi, n // 4 + n + 1)
    f_out, z_out = [], []
    for x in np.atleast_1d(X):
        el = IwanJoint(P) if name is None else make_effect(name, IwanJoint(P), **values)
        u = x * np.sin(th)
        F = el.force_history(u)
        Fc, uc, thc = F[-(n + 1) :], u[-(n + 1) :], th[-(n + 1) :]
        k1 = np.trapezoid(Fc * np.sin(thc), thc) / (np.pi * x)
        D = abs(np.trapezoid(Fc, uc))
        wn2 = K_INF + k1
        f_out.append(np.sqrt(wn2) / (2 * np.pi))
        z_out.append(D / (2 * np.pi * wn2 * x**2) + ZETA0)
    return np.array(f_out), np.array(z_out)


def _shape(name, X, rng):
    """Joint/modal parameters of ``name`` at unit size, and the name of the size parameter.
    (m = 1 and slip = amplitude, so modal and joint values coincide up to names.)"""
    Xm = float(X.max())
    if name == "hardening":
        return {"k3_per_mass": 1.0}, "k3_per_mass"
    if name == "macroslip_onset":  # half the cases a whole patch, half a spread one
        xs = float(rng.uniform(0.3, 0.7)) * Xm
        shape = float(rng.uniform(0.15, 0.5)) if rng.uniform() < 0.5 else 0.0
        return {"kappa_2": 1.0, "X_s": xs, "shape": shape}, "kappa_2"
    if name == "pinning_stiffness":
        return {"k_p_per_mass": 1.0, "delta": float(rng.uniform(0.0, 0.5)) * Xm}, "k_p_per_mass"
    if name == "viscous_damping":
        return {"zeta_v": 1.0}, "zeta_v"
    raise ValueError(name)


def hidden_values(name, X, fp, zp, size, rng, *, f_noise=F_NOISE, z_noise=Z_NOISE):
    """Modal parameters of a hidden ``name`` whose change of the curves is ``size`` x
    noticeable (RMS over points of the noise-normalised log change = size * NOTICEABLE)."""
    vals, key = _shape(name, X, rng)

    def rms(g):
        v = dict(vals, **{key: g})
        f, z = EFFECTS[name].modal_form(X, fp, zp, ZETA0, **v)
        return np.sqrt(np.mean((np.log(f / fp) / f_noise) ** 2 + (np.log(z / zp) / z_noise) ** 2))

    target = size * NOTICEABLE
    hi = 1e-12
    while rms(hi) < target:
        hi *= 4.0
    vals[key] = brentq(lambda g: rms(g) - target, hi / 4.0, hi, xtol=1e-14 * hi, rtol=1e-10)
    return vals


def to_joint(name, values):
    """Joint parameters of the modal values (m = 1, slip per amplitude 1)."""
    return EFFECTS[name].modal_to_joint(values, modal_mass=1.0, slip_per_amplitude=1.0, omega0=1.0)


def seeded_case(seed, name, size, *, P, X, base=None, f_noise=F_NOISE, z_noise=Z_NOISE):
    """(X, f_meas, z_meas, f_pred, z_pred, hidden modal values): the measurement is the
    elements' curve with hidden effect ``name`` (``None``: clean) plus noise; the prediction
    is the plain joint's curve from the same route."""
    rng = np.random.default_rng(seed)
    fp, zp = element_curve(X, P) if base is None else base
    if name is None:
        fm, zm, vals = fp, zp, {}
    else:
        vals = hidden_values(name, X, fp, zp, size, rng, f_noise=f_noise, z_noise=z_noise)
        if name == "viscous_damping":  # a dashpot needs the velocity: added in closed form
            fm, zm = fp, zp + vals["zeta_v"]
        else:
            fm, zm = element_curve(X, P, name, **to_joint(name, vals))
    fm = fm * np.exp(f_noise * rng.normal(size=X.size))
    zm = zm * np.exp(z_noise * rng.normal(size=X.size))
    return X, fm, zm, fp, zp, vals


BASE = IwanParameters(400.0, 2.5266e5, -0.5, 1.0)
