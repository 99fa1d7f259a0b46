"""Synthetic test records with a hidden effect, shared by tests/test_diagnosis.py and
benchmarks/bench_diagnosis.py. The diagnosis is never told which effect is hidden.

Joint: the docs/equations.md section 5 test vector (Fs, KT, chi, beta) =
(1000 N, 1e6 N/m, -0.5, 0.2), phi_max = 2.25 mm. Each amplitude is applied for three cycles
of 96 samples at 1 Hz; the force noise is 5 N (0.5 % of Fs), white or AR(1)-coloured.

The magnitude of an effect is the RMS of the force it adds on the protocol,
``rms(F_effect - F_iwan)`` with the same Iwan parameters, in units of the noise RMS.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from iwan_element import IwanJoint, IwanParameters, make_effect
from iwan_element.diagnose import simulate_element_test

P = IwanParameters(1000.0, 1e6, -0.5, 0.2)
SIGMA = 5.0
PROTOCOLS = {  # amplitudes / phi_max
    "ladder": (0.3, 0.6, 1.0, 1.5),
    "mixed": (1.3, 0.4, 0.8, 0.25),
}
MAGNITUDES = (2.0, 4.0, 8.0)
# effect parameters other than the one scaled to the magnitude
SHAPES = {
    "viscous_damping": ("c", {}),
    "pinning_stiffness": ("k_p", {"delta": 0.5 * P.phi_max}),
    "backlash": ("gap", {}),
    "slip_degradation": ("rate", {}),
    "asymmetric_slip": ("asymmetry", {}),
    "breakaway": ("ratio", {}),
}


def drive(protocol, waveform="sine"):
    """(u, v) of a protocol without noise, as simulate_element_test builds them."""
    d = simulate_element_test(
        IwanJoint(P), np.array(PROTOCOLS[protocol]) * P.phi_max, waveform=waveform
    )
    v = np.gradient(d.u, d.t)
    return d.u, v


def element(name, value, inner=None):
    key, extra = SHAPES[name]
    return make_effect(name, IwanJoint(P) if inner is None else inner, **{key: value}, **extra)


def effect_rms(name, value, protocol):
    u, v = drive(protocol)
    base = IwanJoint(P).force_history(u)
    return float(np.sqrt(np.mean((element(name, value).force_history(u, v) - base) ** 2)))


@functools.cache
def calibrated(name, magnitude, protocol):
    """Effect parameter whose added force has RMS ``magnitude * SIGMA`` on ``protocol`` (to
    0.5 %), by secant steps on ``log rms`` against ``log parameter``."""
    target = magnitude * SIGMA
    key = SHAPES[name][0]
    if key == "ratio":  # break-away: the size is ratio - 1
        x = _calibrate(lambda y: effect_rms(name, 1.0 + y, protocol), 0.05, target)
        return 1.0 + x
    x0 = {"c": 1.0, "k_p": 1e4, "gap": 1e-5, "rate": 1e-3, "asymmetry": 0.01}[key]
    return _calibrate(lambda y: effect_rms(name, y, protocol), x0, target)


def _calibrate(rms, x0, target):
    """Parameter ``x`` with ``rms(x) = target`` (to 0.5 %): bracket by factors of 4 from
    ``x0``, then Brent's method on ``log rms - log target`` in ``log x`` (rms increases with x)."""
    from scipy.optimize import brentq

    def g(lx):
        return math.log(max(rms(math.exp(lx)), 1e-300) / target)

    lo = hi = math.log(x0)
    glo = ghi = g(lo)
    while glo > 0:
        lo -= math.log(4.0)
        glo = g(lo)
    while ghi < 0:
        hi += math.log(4.0)
        ghi = g(hi)
    if lo == hi:
        return x0
    return math.exp(brentq(g, lo, hi, xtol=1e-3, rtol=1e-4))


def record(name, magnitude, protocol, seed, *, colour=0.0, waveform="sine", el=None):
    """TestData with the named effect hidden (``name=None``: clean Iwan joint)."""
    if el is None:
        el = IwanJoint(P) if name is None else element(name, calibrated(name, magnitude, protocol))
    return simulate_element_test(
        el,
        np.array(PROTOCOLS[protocol]) * P.phi_max,
        force_noise=SIGMA,
        noise_correlation=colour,
        seed=seed,
        waveform=waveform,
    )


