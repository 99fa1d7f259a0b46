"""Synthetic test records with a hidden effect, shared by tests/test_diagnosis.py and
benchmarks/bench_diagnosis.py. The diagnosis is never told which effect is hidden.

Joint: the REFERENCE.md sec. 5 test vector (Fs, KT, chi, beta) = (1000 N, 1e6 N/m, -0.5, 0.2),
phi_max = 2.25 mm. Each amplitude is applied for three cycles of 96 samples at 1 Hz; the force
noise is 5 N (0.5 % of Fs), white or AR(1)-coloured.

The magnitude of an effect is the RMS of the force it adds on the protocol,
``rms(F_effect - F_iwan)`` with the same Iwan parameters, in units of the noise RMS.
"""
from __future__ import annotations

import functools
import math

import numpy as np

from iwan_element import IwanJoint, IwanParameters, make_effect
from iwan_element.diagnosis import simulate_element_test

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
}


def drive(protocol, waveform="sine"):
    """(u, v) of a protocol without noise, as simulate_element_test builds them."""
    d = simulate_element_test(IwanJoint(P), np.array(PROTOCOLS[protocol]) * P.phi_max,
                              waveform=waveform)
    v = np.gradient(d.u, d.t)
    return d.u, v


def element(name, value, inner=None):
    key, extra = SHAPES[name]
    return make_effect(name, IwanJoint(P) if inner is None else inner, **{key: value}, **extra)


def effect_rms(name, value, protocol):
    u, v = drive(protocol)
    base = IwanJoint(P).force_history(u)
    return float(np.sqrt(np.mean((element(name, value).force_history(u, v) - base) ** 2)))


@functools.lru_cache(maxsize=None)
def calibrated(name, magnitude, protocol):
    """Effect parameter whose added force has RMS ``magnitude * SIGMA`` on ``protocol``."""
    target = magnitude * SIGMA
    guess = {"c": 1.0, "k_p": 1e4, "gap": 1e-5, "rate": 1e-3, "asymmetry": 0.01}[SHAPES[name][0]]
    lo = hi = guess
    while effect_rms(name, hi, protocol) < target:
        hi *= 2.0
    while effect_rms(name, lo, protocol) > target:
        lo /= 2.0
    for _ in range(30):                      # bisection in log space, to 0.1 %
        mid = math.sqrt(lo * hi)
        if effect_rms(name, mid, protocol) < target:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.001:
            break
    return math.sqrt(lo * hi)


def record(name, magnitude, protocol, seed, *, colour=0.0, waveform="sine", el=None):
    """TestData with the named effect hidden (``name=None``: clean Iwan joint)."""
    if el is None:
        el = IwanJoint(P) if name is None else element(name, calibrated(name, magnitude, protocol))
    return simulate_element_test(el, np.array(PROTOCOLS[protocol]) * P.phi_max,
                                 force_noise=SIGMA, noise_correlation=colour, seed=seed,
                                 waveform=waveform)
