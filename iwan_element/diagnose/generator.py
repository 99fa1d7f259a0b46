"""The test generator of the package: a displacement-driven test of any joint element."""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from ..base.validation import check_int, check_magnitude, check_scalar, finite_array
from ..core.protocol import check_element
from ..identify.loops.testdata import TestData

__all__ = ["simulate_element_test"]


def _drive(amps, cycles, n_per, waveform, envelope):
    """Displacement of the protocol, from and back to rest at 0."""
    if envelope == "linear":  # amplitude interpolated continuously
        n = n_per * cycles * (amps.size - 1 if amps.size > 1 else 1)
        ph = np.arange(n) / n_per
        env = np.interp(np.linspace(0.0, 1.0, n), np.linspace(0.0, 1.0, amps.size), amps)
        base = (
            np.sin(2 * np.pi * ph)
            if waveform == "sine"
            else np.where(
                (ph + 0.25) % 1.0 < 0.5, 4 * ((ph + 0.25) % 1.0) - 1, 3 - 4 * ((ph + 0.25) % 1.0)
            )
        )
        return np.concatenate([env * base, np.zeros(1)])
    if waveform == "sine":
        ph = np.arange(n_per * cycles) / n_per
        blocks = [a * np.sin(2 * np.pi * ph) for a in amps]
    else:  # constant rate 4 max(a) f: shorter periods at small amplitudes
        blocks = []
        for a in amps:
            n_a = max(8, int(round(n_per * a / amps.max())))
            frac = (np.arange(n_a * cycles) / n_a + 0.25) % 1.0
            blocks.append(a * np.where(frac < 0.5, 4 * frac - 1, 3 - 4 * frac))
    return np.concatenate(blocks + [np.zeros(1)])


def _noise(rng, n, sigma, phi):
    e = rng.normal(0.0, 1.0, n)
    if phi > 0.0:
        e = lfilter([math.sqrt(1 - phi * phi)], [1.0, -phi], e)
    return sigma * e


def simulate_element_test(
    element,
    amplitude,
    *,
    cycles: int = 3,
    frequency: float = 1.0,
    samples_per_cycle: int = 96,
    waveform: str = "sine",
    envelope: str = "steps",
    force_noise: float = 0.0,
    displacement_noise: float = 0.0,
    noise_correlation: float = 0.0,
    force_offset: float = 0.0,
    displacement_offset: float = 0.0,
    rest_samples: int = 0,
    seed=0,
) -> TestData:
    """Displacement-driven test of any joint element (an effect stack included), with sensor
    noise and offsets.

    Parameters
    ----------
    element : joint element
        Anything with ``force_history(u, v)`` or ``force_history(u)`` (``IwanJoint``).
    amplitude : array_like, shape (m,)
        Displacement amplitudes [m], ``> 0``.
    cycles : int, keyword-only
        ``envelope="steps"``: periods per amplitude; ``"linear"``: periods between two
        consecutive listed amplitudes. ``>= 1``.
    frequency : float, keyword-only
        Loading frequency [Hz], ``> 0``.
    samples_per_cycle : int, keyword-only
        Samples per period, ``>= 16``.
    waveform : {"sine", "triangle"}, keyword-only
        ``"triangle"`` with ``"steps"`` loads at one constant rate ``4 max(amplitudes) f``.
    envelope : {"steps", "linear"}, keyword-only
        ``"steps"``: each amplitude held for ``cycles`` periods (constant envelope per block);
        ``"linear"``: the amplitude ramps linearly through the listed values (a ramped
        envelope for two values, a triangular one for ``[a, b, a]``).
    force_noise, displacement_noise : float, keyword-only
        Standard deviations of the sensor noise [N], [m], ``>= 0``.
    noise_correlation : float, keyword-only
        Lag-one correlation of both noises, ``[0, 1)``: AR(1) coloured noise.
    force_offset, displacement_offset : float, keyword-only
        Sensor zero offsets [N], [m] added to the measured channels.
    rest_samples : int, keyword-only
        Samples at rest recorded before the motion starts, ``>= 0``.
    seed : int or numpy.random.Generator, keyword-only

    Returns
    -------
    TestData
        The measured record (the element sees the true displacement and the velocity
        ``np.gradient(u, t)``).
    """
    check_element(element, name="element")
    if not callable(getattr(element, "force_history", None)):
        raise ValueError(
            f"element must have a force_history(u[, v]) method; {type(element).__name__} has none"
        )
    amps = check_magnitude("amplitude", finite_array("amplitude", amplitude, ndim=1), unit="m")
    if np.any(amps <= 0.0):
        raise ValueError("amplitude must all be > 0 [m]")
    cycles = check_int("cycles", cycles, 1)
    f = check_scalar("frequency", frequency, low=0.0, low_open=True)
    n_per = check_int("samples_per_cycle", samples_per_cycle, 16)
    if waveform not in ("sine", "triangle"):
        raise ValueError(f"waveform must be 'sine' or 'triangle', got {waveform!r}")
    if envelope not in ("steps", "linear"):
        raise ValueError(f"envelope must be 'steps' or 'linear', got {envelope!r}")
    sf = check_scalar("force_noise", force_noise, low=0.0, high=1e100)
    su = check_scalar("displacement_noise", displacement_noise, low=0.0, high=1e100)
    phi = check_scalar("noise_correlation", noise_correlation, low=0.0, high=1.0, high_open=True)
    f0 = check_scalar("force_offset", force_offset)
    u0 = check_scalar("displacement_offset", displacement_offset)
    n_rest = check_int("rest_samples", rest_samples, 0)
    rng = np.random.default_rng(seed)
    u = np.concatenate([np.zeros(n_rest), _drive(amps, cycles, n_per, waveform, envelope)])
    t = np.arange(u.size) / (n_per * f)
    v = np.gradient(u, t)
    F = element.force_history(u, v) + f0 + (_noise(rng, u.size, sf, phi) if sf > 0 else 0.0)
    u_meas = u + u0 + (_noise(rng, u.size, su, phi) if su > 0 else 0.0)
    return TestData.from_arrays(t, u_meas, F, source=f"simulate_element_test({element!r})")
