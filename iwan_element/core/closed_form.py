"""Closed forms of the four-parameter Iwan model, vectorised over numpy arrays.

All functions take displacements in metres and return forces in newtons, stiffnesses in N/m
and energies in joules. Equation numbers refer to the seed paper (Li, Cai, Ruan, Cai) and to
Segalman (2005), J. Appl. Mech. 72, 752-760. The paper's eq. (15) prints ``(s0 - s)/2``;
the form consistent with its eq. (14) is ``(s0 + s)/2`` and is used here.
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_scalar, finite_array
from .parameters import CHI_MAX, IwanParameters

__all__ = [
    "backbone",
    "tangent_stiffness",
    "secant_stiffness",
    "force_amplitude",
    "dissipation",
    "dissipation_slope",
    "masing_loop",
    "backbone_work",
    "normalized_backbone",
    "masing_descending",
    "masing_ascending",
]


def _as_array(name, u):
    arr = finite_array(name, u, ndim=None)
    return arr


def _check_params(params) -> IwanParameters:
    if not isinstance(params, IwanParameters):
        raise ValueError(f"params must be an IwanParameters instance, got {type(params).__name__}")
    return params


def _ratio(a, p: IwanParameters):
    """``min(a/phi_max, 1)``: every power in the closed forms is a power of this ratio, never
    of ``phi_max`` (whose unit power overflows for large ``chi``; see ``IwanParameters.R``).
    """
    with np.errstate(over="ignore"):
        return np.minimum(a / p.phi_max, 1.0)


def _finite(name, value, what):
    """Raise ``ValueError`` naming ``name`` if an energy overflowed (input far beyond macroslip)."""
    if not np.all(np.isfinite(value)):
        raise ValueError(
            f"{name} is too large: the {what} overflows the float range "
            f"(|{name}| must be below about 1e300 m / Fs)"
        )
    return value


def _out(x, like):
    """Return a float for scalar input, an array otherwise."""
    return float(x) if np.ndim(like) == 0 else x


def backbone(u, params: IwanParameters) -> float | NDArray[np.float64]:
    """Virgin-loading (backbone) force ``F(u)`` [N] (Segalman 2005 eq. 17; paper eqs. 12, 18).

    ``F(u) = KT u - R |u|**(chi+2) sign(u) / ((chi+1)(chi+2))`` for ``|u| < phi_max`` and
    ``Fs sign(u)`` beyond (macroslip).

    Parameters
    ----------
    u : float or array_like
        Joint displacement [m], any shape.
    params : IwanParameters

    Returns
    -------
    float or ndarray
        Force [N], same shape as ``u``.
    """
    p = _check_params(params)
    x = _as_array("u", u)
    a = np.abs(x)
    r = _ratio(a, p)
    # R |u|**(chi+2)/((chi+1)(chi+2)) = KT |u| r**(chi+1)/((1+beta)(chi+2)): no power of phi_max
    micro = p.phi_max * r * (p.KT - p.K_slider * r ** (p.chi + 1.0) / (p.chi + 2.0))
    f = np.where(a < p.phi_max, micro, p.Fs) * np.sign(x)
    return _out(f, u)


def tangent_stiffness(u, params: IwanParameters) -> float | NDArray[np.float64]:
    """Tangent stiffness of the virgin curve ``dF/du`` [N/m] (derivative of eq. 17).

    ``KT - R |u|**(chi+1)/(chi+1)`` for ``|u| < phi_max`` (it tends to ``S`` as
    ``|u| -> phi_max``) and 0 in macroslip.
    """
    p = _check_params(params)
    x = _as_array("u", u)
    a = np.abs(x)
    r = _ratio(a, p)
    k = np.where(a < p.phi_max, p.KT - p.K_slider * r ** (p.chi + 1.0), 0.0)
    return _out(k, u)


def force_amplitude(amplitude, params: IwanParameters) -> float | NDArray[np.float64]:
    """Force amplitude ``F0`` [N] of a steady cycle of displacement amplitude ``u0`` [m]
    (paper eqs. 18-20): the backbone at ``u0``.
    """
    x = _as_array("amplitude", amplitude)
    if np.any(x < 0):
        raise ValueError("amplitude (the displacement amplitude u0) must be >= 0 [m]")
    return backbone(amplitude, params)


def secant_stiffness(amplitude, params: IwanParameters) -> float | NDArray[np.float64]:
    """Secant stiffness ``F0/u0`` [N/m] of a cycle of amplitude ``u0`` (paper eq. 24).

    ``K_sec = KT [1 - r**(chi+1) / ((chi+2)(1+beta))]`` with ``r = u0/phi_max <= 1``;
    ``Fs/u0`` in macroslip; ``KT`` at ``u0 = 0``.
    """
    p = _check_params(params)
    x = _as_array("amplitude", amplitude)
    if np.any(x < 0):
        raise ValueError("amplitude (the displacement amplitude u0) must be >= 0 [m]")
    r = np.minimum(x / p.phi_max, 1.0)
    micro = p.KT * (1.0 - r ** (p.chi + 1.0) / ((p.chi + 2.0) * (1.0 + p.beta)))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # used above phi_max only
        macro = p.Fs / x
    k = np.where(x <= p.phi_max, micro, macro)
    return _out(k, amplitude)


def slip_energy(y, p: IwanParameters):
    """``I_H(y) = int_0^y int_0^q phi rho(phi) dphi dq`` [J].

    The dissipation per cycle is ``4 I_H(u0)``. ``I_H`` is
    ``R y**(chi+3)/((chi+2)(chi+3))`` below ``phi_max``, growing by ``Fs`` per metre beyond.
    """
    r = _ratio(y, p)
    e = (
        p.KT
        * p.phi_max
        * p.phi_max
        * (p.chi + 1.0)
        / ((1.0 + p.beta) * (p.chi + 2.0) * (p.chi + 3.0))
    )
    return e * r ** (p.chi + 3.0) + p.Fs * np.maximum(y - p.phi_max, 0.0)


def dissipation(amplitude, params: IwanParameters) -> float | NDArray[np.float64]:
    """Energy dissipated per steady cycle of displacement amplitude ``u0`` [J].

    Microslip, ``u0 <= phi_max`` (paper eq. 17, Segalman 2005 eq. 20)::

        D = 4 R u0**(chi+3) / ((chi+2)(chi+3))

    Macroslip, ``u0 > phi_max``::

        D = 4 R [u0 phi_max**(chi+2)/(chi+2) - phi_max**(chi+3)/(chi+3)]
            + 4 S phi_max (u0 - phi_max)

    Parameters
    ----------
    amplitude : float or array_like
        Displacement amplitude [m], ``>= 0``.
    params : IwanParameters
    """
    p = _check_params(params)
    x = _as_array("amplitude", amplitude)
    if np.any(x < 0):
        raise ValueError("amplitude (the displacement amplitude u0) must be >= 0 [m]")
    return _finite("amplitude", _out(4.0 * slip_energy(x, p), amplitude), "dissipation")


def dissipation_slope(amplitude, params: IwanParameters) -> float | NDArray[np.float64]:
    """Local slope ``d ln D / d ln F0`` of dissipation vs force amplitude (paper eq. 21).

    Tends to ``chi + 3`` only as ``F0 -> 0`` (paper eq. 22); ``inf`` in macroslip, where
    ``F0 = Fs`` is constant.
    """
    p = _check_params(params)
    x = _as_array("amplitude", amplitude)
    if np.any(x <= 0):
        raise ValueError(
            "amplitude (the displacement amplitude u0) must be > 0 for a log slope [m]"
        )
    g = np.minimum(x / p.phi_max, 1.0) ** (p.chi + 1.0)
    with np.errstate(divide="ignore"):
        slope = (p.chi + 3.0) * ((p.beta + 1.0) - g / (p.chi + 2.0)) / (p.beta + 1.0 - g)
    slope = np.where(x < p.phi_max, slope, np.inf)
    return _out(slope, amplitude)


def backbone_work(u, params: IwanParameters) -> float | NDArray[np.float64]:
    """Work along the virgin curve ``G(u) = int_0^|u| F(x) dx`` [J] (even in ``u``).

    Used for energy bookkeeping of Masing branches: along a branch leaving the reversal
    ``(u_r, F_r)`` the work from ``u_a`` to ``u_b`` is
    ``F_r (u_b - u_a) + 4 [G((u_b - u_r)/2) - G((u_a - u_r)/2)]``.
    """
    p = _check_params(params)
    x = np.abs(_as_array("u", u))
    r = _ratio(x, p)
    e = p.K_slider * p.phi_max * p.phi_max / ((p.chi + 2.0) * (p.chi + 3.0))
    g = 0.5 * p.KT * p.phi_max * p.phi_max * r * r - e * r ** (p.chi + 3.0)
    g = g + p.Fs * np.maximum(x - p.phi_max, 0.0)
    return _finite("u", _out(g, u), "backbone work")


def masing_loop(
    amplitude: float, params: IwanParameters, *, n: int = 401
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One closed steady-state hysteresis loop of amplitude ``u0`` (paper eqs. 13-15).

    The loop starts at ``(u0, F0)``, follows the descending branch
    ``F = F0 - 2 F_bb((u0 - u)/2)`` to ``-u0`` and the ascending branch
    ``F = -F0 + 2 F_bb((u0 + u)/2)`` back to ``u0``.

    Parameters
    ----------
    amplitude : float
        Displacement amplitude [m], ``> 0``.
    params : IwanParameters
    n : int, keyword-only
        Points per branch, ``>= 3``.

    Returns
    -------
    u, F : ndarray, shape (2n - 1,)
        Displacement [m] and force [N] around the loop, first point equal to the last.
    """
    p = _check_params(params)
    amplitude = check_scalar("amplitude", amplitude, low=0.0, low_open=True)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 3 <= n <= 10_000_000:
        raise ValueError(f"n must be an integer in [3, 1e7], got {n!r}")
    F0 = backbone(amplitude, p)
    down = np.linspace(amplitude, -amplitude, n)
    up = np.linspace(-amplitude, amplitude, n)[1:]
    F_down = F0 - 2.0 * backbone((amplitude - down) / 2.0, p)
    F_up = -F0 + 2.0 * backbone((amplitude + up) / 2.0, p)
    return np.concatenate([down, up]), np.concatenate([F_down, F_up])


