"""The measurement of a vibration diagnosis (:mod:`.diagnosis`) and its noise: the arrays from
an :class:`~iwan_element.AmplitudeCurve` or three arrays, their checks (positive, equal
lengths, Hz and ratios rather than rad/s and percent) and the noise of each log-residual
curve (stated, given, or the curve's own scatter along amplitude).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import chi2 as _chi2

from ...base.validation import check_magnitude, check_scalar, finite_array, same_length
from ...identify.files.units import check_damping_ratio, check_frequency_ratio
from ...identify.loops.noise import difference_sigma
from ...identify.modal.curves import AmplitudeCurve


def _check_units(fm, fp, zm, zp):
    """Clear errors for rad/s given as Hz and percent given as a ratio."""
    check_frequency_ratio("frequency", fm, "predicted_frequency", fp)
    check_damping_ratio("damping_ratio", zm)
    check_damping_ratio("predicted_damping_ratio", zp)


#: Efficiency of the second differences' MAD scale against the standard deviation: its
#: sampling spread is that of a chi-square with about this fraction of the differences'
#: count as degrees of freedom.
MAD_EFFICIENCY = 0.37


def _noise(r, stated, n, name):
    """Noise of one log-residual curve [-] and its source text: the stated uncertainty when
    there is one, unless the curve's own scatter (second differences along amplitude) lies
    above the stated value's 99 % range (then the scatter: the curve is noisier than stated);
    the scatter when none is stated. (Taking the larger of the two whenever the scatter
    happens to exceed the stated value would bias the noise upwards: with 12 points the
    scatter's own spread is a factor 1.9, and a noise set too high makes every effect's
    evidence too small).
    """
    scatter = difference_sigma(r) if n >= 5 else 0.0  # second differences along amplitude
    if stated is None:
        return max(scatter, 1e-12), f"{name}: scatter"
    st = float(np.median(stated))
    dof = max(MAD_EFFICIENCY * (n - 2), 1.0)
    if scatter > st * math.sqrt(float(_chi2.ppf(0.99, dof)) / dof):
        return scatter, f"{name}: scatter (above the stated uncertainty's 99 % range)"
    return max(st, 1e-12), f"{name}: stated"


#: Largest relative standard uncertainty or noise [-] accepted per curve: a frequency known
#: to 50 % or a damping ratio to 100 % carries no amplitude dependence; larger values are
#: percent given for a ratio (5.0 for 5 %).
_RELATIVE_MAX = {"frequency": 0.5, "damping_ratio": 1.0}


def _curve_level(name, r, given, stated, n):
    """Noise of one curve: ``given`` if set, else the stated uncertainty unless the scatter is
    clearly above it (:func:`_noise`).
    """
    if given is not None:
        return _relative(
            f"{name}_noise", name, check_scalar(f"{name}_noise", given, low=0.0, low_open=True)
        ), f"{name}: given"
    return _noise(r, _stated(f"{name}_uncertainty", stated, n), n, name)


def _relative(arg, curve, a):
    """``a`` (a relative standard deviation [-] of ``curve``), or a ValueError naming ``arg``
    when it exceeds :data:`_RELATIVE_MAX` (most likely percent).
    """
    top = _RELATIVE_MAX[curve]
    peak = float(np.max(a))
    if peak > top:
        raise ValueError(
            f"{arg} must be a relative standard uncertainty in (0, {top:g}] [-], "
            f"got {peak:g} ({100 * peak:g} %); a ratio, not percent: give "
            f"{peak / 100:g} for {peak:g} %"
        )
    return a


def _stated(name, value, n):
    if value is None:
        return None
    a = np.broadcast_to(finite_array(name, value, ndim=None), (n,)).astype(float)
    if np.any(a <= 0):
        raise ValueError(f"{name} must be > 0 (relative standard uncertainty [-])")
    return a


def _inputs(amplitude, frequency, damping_ratio, predicted_frequency, predicted_damping_ratio):
    arrs = {}
    for nm, a in (
        ("amplitude", amplitude),
        ("frequency", frequency),
        ("damping_ratio", damping_ratio),
        ("predicted_frequency", predicted_frequency),
        ("predicted_damping_ratio", predicted_damping_ratio),
    ):
        arrs[nm] = check_magnitude(nm, finite_array(nm, a, ndim=1, min_size=3))
    n = same_length(**arrs)
    for nm, a in arrs.items():
        if np.any(a <= 0):
            raise ValueError(f"{nm} must be > 0 everywhere")
    _check_units(
        arrs["frequency"],
        arrs["predicted_frequency"],
        arrs["damping_ratio"],
        arrs["predicted_damping_ratio"],
    )
    return n, arrs


def _measurement(amplitude, frequency, damping_ratio, f_unc, z_unc):
    """Arrays and stated relative uncertainties from an AmplitudeCurve or three arrays."""
    if not isinstance(amplitude, AmplitudeCurve):
        if frequency is None or damping_ratio is None:
            raise ValueError(
                "frequency and damping_ratio are required unless amplitude is an AmplitudeCurve"
            )
        return amplitude, frequency, damping_ratio, f_unc, z_unc
    c = amplitude
    if frequency is not None or damping_ratio is not None:
        raise ValueError(
            "give either an AmplitudeCurve or three arrays, not both: frequency and "
            "damping_ratio must be None when amplitude is an AmplitudeCurve"
        )

    def rel(std, val):
        r = np.asarray(std, float) / val
        return r if np.all(np.isfinite(r)) and np.all(r > 0) else None

    f_unc = rel(c.frequency_std, c.frequency) if f_unc is None else f_unc
    z_unc = rel(c.damping_ratio_std, c.damping_ratio) if z_unc is None else z_unc
    return c.amplitude, c.frequency, c.damping_ratio, f_unc, z_unc
