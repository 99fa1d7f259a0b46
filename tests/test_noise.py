"""Noise estimation from one record (no repeated cycles): known synthetic noise, every protocol."""

import zlib

import numpy as np
import pytest
from scipy.signal import lfilter

from iwan_element import IwanJoint, IwanParameters
from iwan_element.identify.loops.noise import NoiseEstimate, estimate_noise

P = IwanParameters(Fs=800.0, KT=3e6, chi=-0.4, beta=0.5)
FS, N = 500.0, 6000  # 500 Hz, 12 s, 0.5 Hz loading: 1000 samples a period
T = np.arange(N) / FS


def _protocol(name, rng):
    w = 2 * np.pi * 0.5
    if name == "constant":
        return 1e-3 * np.sin(w * T)
    if name == "ramped":
        return 1e-3 * np.linspace(0.1, 1.0, N) * np.sin(w * T)
    if name == "swept":  # 0.2 -> 1 Hz
        return 1e-3 * np.sin(2 * np.pi * (0.2 * T + 0.4 * T**2 / T[-1]))
    amps = np.repeat(rng.uniform(0.1, 1.0, N // 1000 + 1), 1000)[:N]  # random per cycle
    return 1e-3 * amps * np.sin(w * T)


def _noise(kind, rng, sigma):
    e = rng.normal(size=N)
    if kind == "ar":  # AR(1), phi = 0.6, unit stationary variance
        e = lfilter([np.sqrt(1 - 0.36)], [1, -0.6], e)
    return sigma * e


@pytest.mark.parametrize("protocol", ["constant", "ramped", "swept", "random"])
@pytest.mark.parametrize("kind", ["white", "ar"])
def test_estimate_matches_known_noise_on_both_channels(protocol, kind):
    # a stable seed: hash() of strings changes with every interpreter (PYTHONHASHSEED)
    rng = np.random.default_rng(zlib.crc32(f"{protocol}-{kind}".encode()))
    u = _protocol(protocol, rng)
    F = IwanJoint(P).force_history(u)  # independent route: the exact element, kinks included
    for y, s in ((u, 2e-6), (F, 4.0)):
        est = estimate_noise(T, y + _noise(kind, rng, s))
        lo = 0.85 if kind == "white" else 0.75  # noise correlated over ~4 samples: most is seen
        assert lo * s < est.sigma < 1.15 * s, (protocol, kind, est)
        if kind == "white":
            # u is smooth: n_eff ~ n. The force has kinks at macroslip entry whose leak into the
            # residual is correlated, which lowers n_eff (conservative), but not by much
            assert est.n_eff > (0.8 if y is u else 0.2) * N, est
        else:  # AR(1) 0.6: integrated time (1+phi)/(1-phi) = 4 samples
            # (the force's kinks leak a little correlated signal: a longer time, conservative)
            assert 2.5 < est.correlation_time * FS < (6.0 if y is u else 8.0), est
            assert 0.3 < est.lag_one < 0.8, est


@pytest.mark.parametrize("rho", [0.0, 0.5])
def test_coloured_residual_with_the_channel_window(rho):
    """A fit residual that is pure AR(1) noise (what the diagnoses pass): with the measured
    channel's window the level and the correlation time are those of the noise (the old
    estimator read tau = 1 for rho = 0.5, true 3, on such residuals)."""
    sig, tau = [], []
    for seed in range(12):
        rng = np.random.default_rng(100 + seed)
        e = lfilter([np.sqrt(1 - rho**2)], [1, -rho], rng.normal(size=1400))[200:]
        est = estimate_noise(np.arange(1200) / 128.0, 3.0 * e, window=32 / 128.0)
        sig.append(est.sigma / 3.0)
        tau.append(est.tau)
    true_tau = (1 + rho) / (1 - rho)
    assert 0.9 < np.median(sig) < 1.1 and max(sig) < 1.35 and min(sig) > 0.8, sig
    assert 0.75 * true_tau < np.median(tau) < 1.35 * true_tau, tau


def test_pure_noise_and_difference_method():
    rng = np.random.default_rng(3)
    y = rng.normal(0.0, 2.5, N)
    for m in ("auto", "difference"):
        est = estimate_noise(T, y, method=m)
        assert abs(est.sigma / 2.5 - 1) < 0.08
    # the difference method does not see coloured noise; savgol does (most of it)
    e = lfilter([np.sqrt(1 - 0.64)], [1, -0.8], rng.normal(size=N))
    u = _protocol("constant", rng) + 2e-6 * e
    assert estimate_noise(T, u, method="difference").sigma < 0.6 * estimate_noise(T, u).sigma


def test_chatter_bursts_do_not_dominate():
    rng = np.random.default_rng(5)
    u = _protocol("constant", rng)
    F = IwanJoint(P).force_history(u) + rng.normal(0, 3.0, N)
    rev = np.flatnonzero(np.diff(np.sign(np.diff(u)))) + 1
    for i in rev:  # 45 Hz ringing, 60 ms, after each reversal
        k = np.arange(min(30, N - i))
        F[i : i + k.size] += 150.0 * np.exp(-k / 10.0) * np.sin(2 * np.pi * 45 * k / FS)
    est = estimate_noise(T, F)
    assert est.sigma < 1.3 * 3.0


def test_result_and_errors_and_no_mutation():
    rng = np.random.default_rng(0)
    y = rng.normal(size=100)
    t = np.arange(100.0)
    y0, t0 = y.copy(), t.copy()
    est = estimate_noise(t, y)
    assert isinstance(est, NoiseEstimate) and est.to_dict()["method"] == "savgol+ar1"
    assert "sigma" in est.report()
    np.testing.assert_array_equal(y, y0)
    np.testing.assert_array_equal(t, t0)
    with pytest.raises(ValueError, match="method"):
        estimate_noise(t, y, method="mad")
    with pytest.raises(ValueError, match="y"):
        estimate_noise(t, np.r_[y[:-1], np.nan])
    with pytest.raises(ValueError, match="same length"):
        estimate_noise(t[:-1], y)
    with pytest.raises(ValueError, match="t"):
        estimate_noise(t[::-1], y)
    with pytest.raises(ValueError, match="at least 32"):
        estimate_noise(t[:10], y[:10])
    flat = estimate_noise(t, np.ones(100))
    assert flat.sigma == 0.0 and flat.warnings
