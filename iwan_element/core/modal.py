"""Single-mode modal Iwan model: amplitude-dependent frequency and damping, and its ring-down.

One mass-normalised mode with an Iwan joint and a linear viscous floor (Segalman 2005,
J. Appl. Mech. 72:752-760; docs/equations.md section 7)::

    m q'' + c q' + K_inf q + F_J(q) = 0,     c = 2 zeta0 m w0,   w0**2 = (K_inf + KT) / m

with ``F_J`` the four-parameter Iwan force (Fs, KT, chi, beta) in modal units. At modal
displacement amplitude ``Q`` (docs/equations.md section 7)::

    w(Q)**2 = (K_inf + K(Q)) / m
    zeta(Q) = zeta_v(Q) + D(Q) / (2 pi m w(Q)**2 Q**2)

``D`` is the exact dissipation per cycle (docs/equations.md section 2). Two choices are offered:

* ``stiffness="secant"`` (docs/equations.md section 7, QSMA): ``K(Q) = F(Q)/Q``, the secant of the
  backbone (paper eq. 24).
* ``stiffness="harmonic"``: ``K(Q)`` is the in-phase first-harmonic coefficient of the
  Masing loop of amplitude ``Q`` divided by ``Q`` (the describing function). This is the
  stiffness that a ring-down or a stepped-sine test measures to first order in the damping
  (averaging method); it lies below the secant (by 1.9 % of the secant's stiffness drop in
  microslip at chi = -0.5, about 0.07 % in frequency at Q = 0.1 phi_max for the modal test
  vector of docs/equations.md section 5).
* ``floor="constant"`` (docs/equations.md section 7): ``zeta_v = zeta0`` at every amplitude;
  ``floor="dashpot"``: a fixed dashpot ``c = 2 zeta0 m w0`` gives ``zeta_v = zeta0 w0 / w(Q)``.

:func:`modal_ringdown` integrates the oscillator in time with the exact :class:`IwanJoint`
(an independent route to the same curves).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_magnitude, check_scalar, finite_array
from .closed_form import backbone, dissipation, secant_stiffness, tangent_stiffness
from .joint import IwanJoint
from .modal_ringdown import ModalRingdown
from .parameters import IwanParameters

__all__ = ["harmonic_stiffness", "modal_iwan_curve", "modal_ringdown", "viscous_floor"]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)


def _check(params):
    if not isinstance(params, IwanParameters):
        raise ValueError(f"params must be an IwanParameters instance, got {type(params).__name__}")
    return params


def harmonic_stiffness(amplitude, params: IwanParameters) -> float | NDArray[np.float64]:
    """First-harmonic (describing-function) stiffness of the Iwan joint [N/m].

    For ``u = Q cos(theta)`` the steady Masing loop has the descending branch
    ``F = F_bb(Q) - 2 F_bb((Q - u)/2)`` (docs/equations.md section 2); the in-phase coefficient is
    ``a1 = (2/pi) int_0^pi F cos(theta) dtheta`` and the stiffness is ``a1 / Q``. The integral
    has a closed form in microslip (``Q <= phi_max``),
    ``KT - R Q**(chi+1) 4 n Gamma(n + 1/2) / (sqrt(pi) Gamma(n + 2) (chi+1)(chi+2))`` with
    ``n = chi + 2``, and beyond it is done by Gauss-Legendre quadrature split at the angle
    where the branch reaches macroslip (accurate to about 1e-10 relative).

    Parameters
    ----------
    amplitude : float or array_like
        Displacement amplitude [m], ``>= 0``.
    params : IwanParameters

    Returns
    -------
    float or ndarray
        Stiffness [N/m]; ``KT`` at ``Q = 0``.
    """
    p = _check(params)
    x = check_magnitude("amplitude", finite_array("amplitude", amplitude, ndim=None), unit="m")
    if np.any(x < 0):
        raise ValueError("amplitude (the modal displacement amplitude Q) must be >= 0 [m]")
    q = np.atleast_1d(x).ravel()
    out = np.full(q.shape, p.KT)
    micro = (q > 0) & (q <= p.phi_max)
    n = p.chi + 2.0
    gam = 4.0 * n * math.exp(math.lgamma(n + 0.5) - math.lgamma(n + 2.0)) / math.sqrt(math.pi)
    out[micro] = p.KT - p.R * q[micro] ** (p.chi + 1.0) * gam / ((p.chi + 1.0) * (p.chi + 2.0))
    macro = q > p.phi_max
    if np.any(macro):
        out[macro] = _harmonic_quadrature(q[macro], p)
    shaped = out.reshape(np.shape(x))
    return float(shaped) if np.ndim(amplitude) == 0 else shaped


def _harmonic_quadrature(q, p):
    """In-phase first-harmonic stiffness by Gauss-Legendre quadrature split at the kink."""
    qq = q[:, None]
    # kink of the branch where (Q - u)/2 = phi_max, i.e. cos(theta_k) = 1 - 2 phi_max / Q
    th_k = np.arccos(np.clip(1.0 - 2.0 * p.phi_max / qq, -1.0, 1.0))
    total = np.zeros_like(qq)
    for lo, hi in ((np.zeros_like(th_k), th_k), (th_k, np.full_like(th_k, math.pi))):
        half = 0.5 * (hi - lo)
        th = lo + half * (_GL_X[None, :] + 1.0)
        u = qq * np.cos(th)
        F = backbone(qq, p) - 2.0 * backbone(0.5 * (qq - u), p)
        total += half * np.sum(_GL_W[None, :] * F * np.cos(th), axis=1, keepdims=True)
    return (2.0 / math.pi) * total[:, 0] / q


def viscous_floor(zeta0, w0_sq, w_sq, k_e, floor: str) -> float | NDArray[np.float64]:
    """The viscous part of a mode's damping ratio (the package's one copy of the rule;
    ``docs/equations.md`` section 7).

    ``floor="constant"``: ``zeta0`` itself. ``floor="dashpot"``: a fixed dashpot
    ``c = 2 zeta0 w0`` (per unit modal mass) dissipates ``pi c w X**2`` per cycle, which as a
    ratio of the energy measure ``k_e X**2`` (``k_e = w**2`` for the energy form, the
    tangent for a free decay's form; per unit mass) is ``zeta0 w0 w / k_e``.

    Parameters
    ----------
    zeta0 : float
        Viscous damping ratio at the linear frequency.
    w0_sq, w_sq, k_e : float or ndarray
        Squared linear and amplitude-dependent angular frequency [rad^2/s^2] and the energy
        measure [rad^2/s^2] (stiffnesses per unit modal mass).
    floor : {"constant", "dashpot"}
    """
    if floor == "constant":
        return zeta0 + 0.0 * np.asarray(w_sq)
    return zeta0 * np.sqrt(w0_sq * np.asarray(w_sq)) / k_e


def modal_iwan_curve(
    amplitude,
    params: IwanParameters,
    *,
    K_inf: float,
    zeta0: float = 0.0,
    mass: float = 1.0,
    stiffness: str = "secant",
    floor: str = "constant",
    damping_form: str = "energy",
) -> tuple[float | NDArray[np.float64], float | NDArray[np.float64]]:
    """Natural frequency and damping ratio of a single-mode modal Iwan model.

    ``w(Q)**2 = (K_inf + K(Q)) / mass`` and
    ``zeta(Q) = zeta_v + D(Q) / (2 pi mass w(Q)**2 Q**2)`` (Segalman 2005; docs/equations.md
    section 7, test vector in section 5).

    Parameters
    ----------
    amplitude : float or array_like
        Modal displacement amplitude [m] (or any consistent modal unit), ``> 0``.
    params : IwanParameters
        Iwan joint in the same modal units (Fs [N], KT [N/m]).
    K_inf : float, keyword-only
        Linear stiffness in parallel with the joint [N/m], ``>= 0``; ``w0**2 = (K_inf+KT)/mass``.
    zeta0 : float, keyword-only
        Linear viscous damping floor [-], ``0 <= zeta0 < 1``.
    mass : float, keyword-only
        Modal mass [kg], ``> 0`` (1 for a mass-normalised mode).
    stiffness : {"secant", "harmonic"}, keyword-only
        ``"secant"`` (docs/equations.md section 7, QSMA) or ``"harmonic"`` (first-harmonic
        stiffness, what a ring-down or stepped-sine test measures; see :func:`harmonic_stiffness`).
    floor : {"constant", "dashpot"}, keyword-only
        ``"constant"``: the floor adds ``zeta0`` at every amplitude (docs/equations.md section 7);
        ``"dashpot"``: a fixed dashpot ``c = 2 zeta0 mass w0`` adds ``zeta0 w0 / w(Q)``.
    damping_form : {"energy", "decay"}, keyword-only
        ``"energy"`` (default; QSMA, steady forced response): ``zeta = D / (2 pi m w**2
        Q**2)``. ``"decay"``: the damping ratio a free decay shows, its amplitude's decay rate
        over ``w``. The energy at a turning point is what the dissipation ``D`` drains once per
        cycle, and it grows with the amplitude as ``dE/dQ = (K_inf + K_t(Q)) Q`` with the
        joint's tangent ``K_t`` (the sliders still stuck), not ``m w**2 Q``, so
        ``zeta = D / (2 pi (K_inf + K_t) Q**2)`` (and a dashpot adds
        ``zeta0 m w0 w / (K_inf + K_t)``) (docs/equations.md section 8). A ring-down of the
        exact oscillator follows it to 0.4 % where the energy form is 4-8 % low
        (0.05-0.2 phi_max, K_inf = 0.6 KT).

    Returns
    -------
    frequency : ndarray or float
        Undamped natural frequency ``w(Q) / (2 pi)`` [Hz].
    damping_ratio : ndarray or float
        Equivalent viscous damping ratio [-].
    """
    p = _check(params)
    x = check_magnitude("amplitude", finite_array("amplitude", amplitude, ndim=None), unit="m")
    if np.any(x <= 0):
        raise ValueError("amplitude (the modal displacement amplitude Q) must be > 0 [m]")
    K_inf = check_scalar("K_inf", K_inf, low=0.0)
    zeta0 = check_scalar("zeta0", zeta0, low=0.0, high=1.0, high_open=True)
    mass = check_scalar("mass", mass, low=0.0, low_open=True)
    if stiffness == "secant":
        k = secant_stiffness(x, p)
    elif stiffness == "harmonic":
        k = harmonic_stiffness(x, p)
    else:
        raise ValueError(f"stiffness must be 'secant' or 'harmonic', got {stiffness!r}")
    if floor not in ("constant", "dashpot"):
        raise ValueError(f"floor must be 'constant' or 'dashpot', got {floor!r}")
    if damping_form not in ("energy", "decay"):
        raise ValueError(f"damping_form must be 'energy' or 'decay', got {damping_form!r}")
    w2 = (K_inf + np.asarray(k)) / mass
    w0 = math.sqrt((K_inf + p.KT) / mass)
    # the stiffness that relates the energy to the amplitude: m w^2, or dE/dQ / Q for a decay
    k_e = mass * w2 if damping_form == "energy" else K_inf + np.asarray(tangent_stiffness(x, p))
    zv = viscous_floor(zeta0, w0 * w0, w2, k_e / mass, floor)
    zeta = zv + np.asarray(dissipation(x, p)) / (2.0 * math.pi * k_e * x * x)
    f = np.sqrt(w2) / (2.0 * math.pi)
    if np.ndim(amplitude) == 0:
        return float(f), float(zeta)
    return f, zeta


#: Most time steps modal_ringdown integrates (about a minute of the exact joint).
_MAX_RINGDOWN_STEPS = 2e7


def modal_ringdown(
    t,
    params: IwanParameters,
    *,
    K_inf: float,
    q0: float,
    v0: float = 0.0,
    zeta0: float = 0.0,
    mass: float = 1.0,
    max_phase_step: float = 0.01,
) -> ModalRingdown:
    """Free decay of the single-mode modal Iwan oscillator, with the exact :class:`IwanJoint`.

    Integrates ``mass q'' + c q' + K_inf q + F_J(q) = 0`` (``c = 2 zeta0 mass w0``, the
    ``floor="dashpot"`` convention of :func:`modal_iwan_curve`) by central differences with
    the dashpot velocity centred, committing the joint once per step. Sub-steps are taken so
    that ``w0 h <= max_phase_step``: the method's relative frequency error is
    ``(w0 h)**2 / 24`` (4e-6 at the default).

    Parameters
    ----------
    t : array_like
        Uniformly spaced output times [s], strictly increasing, starting at the release.
    params : IwanParameters
    K_inf, zeta0, mass : float, keyword-only
        As in :func:`modal_iwan_curve`.
    q0, v0 : float, keyword-only
        Initial displacement [m] and velocity [m/s]; the joint starts virgin.
    max_phase_step : float, keyword-only
        Largest ``w0 h`` [rad], in ``(0, 0.2]``.

    Returns
    -------
    ModalRingdown
        ``t``, ``displacement`` [m], ``velocity`` [m/s] and ``acceleration`` [m/s^2] at
        ``t``, with the run's settings (``report()``, ``to_dataframe()``, ``plot()``).
    """
    p = _check(params)
    tt = check_magnitude("t", finite_array("t", t, min_size=2), unit="s")
    dt = np.diff(tt)
    if np.any(dt <= 0) or np.ptp(dt) > 1e-6 * dt.mean():
        raise ValueError("t must be uniformly spaced and strictly increasing")
    K_inf = check_scalar("K_inf", K_inf, low=0.0)
    q0 = check_scalar("q0", q0)
    v0 = check_scalar("v0", v0)
    zeta0 = check_scalar("zeta0", zeta0, low=0.0, high=1.0, high_open=True)
    mass = check_scalar("mass", mass, low=0.0, low_open=True)
    dphi = check_scalar("max_phase_step", max_phase_step, low=0.0, high=0.2, low_open=True)
    w0 = math.sqrt((K_inf + p.KT) / mass)
    steps = w0 * (tt[-1] - tt[0]) / dphi
    if steps > _MAX_RINGDOWN_STEPS:
        raise ValueError(
            f"t spans {tt[-1] - tt[0]:g} s = {steps:.3g} integration steps of "
            f"max_phase_step/w0 (w0 = sqrt((K_inf + KT)/mass)) = {dphi / w0:.3g} s; at most "
            f"{_MAX_RINGDOWN_STEPS:.0e} are allowed (check the unit of t)"
        )
    n_sub = max(1, math.ceil(w0 * dt.mean() / dphi))
    h = dt.mean() / n_sub
    c = 2.0 * zeta0 * mass * w0
    joint = IwanJoint(p)
    trial, commit = joint.trial, joint.commit
    n = tt.size
    q_out = np.empty(n)
    v_out = np.empty(n)
    a_out = np.empty(n)
    F, _ = trial(q0)
    commit()
    a_now = -(c * v0 + K_inf * q0 + F) / mass
    q_prev = q0 - h * v0 + 0.5 * h * h * a_now
    q = q0
    cp = 1.0 + 0.5 * c * h / mass
    cm = 1.0 - 0.5 * c * h / mass
    hh = h * h / mass
    q_out[0], v_out[0], a_out[0] = q0, v0, a_now
    for i in range(1, n):
        for _ in range(n_sub):
            q_next = (2.0 * q - cm * q_prev - hh * (K_inf * q + F)) / cp
            F, _ = trial(q_next)
            commit()
            q_prev, q = q, q_next
        # velocity from the last step's difference, corrected to second order with the
        # acceleration at the end point
        v = (q - q_prev) / h
        a = -(c * v + K_inf * q + F) / mass
        v = v + 0.5 * h * a
        a = -(c * v + K_inf * q + F) / mass
        q_out[i], v_out[i], a_out[i] = q, v, a
    return ModalRingdown(
        t=tt.copy(),
        displacement=q_out,
        velocity=v_out,
        acceleration=a_out,
        joint=p,
        K_inf=K_inf,
        zeta0=zeta0,
        mass=mass,
        q0=q0,
        v0=v0,
    )