# ---------------------------------------------------------------- dimensionless (paper eqs. 12-15)
def _dimensionless_check(chi, beta):
    chi = check_scalar("chi", chi, low=-1.0, low_open=True, high=CHI_MAX)
    beta = check_scalar("beta", beta, low=-1e300 / (abs(chi) + 2.0), high=1e300 / (abs(chi) + 2.0))
    den = beta * chi + 2.0 * beta + chi + 1.0
    if den == 0.0:
        raise ValueError(f"(chi, beta) = ({chi}, {beta}) make the denominator of eq. 12 zero")
    if beta < 0.0:
        warnings.warn(
            f"beta = {beta} < 0 is non-physical (negative spike stiffness); the curve is "
            "drawn as a dimensionless shape only",
            UserWarning,
            stacklevel=3,
        )
    return chi, beta, den


def _f(s, chi, beta, den):
    a = np.minimum(np.abs(s), 1.0)
    return np.sign(s) * a * (beta * chi + 2.0 * beta + chi + 2.0 - a ** (chi + 1.0)) / den


def normalized_backbone(s, chi: float, beta: float) -> float | NDArray[np.float64]:
    """Dimensionless backbone ``f(s) = F(s phi_max)/Fs`` (paper eq. 12).

    ::

        f(s) = s (beta chi + 2 beta + chi + 2 - s**(chi+1)) / (beta chi + 2 beta + chi + 1)

    for ``|s| <= 1`` (odd in ``s``) and ``sign(s)`` beyond. Any ``chi > -1`` and finite
    ``beta`` are accepted so that the paper's Fig. 3 can be drawn; ``beta < 0`` warns.
    """
    chi, beta, den = _dimensionless_check(chi, beta)
    s_arr = _as_array("s", s)
    return _out(_f(s_arr, chi, beta, den), s)


