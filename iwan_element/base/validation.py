"""Input checks shared by the package: every message names the argument and its allowed range."""

from __future__ import annotations

import math
from dataclasses import fields
from numbers import Real
from typing import Any

import numpy as np


def check_scalar(
    name: str,
    value,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Return ``value`` as a finite float inside the given range, else raise ``ValueError``.

    ``low_open=True`` excludes the lower bound itself (``value > low``).
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(
        value, (Real, np.floating, np.integer)
    ):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {x}")
    rng = _range_text(low, high, low_open, high_open)
    if low is not None and (x < low or (low_open and x == low)):
        raise ValueError(f"{name} must be in {rng}, got {x}")
    if high is not None and (x > high or (high_open and x == high)):
        raise ValueError(f"{name} must be in {rng}, got {x}")
    return x


def _range_text(low, high, low_open, high_open) -> str:
    left = "(" if (low is None or low_open) else "["
    right = ")" if (high is None or high_open) else "]"
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    return f"{left}{lo}, {hi}{right}"


def finite_array(name: str, value, *, ndim: int | None = 1, min_size: int = 1) -> np.ndarray:
    """Return a new float array copy of ``value``; reject NaN/inf, wrong rank or too few entries.

    The copy guarantees that nothing the caller passed is mutated downstream.
    """
    _reject_non_real(name, value)
    try:
        arr = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric array-like ({exc})") from None
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array, got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} must have at least {min_size} entries, got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(f"{name} contains NaN or infinite values (first at index {first})")
    return arr


def _reject_non_real(name: str, value) -> None:
    """Raise ``ValueError`` for text, complex or non-numeric object input, which numpy would
    otherwise parse (``"1.5"``) or truncate (``1+2j -> 1``) silently.
    """
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{name} must be numeric array-like, got text {value!r:.40}")
    kind = np.asarray(value).dtype.kind if not isinstance(value, np.ndarray) else value.dtype.kind
    if kind in "USc" or (
        kind == "O"
        and any(
            isinstance(v, (str, bytes, complex)) or v is None
            for v in np.asarray(value, dtype=object).ravel().tolist()
        )
    ):
        raise ValueError(
            f"{name} must be real numbers, got an array of "
            f"{'complex' if kind == 'c' else 'text or objects'}"
        )


def same_length(**arrays: np.ndarray) -> int:
    """Raise ``ValueError`` unless all the named 1-D arrays have the same length; return it."""
    sizes = {k: len(v) for k, v in arrays.items()}
    if len(set(sizes.values())) > 1:
        desc = ", ".join(f"{k} has {n}" for k, n in sizes.items())
        raise ValueError(f"arrays must have the same length: {desc}")
    return next(iter(sizes.values()))


def check_int(name: str, value, low: int) -> int:
    """Return ``value`` as an int ``>= low``, else raise ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    return int(value)


def check_time(t, n: int, name: str = "t") -> np.ndarray:
    """Return ``t`` as a new finite, strictly increasing array of length ``n``."""
    tt = check_magnitude(name, finite_array(name, t, ndim=1), unit="s")
    if tt.size != n:
        raise ValueError(f"{name} must have the same length as the data ({n}), got {tt.size}")
    bad = np.flatnonzero(np.diff(tt) <= 0.0)
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{name} (time) must be strictly increasing; it goes from {tt[i]:g} to "
            f"{tt[i + 1]:g} at samples {i}..{i + 1}"
        )
    return tt


def check_uniform_time(t, n: int, name: str = "t", data: str = "y") -> tuple[np.ndarray, float]:
    """``(t, dt)``: ``t`` as a new finite, strictly increasing array of length ``n`` (that of
    ``data``) on a uniform grid, and its step [s] (the least-squares grid: the first and last
    samples carry jitter too, so a line through them would double it). Steps may depart from
    the grid by up to 5 % (the rounding of a written time column), not more (gaps).
    """
    tt = finite_array(name, t)
    if tt.size != n:
        raise ValueError(f"{name} must have the same length as {data} ({n}), got {tt.size}")
    d = np.diff(tt)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0])
        raise ValueError(
            f"{name} (time) must be strictly increasing; it goes from {tt[i]:g} to "
            f"{tt[i + 1]:g} at samples {i}..{i + 1}"
        )
    idx = np.arange(n) - 0.5 * (n - 1)
    dt = float(idx @ (tt - tt.mean()) / (idx @ idx))
    jitter = float(np.max(np.abs(tt - tt.mean() - idx * dt)))
    if jitter > 0.05 * dt:
        raise ValueError(
            f"{name} must be uniformly sampled: it departs from a uniform grid by "
            f"{jitter:.3g} s, more than 5 % of the mean step {dt:.3g} s; resample first"
        )
    return tt, dt


#: Magnitude range accepted for measured records and amplitudes (in SI units). Far outside any
#: physical joint test (nm..km, uN..GN), and far enough inside the float range that the squares,
#: products and sums of squares the identification forms (up to ~1e200 / 1e-200 for a record of
#: 1e8 samples) neither overflow nor fall below float resolution.
MAGNITUDE_RANGE = (1e-100, 1e100)


def check_magnitude(name: str, arr: np.ndarray, *, unit: str = "") -> np.ndarray:
    """Return ``arr`` unchanged if its largest magnitude is 0 or inside :data:`MAGNITUDE_RANGE`.

    Raise ``ValueError`` naming ``name`` and the allowed range otherwise: values whose squares
    or products overflow (``> 1e100``), or a record that is entirely below ``1e-100`` in
    magnitude (its squares and quotients underflow to 0 and divide by zero). An all-zero array
    passes here; whether it may be constant is for the caller to decide.
    """
    lo, hi = MAGNITUDE_RANGE
    peak = float(np.max(np.abs(arr))) if np.size(arr) else 0.0
    if peak > hi or 0.0 < peak < lo:
        u = f" {unit}" if unit else ""
        raise ValueError(
            f"{name} must have magnitudes in [{lo:g}, {hi:g}]{u} (largest |{name}| "
            f"is {peak:g}{u}); rescale the units"
        )
    return arr


def check_varies(name: str, arr: np.ndarray, *, unit: str = "", what: str = "") -> np.ndarray:
    """Return ``arr`` unchanged if it is not constant; ``ValueError`` naming ``name``, its
    constant value and ``what`` the caller needs of it otherwise (a constant record has no
    scale: every misfit and noise level measured against it divides by zero).
    """
    if np.size(arr) and float(np.ptp(arr)) == 0.0:
        u = f" {unit}" if unit else ""
        raise ValueError(
            f"{name} is constant ({float(arr.flat[0]):g}{u} everywhere)"
            + (f": {what}" if what else "")
        )
    return arr


def plain_number(value: Any) -> Any:
    """``value`` as a Python ``int`` or ``float`` when it is a numpy integer or floating
    scalar (what indexing an array or reading a file gives), else unchanged (``bool`` and
    ``np.bool_`` too, so that the callers' checks still refuse them). The checks that follow
    then treat ``np.float32(2e-4)`` and ``np.int64(3)`` as the numbers they are.
    """
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.floating):
        return float(value)
    return value


def plain_fields(obj) -> None:
    """Replace, in place, every field of the frozen dataclass ``obj`` that holds a numpy
    integer or floating scalar by the Python number (:func:`plain_number`); call it first in
    ``__post_init__`` so that the field checks and ``to_dict`` see plain numbers.
    """
    for f in fields(obj):
        v = getattr(obj, f.name)
        p = plain_number(v)
        if p is not v:
            object.__setattr__(obj, f.name, p)