# ----------------------------------------------------------------------------- vibration
MODAL = IwanParameters(400.0, 2.5266e5, -0.5, 1.0)  # docs/equations.md section 5, modal Iwan
K_INF, M_MODAL, ZETA0 = 1.4212e5, 1.0, 1e-4


def modal_curves(X, *, zeta_v=0.0, k_p=0.0, delta=0.0):
    """Single-mode modal Iwan (docs/equations.md section 5): frequency [Hz] and damping ratio at
    amplitudes X [m], with a hidden viscous ratio ``zeta_v`` and/or a pinning spring
    ``k_p`` [N/m] beyond ``delta`` [m] (harmonic-balance stiffness of the dead-zone spring)."""
    from iwan_element import dissipation, secant_stiffness

    r = np.clip(delta / X, 0.0, 1.0)
    k_eq = k_p * (1 - (2 / np.pi) * (np.arcsin(r) + r * np.sqrt(1 - r * r)))
    wn2 = (K_INF + secant_stiffness(X, MODAL) + k_eq) / M_MODAL
    zeta = dissipation(X, MODAL) / (2 * np.pi * M_MODAL * wn2 * X**2) + ZETA0 + zeta_v
    return np.sqrt(wn2) / (2 * np.pi), zeta


def vibration_case(seed, *, n=30, zeta_v=0.0, k_p=0.0, delta=0.0, f_noise=2e-4, z_noise=0.02):
    """(X, f_meas, z_meas, f_pred, z_pred): measured = hidden effect + relative noise."""
    rng = np.random.default_rng(seed)
    X = np.geomspace(1e-3, 3.0, n) * MODAL.phi_max
    fp, zp = modal_curves(X)
    fm, zm = modal_curves(X, zeta_v=zeta_v, k_p=k_p, delta=delta)
    fm = fm * np.exp(f_noise * rng.normal(size=n))
    zm = zm * np.exp(z_noise * rng.normal(size=n))
    return X, fm, zm, fp, zp


def modal_curves_from_elements(X, *, k_p=0.0, delta=0.0, zeta_v=0.0, n=720):
    """Single-mode curves by an independent route: the time-domain elements
    (``PinningStiffness(IwanJoint(MODAL))``) driven from rest into a steady sinusoidal cycle at
    each amplitude; harmonic balance with the first-harmonic stiffness
    ``(1/(pi X)) int F sin(theta) dtheta`` and the loop area, both by quadrature of the
    simulated force. No closed form and no describing function is used."""
    from iwan_element import PinningStiffness

    th = np.linspace(0.0, 0.5 * np.pi + 2 * np.pi, n // 4 + n + 1)
    f_out, z_out = [], []
    for x in np.atleast_1d(X):
        el = PinningStiffness(IwanJoint(MODAL), k_p=k_p, delta=delta)
        u = x * np.sin(th)
        F = el.force_history(u)
        Fc, uc, thc = F[-(n + 1) :], u[-(n + 1) :], th[-(n + 1) :]
        k1 = np.trapezoid(Fc * np.sin(thc), thc) / (np.pi * x)
        D = abs(np.trapezoid(Fc, uc))
        wn2 = (K_INF + k1) / M_MODAL
        f_out.append(np.sqrt(wn2) / (2 * np.pi))
        z_out.append(D / (2 * np.pi * M_MODAL * wn2 * x**2) + ZETA0 + zeta_v)
    return np.array(f_out), np.array(z_out)


def vibration_case_elements(
    seed, *, n=30, zeta_v=0.0, k_p=0.0, delta=0.0, f_noise=2e-4, z_noise=0.02
):
    """As :func:`vibration_case`, prediction and measurement both from the elements."""
    rng = np.random.default_rng(seed)
    X = np.geomspace(1e-3, 3.0, n) * MODAL.phi_max
    fp, zp = modal_curves_from_elements(X)
    fm, zm = modal_curves_from_elements(X, zeta_v=zeta_v, k_p=k_p, delta=delta)
    fm = fm * np.exp(f_noise * rng.normal(size=n))
    zm = zm * np.exp(z_noise * rng.normal(size=n))
    return X, fm, zm, fp, zp