def masing_descending(s, s0: float, chi: float, beta: float) -> float | NDArray[np.float64]:
    """Descending (unloading) branch from the reversal ``(s0, f(s0))`` (paper eq. 13).

    ::

        f_u(s) = f(s0) - 2 f((s0 - s)/2)
    """
    chi, beta, den = _dimensionless_check(chi, beta)
    s0 = check_scalar("s0", s0)
    s_arr = _as_array("s", s)
    return _out(_f(s0, chi, beta, den) - 2.0 * _f((s0 - s_arr) / 2.0, chi, beta, den), s)


def masing_ascending(s, s0: float, chi: float, beta: float) -> float | NDArray[np.float64]:
    """Ascending (reloading) branch from the reversal ``(-s0, -f(s0))`` (paper eq. 15).

    Corrected::

        f_d(s) = -f(s0) + 2 f((s0 + s)/2)

    The paper prints ``(s0 - s)/2``; its own eq. 14, ``f_d(s) = -f_u(-s)``, gives this form.
    """
    chi, beta, den = _dimensionless_check(chi, beta)
    s0 = check_scalar("s0", s0)
    s_arr = _as_array("s", s)
    return _out(-_f(s0, chi, beta, den) + 2.0 * _f((s0 + s_arr) / 2.0, chi, beta, den), s)
