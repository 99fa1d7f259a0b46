"""The band-passed analytic signal of a record and a mode's envelope: the one band-pass +
Hilbert route of the package.

:func:`analytic_signal` band-passes a record with a zero-phase Butterworth filter
(``scipy.signal.butter`` as second-order sections, ``scipy.signal.sosfiltfilt``, which
applies ``|H|**2`` without delay) and takes its analytic signal ``z = y_f + i H[y_f]``
(``scipy.signal.hilbert``): ``|z|`` is the envelope of the mode in the band and
``unwrap(angle z)`` its phase (J. S. Bendat, A. G. Piersol, *Random Data*, 4th ed., 2010,
section 13.1). Two options for records that start or end abruptly (a ring-down cropped at
the impact):

* ``taper_ends=True``: half-Hann ramps over the filter's own end effects (the samples until
  its impulse response stays below 1e-3 of its peak, at most a quarter of the record), so
  the Hilbert kernel's slow ``1/t`` decay does not spread a step at the record's ends over
  the whole record;
* ``pad=True``: the FFT-based transform zero-padded to at least twice the record's length
  (the transform is circular: unpadded, a ring-down's large start leaks into its quiet end).

:func:`mode_envelope` is the envelope of one mode in a band, optionally divided by
``w**integrate`` with ``w`` [rad/s] the mode's own frequency (the mean rate of the analytic
signal's phase): ``integrate=2`` reads a displacement envelope [m] from an acceleration
record [m/s^2]. The mode's own frequency, not the band's centre: 80.4 Hz in a 60-120 Hz
band, a centre's ``w**2`` reads the displacement 20 % low.

Users: the free-decay filter (:mod:`._filter`, tapered and padded), the flattened-peak
detector (:mod:`.saturation`, plain) and the hammer-test prediction
(:mod:`iwan_element.models.hammer`, a displacement envelope from acceleration).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy import signal

__all__ = ["analytic_signal", "mode_envelope"]


def _filter_extent(sos, fs, lo, hi):
    """Samples until the one-pass impulse response stays below 1e-3 of its peak."""
    n = int(max(64, 40.0 * fs / (hi - lo)))
    imp = np.zeros(n)
    imp[0] = 1.0
    h = np.abs(signal.sosfilt(sos, imp))
    above = np.flatnonzero(h > 1e-3 * h.max())
    return int(above[-1]) + 1


def _hilbert(y):
    """Analytic signal, zero-padded to at least twice the length (no circular wrap)."""
    return signal.hilbert(y, N=int(2 ** math.ceil(math.log2(2 * y.size))))[: y.size]


def _ramp_ends(x, n0, n1):
    """Half-Hann ramps over the first ``n0`` and the last ``n1`` samples (copy)."""
    out = x.copy()
    for n, sl, rev in ((n0, slice(0, n0), False), (n1, slice(x.size - n1, x.size), True)):
        if n > 0:
            r = 0.5 - 0.5 * np.cos(np.pi * (np.arange(n) + 0.5) / n)
            out[sl] *= r[::-1] if rev else r
    return out


def analytic_signal(
    y, fs: float, band, *, order: int = 4, taper_ends: bool = False, pad: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.complex128]]:
    """Zero-phase band-passed record and its analytic signal (module docstring).

    Parameters
    ----------
    y : ndarray, shape (n,)
        The record (finite; any unit), uniformly sampled.
    fs : float
        Sampling rate [Hz].
    band : (float, float)
        Pass band ``(low, high)`` [Hz], ``0 < low < high < fs / 2``.
    order : int, keyword-only
        Butterworth order of the band-pass (per pass; ``sosfiltfilt`` runs it twice).
    taper_ends : bool, keyword-only
        Ramp the filter's end effects down before the Hilbert transform.
    pad : bool, keyword-only
        Zero-pad the transform to at least twice the record's length.

    Returns
    -------
    sos : ndarray
        The band-pass as second-order sections.
    yf : ndarray, shape (n,)
        The band-passed record (untapered), in the unit of ``y``.
    z : ndarray of complex, shape (n,)
        Its analytic signal: ``|z|`` the envelope, ``angle(z)`` the phase [rad].
    """
    sos = signal.butter(order, band, btype="bandpass", fs=fs, output="sos")
    yf = signal.sosfiltfilt(sos, y)
    yt = yf
    if taper_ends:
        m = min(_filter_extent(sos, fs, band[0], band[1]), y.size // 4)
        yt = _ramp_ends(yf, m, m)
    z = _hilbert(yt) if pad else signal.hilbert(yt)
    return sos, yf, z


def mode_envelope(
    t, y, band, *, order: int = 4, integrate: int = 0, span=None
) -> NDArray[np.float64]:
    """Envelope of the mode in ``band`` [Hz] of the record ``y`` at times ``t`` [s].

    ``|z| / w**integrate`` with ``z`` the zero-phase band-passed analytic signal
    (:func:`analytic_signal`, unpadded) and ``w`` [rad/s] the slope of a straight line
    through the unwrapped phase over ``span`` (a boolean mask; default the whole record):
    ``integrate=2`` turns an acceleration envelope [m/s^2] into a displacement one [m].
    ``t`` must be uniformly sampled (the rate is ``(n - 1) / (t[-1] - t[0])``).
    """
    fs = (t.size - 1) / (t[-1] - t[0])
    _, _, z = analytic_signal(y, fs, band, order=order)
    env = np.abs(z)
    if integrate:
        m = slice(None) if span is None else span
        w = np.polyfit(t[m], np.unwrap(np.angle(z))[m], 1)[0]
        scale = 1.0
        for _ in range(integrate):
            scale *= w
        env = env / scale
    return env
