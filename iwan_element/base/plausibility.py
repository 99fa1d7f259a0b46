"""Whether a measured record can be a vibration test of a jointed structure: one rule for
every entry that reads a measurement (ring-downs, sweeps, stepped sines, multi-sensor decays).

A record given in the wrong quantity or unit is read as a displacement amplitude ``X`` [m]
``1000`` or ``w**2`` times off, and every later stage fits it without complaint (issue 45:
an accelerometer record declared displacement gave ``X = 39.7 m``, "usable"). What such a
record cannot hide is the velocity ``w X`` and acceleration ``w**2 X`` it implies:

* :data:`V_MAX` = 10 m/s. Peak velocity of a bolted or lap-jointed structure in a vibration
  test. Electrodynamic modal shakers are rated to about 1-2 m/s; a hammer ring-down of the
  Brake-Reuss beam (72 cm, 3 bolts, Rice University data in ``../shared/data``) reaches about
  0.1 m/s at its first mode, its force-controlled stepped sines 0.14 m/s at 275 um and 80 Hz;
  1 mm at 1.6 kHz (far beyond any joint test's amplitude at that frequency) is 10 m/s. Above it
  the record is another quantity (acceleration declared displacement moves at thousands of
  m/s) or another unit (mm/s^2 read as m/s^2 is 1000 times too fast).
* :data:`A_MAX` = 2e4 m/s^2 (about 2000 g) of one mode. The accelerometers of modal tests
  (10-100 mV/g) saturate at 50-500 g, and a joint's vibration test stays well inside them (the
  same beam: 70 m/s^2 in its sweeps, 700 m/s^2 at the hammer's hit, all modes together). A
  high mode read in mm/s^2 as m/s^2 can stay below :data:`V_MAX` (100 m/s^2 at 2 kHz read
  1000x is 8 m/s) but not below this.

The checks compare the levels of what was identified (amplitude and frequency of each point
of a curve: :func:`level_failure`) and, for a time record declared displacement or velocity,
the record's own derivatives (:func:`record_failure`): a record whose content makes
``w X`` or ``w**2 X`` implausible rises with frequency like the quantity it really is (an
acceleration's spectrum is flat where a displacement's falls as ``f**-2``), and its
derivative shows it whatever its band. Each message names the argument, the levels reached
and the likely slip (the quantity or unit that would make the levels plausible). An
acceleration record declared acceleration but truly displacement is not caught: its levels
are small, not implausible, and a hammer's soft tip makes a true acceleration spectrum fall
like a displacement's.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["A_MAX", "V_MAX", "QUANTITY_POWER", "level_failure", "record_failure"]

#: Largest velocity amplitude [m/s] a vibration test of a jointed structure reaches.
V_MAX = 10.0
#: Largest acceleration amplitude [m/s^2] of one mode in such a test (about 2000 g).
A_MAX = 2.0e4

#: The power of the angular frequency that turns a displacement amplitude into each
#: quantity's amplitude (``Y = w**k X``).
QUANTITY_POWER = {"displacement": 0, "velocity": 1, "acceleration": 2}
_UNIT = {"displacement": "m", "velocity": "m/s", "acceleration": "m/s^2"}
_MILLI = {"displacement": "mm", "velocity": "mm/s", "acceleration": "mm/s^2"}
_MICRO = {"displacement": "um", "velocity": "um/s", "acceleration": "um/s^2"}


def _levels(X, w) -> tuple[float, float]:
    return float(np.max(w * X)), float(np.max(w * w * X))


def _plausible(X, w) -> bool:
    v, a = _levels(X, w)
    return v <= V_MAX and a <= A_MAX


def _likely_slip(X, w, quantity: str) -> str:
    """The first reading of the same numbers that gives plausible levels: another quantity
    in SI units, the same quantity in milli- or micro-units, another quantity in milli-units.
    """
    k = QUANTITY_POWER[quantity]
    others = [q for q in QUANTITY_POWER if q != quantity]
    tries = [(q, 1.0, f"{q} in {_UNIT[q]} (give quantity={q!r})") for q in others]
    tries += [
        (
            quantity,
            1e-3,
            f"{quantity} in {_MILLI[quantity]} given as {_UNIT[quantity]} "
            "(1000x too large: divide by 1000)",
        ),
        (
            quantity,
            1e-6,
            f"{quantity} in {_MICRO[quantity]} given as {_UNIT[quantity]} (1e6x too large)",
        ),
    ]
    tries += [
        (q, 1e-3, f"{q} in {_MILLI[q]} (give quantity={q!r} and divide by 1000)") for q in others
    ]
    for q, scale, text in tries:
        if _plausible(scale * X * w ** (k - QUANTITY_POWER[q]), w):
            return f"it is likely {text}"
    return "check the quantity and the units of the record"


def level_failure(amplitude, frequency, *, quantity: str, name: str) -> str:
    """Why displacement amplitudes read from a record cannot be a jointed structure's
    vibration test ("" when they can).

    Parameters
    ----------
    amplitude : array_like
        Displacement amplitudes [m] identified from the record (each point of a curve, each
        sweep line), after the record was read as ``quantity``.
    frequency : array_like
        Frequency of each amplitude [Hz] (same shape).
    quantity : {"displacement", "velocity", "acceleration"}
        What the caller declared the record to be.
    name : str
        The argument that holds the record, named in the message.

    Returns
    -------
    str
        "" when the velocity ``w X`` stays within :data:`V_MAX` and the acceleration
        ``w**2 X`` within :data:`A_MAX`; otherwise a sentence naming ``name``, the levels,
        the limits and the likely slip.
    """
    X = np.abs(np.asarray(amplitude, dtype=float)).ravel()
    w = 2.0 * math.pi * np.abs(np.asarray(frequency, dtype=float)).ravel()
    ok = np.isfinite(X) & np.isfinite(w)
    X, w = X[ok], w[ok]
    if X.size == 0 or _plausible(X, w):
        return ""
    v, a = _levels(X, w)
    return (
        f"{name} read as {quantity} [{_UNIT[quantity]}] gives displacement amplitudes up to "
        f"{X.max():.3g} m moving at up to {v:.3g} m/s and {a:.3g} m/s^2, beyond any "
        f"vibration test of a jointed structure ({V_MAX:g} m/s, {A_MAX:g} m/s^2): "
        f"{_likely_slip(X, w, quantity)}; not usable until the quantity and units are checked"
    )


def record_failure(y, dt: float, *, quantity: str, name: str) -> str:
    """Why a time record declared displacement or velocity cannot be one ("" when it can).

    The record's derivatives (central differences, which under-read the highest
    frequencies, so the check errs on the lenient side) give its velocity and acceleration;
    their 99.5th percentiles of magnitude (a few glitches do not count) are compared with
    :data:`V_MAX` and ten times :data:`A_MAX` (all modes and the impact together, not one
    mode). An acceleration record declared displacement is differentiated twice and moves
    at 1e4-1e7 m/s; a true displacement record, even in micrometres at 100 kHz with a
    nanometre of noise, stays below 1e-3 m/s. Acceleration records are not checked here
    (their modes are, by :func:`level_failure`).

    Parameters
    ----------
    y : ndarray, shape (n,)
        The record, in SI units of ``quantity``.
    dt : float or ndarray, shape (n,)
        Sample step [s], or the sample times [s] of a record not sampled uniformly.
    quantity : {"displacement", "velocity", "acceleration"}
        What the caller declared the record to be.
    name : str
        The argument that holds the record, named in the message.
    """
    k = QUANTITY_POWER[quantity]
    if k == 2 or np.size(y) < 3:
        return ""
    d1 = np.gradient(np.asarray(y, dtype=float), dt)
    vel = d1 if k == 0 else np.asarray(y, dtype=float)
    acc = np.gradient(d1, dt) if k == 0 else d1
    v = float(np.percentile(np.abs(vel), 99.5))
    a = float(np.percentile(np.abs(acc), 99.5))
    if v <= V_MAX and a <= 10.0 * A_MAX:
        return ""
    raw = float(np.percentile(np.abs(np.asarray(y, dtype=float)), 99.5))
    fits = []
    if k == 0 and raw <= V_MAX and v <= 10.0 * A_MAX:  # read as velocity: y, y'
        fits.append("velocity in m/s (give quantity='velocity')")
    if raw <= 10.0 * A_MAX:
        fits.append("acceleration in m/s^2 (give quantity='acceleration')")
    likely = " or ".join(fits) or f"{quantity} in milli- or micro-units given as {_UNIT[quantity]}"
    return (
        f"{name} read as {quantity} [{_UNIT[quantity]}] moves at {v:.3g} m/s and "
        f"{a:.3g} m/s^2 (99.5th percentiles of its derivatives), beyond any vibration test "
        f"of a jointed structure ({V_MAX:g} m/s, {10 * A_MAX:g} m/s^2 all modes together): "
        f"the record is likely {likely}; not usable until the quantity and units are "
        "checked"
    )
