"""Seeded free decays of one nonlinear mode, for the vibration tests and benchmarks.

Two independent routes, neither of which is the extraction code under test:

* :func:`svam_decay`: the slowly-varying-amplitude model of one mode (averaging; the
  project's ``docs/equations.md``, free decay of one nonlinear mode)::

      da/dt = -zeta(a) w(a) a,      dtheta/dt = w(a) sqrt(1 - zeta(a)**2)

  integrated with ``scipy.integrate.solve_ivp`` to 1e-10, for prescribed curves ``w(a)``
  and ``zeta(a)``. The signal is ``a cos(theta)`` (displacement) and its exact first and
  second time derivatives (velocity, acceleration), so the truth at every sample is the
  prescribed ``f(a)`` and ``zeta(a)``.
* :func:`joint_decay`: the single-mode oscillator with the exact Iwan joint, integrated in
  time (:func:`iwan_element.modal_ringdown`); its truth is the modal Iwan closed form
  (:func:`iwan_element.modal_iwan_curve`, first-harmonic stiffness, dashpot floor, the
  damping a decay shows: ``damping_form="decay"``).

Both add a second, linear mode at ``ratio * f0`` and white noise of ``noise`` times the
record's largest absolute value, from an explicit ``numpy.random.Generator``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from iwan_element import IwanParameters, modal_iwan_curve, modal_ringdown

QUANTITIES = ("displacement", "velocity", "acceleration")


@dataclass(frozen=True)
class Decay:
    """A seeded record and its truth.

    ``t`` [s], ``y`` (SI units of ``quantity``), ``a0`` the initial displacement amplitude
    of the mode at the sensor [m]; ``frequency(X)`` [Hz] and ``damping(X)`` [-] the true
    curves of the mode against displacement amplitude; ``f0`` its small-amplitude
    frequency [Hz], ``band`` a pass band around it that excludes the second mode.
    """

    t: np.ndarray
    y: np.ndarray
    quantity: str
    a0: float
    f0: float
    band: tuple
    frequency: Callable
    damping: Callable
    truth: dict


def _second_mode(t, ratio, f0, level, rng):
    """A linear mode at ratio * f0 [Hz], 0.3 % damping, random phase."""
    w2 = 2 * math.pi * ratio * f0
    z2 = 0.003
    ph = rng.uniform(0, 2 * math.pi)
    return level * np.exp(-z2 * w2 * t) * np.cos(w2 * math.sqrt(1 - z2**2) * t + ph)


def _band(f0, ratio):
    """A pass band around f0 that keeps the second mode out: half-way to it, at most 25 %."""
    gap = min(abs(ratio - 1.0) / 2.0, 0.25)
    return (f0 * (1 - gap), f0 * (1 + gap))


def _finish(t, y_mode, quantity, f0, ratio, second, noise, rng):
    k = QUANTITIES.index(quantity)
    y = y_mode.copy()
    if second > 0:
        scale = (2 * math.pi * ratio * f0) ** k
        y += scale * _second_mode(
            t, ratio, f0, second * float(np.max(np.abs(y_mode))) / (2 * math.pi * f0) ** k, rng
        )
    if noise > 0:
        y += noise * float(np.max(np.abs(y))) * rng.standard_normal(t.size)
    return y


def svam_decay(
    frequency: Callable,
    damping: Callable,
    *,
    a0: float,
    duration: float,
    fs: float,
    quantity: str = "acceleration",
    ratio: float = 1.3,
    second: float = 0.3,
    noise: float = 0.01,
    rng: np.random.Generator,
    truth: dict | None = None,
) -> Decay:
    """A free decay from the slowly-varying-amplitude model of one mode.

    ``frequency(a)`` [Hz] and ``damping(a)`` [-] are vectorised callables of the
    displacement amplitude ``a`` [m]; ``second`` is the second mode's initial displacement
    amplitude relative to ``a0``.
    """
    t = np.arange(int(round(duration * fs))) / fs

    def wn(a):
        return 2 * math.pi * frequency(a)

    def rhs(_, s):
        a = math.exp(s[0])
        z = float(damping(a))
        w = float(wn(a))
        return [-z * w, w * math.sqrt(1 - z * z)]

    sol = solve_ivp(
        rhs, (0.0, t[-1]), [math.log(a0), 0.0], t_eval=t, rtol=1e-11, atol=1e-12, method="DOP853"
    )
    a = np.exp(sol.y[0])
    th = sol.y[1]
    z = np.asarray(damping(a), dtype=float)
    w = np.asarray(wn(a), dtype=float)
    wd = w * np.sqrt(1 - z * z)
    g = z * w * a  # -da/dt
    h = 1e-6 * a
    dg = (damping(a + h) * wn(a + h) * (a + h) - damping(a - h) * wn(a - h) * (a - h)) / (2 * h)
    dwd = (
        wn(a + h) * np.sqrt(1 - damping(a + h) ** 2) - wn(a - h) * np.sqrt(1 - damping(a - h) ** 2)
    ) / (2 * h)
    da = -g
    dda = -dg * da
    dth, ddth = wd, dwd * da
    c, s = np.cos(th), np.sin(th)
    sig = {
        "displacement": a * c,
        "velocity": da * c - a * dth * s,
        "acceleration": dda * c - 2 * da * dth * s - a * ddth * s - a * dth**2 * c,
    }
    f0 = float(frequency(1e-3 * a0))
    y = _finish(t, sig[quantity], quantity, f0, ratio, second, noise, rng)
    return Decay(
        t, y, quantity, float(a0), f0, _band(f0, ratio), frequency, damping, dict(truth or {})
    )


def modal_curves(f0: float, zeta0: float, dzeta: float, df: float, x_ref: float, chi: float = -0.5):
    """Microslip-like truth curves: ``f = f0 (1 - df (a/x_ref)**(chi+1))``,
    ``zeta = zeta0 + dzeta (a/x_ref)**(chi+1)``."""
    n = chi + 1.0

    def frequency(a):
        return f0 * (1.0 - df * (np.asarray(a, dtype=float) / x_ref) ** n)

    def damping(a):
        return zeta0 + dzeta * (np.asarray(a, dtype=float) / x_ref) ** n

    return frequency, damping


def joint_decay(
    params: IwanParameters,
    *,
    K_inf: float,
    zeta0: float,
    q0: float,
    duration: float,
    fs: float,
    quantity: str = "acceleration",
    ratio: float = 1.3,
    second: float = 0.3,
    noise: float = 0.01,
    rng: np.random.Generator,
) -> Decay:
    """A free decay of the unit-mass modal oscillator with the exact Iwan joint.

    Released from rest at ``q0`` [m]; the truth is :func:`modal_iwan_curve` with the
    first-harmonic stiffness, the dashpot floor and ``damping_form="decay"`` (what a ring-down
    measures to first order in the damping).
    """
    t = np.arange(int(round(duration * fs))) / fs
    rd = modal_ringdown(t, params, K_inf=K_inf, q0=q0, zeta0=zeta0)
    q, v, acc = rd.displacement, rd.velocity, rd.acceleration
    sig = {"displacement": q, "velocity": v, "acceleration": acc}[quantity]

    def curve(a):
        f, z = modal_iwan_curve(
            np.atleast_1d(np.asarray(a, dtype=float)),
            params,
            K_inf=K_inf,
            zeta0=zeta0,
            stiffness="harmonic",
            floor="dashpot",
            damping_form="decay",
        )
        return np.asarray(f), np.asarray(z)

    f0 = math.sqrt(K_inf + params.KT) / (2 * math.pi)
    y = _finish(t, sig, quantity, f0, ratio, second, noise, rng)
    truth = {
        "Fs": params.Fs,
        "KT": params.KT,
        "chi": params.chi,
        "beta": params.beta,
        "K_inf": K_inf,
        "zeta0": zeta0,
    }
    return Decay(
        t,
        y,
        quantity,
        abs(float(q0)),
        f0,
        _band(f0, ratio),
        lambda a: curve(a)[0],
        lambda a: curve(a)[1],
        truth,
    )


def svam_case(
    zeta: float,
    *,
    quantity: str = "acceleration",
    ratio: float = 1.3,
    second: float = 0.3,
    noise: float = 0.01,
    rng: np.random.Generator,
    f0: float = 20.0,
    fs: float = 800.0,
    a0: float = 1e-4,
    end: float = 0.02,
) -> Decay:
    """A :func:`svam_decay` whose damping is about ``zeta`` at the start.

    Microslip-like truth (:func:`modal_curves`, chi = -0.5): ``zeta(a) = zeta (0.5 + 0.5
    sqrt(a / a0))`` and a frequency 0.5 % lower at ``a0`` than at small amplitude. The record
    lasts until the slowest decay (damping ``zeta / 2``) has reached ``end * a0``.
    """
    frequency, damping = modal_curves(f0, 0.5 * zeta, 0.5 * zeta, 0.005, a0)
    duration = math.log(1.0 / end) / (0.5 * zeta * 2 * math.pi * f0)
    return svam_decay(
        frequency,
        damping,
        a0=a0,
        duration=duration,
        fs=fs,
        quantity=quantity,
        ratio=ratio,
        second=second,
        noise=noise,
        rng=rng,
        truth={"zeta": zeta, "source": "svam"},
    )


def joint_case(
    zeta: float,
    *,
    quantity: str = "acceleration",
    ratio: float = 1.3,
    second: float = 0.3,
    noise: float = 0.01,
    rng: np.random.Generator,
    f0: float = 20.0,
    fs: float = 800.0,
    end: float = 0.02,
) -> Decay:
    """A :func:`joint_decay` whose damping is about ``zeta`` at the release.

    Unit-mass modal Iwan joint (chi = -0.5, beta = 0.5, KT = 0.5 w0**2, phi_max = 1 mm): the
    joint supplies two thirds of ``zeta`` at the release (at most what it gives at 0.9
    phi_max, about 3 %) and a dashpot floor ``zeta0`` the rest; the release amplitude is where
    the closed-form damping is ``zeta``. The record lasts until the dashpot alone would have
    brought the release amplitude down to ``end`` times it.
    """
    from scipy.optimize import brentq

    chi, beta, phimax = -0.5, 0.5, 1e-3
    w02 = (2 * math.pi * f0) ** 2
    KT = 0.5 * w02
    c = beta + (chi + 1) / (chi + 2)
    p = IwanParameters(KT * c * phimax / (1 + beta), KT, chi, beta)
    k_inf = w02 - KT

    def joint_zeta(q, z0):
        return float(
            modal_iwan_curve(
                np.array([q]), p, K_inf=k_inf, zeta0=z0, stiffness="harmonic", floor="dashpot"
            )[1][0]
        )

    zeta0 = max(zeta / 3.0, zeta - joint_zeta(0.9 * phimax, 0.0))
    q0 = math.exp(
        brentq(
            lambda lq: joint_zeta(math.exp(lq), zeta0) - zeta,
            math.log(1e-9 * phimax),
            math.log(0.9 * phimax),
            xtol=1e-10,
        )
    )
    duration = math.log(1.0 / end) / (zeta0 * 2 * math.pi * f0)
    return joint_decay(
        p,
        K_inf=k_inf,
        zeta0=zeta0,
        q0=q0,
        duration=duration,
        fs=fs,
        quantity=quantity,
        ratio=ratio,
        second=second,
        noise=noise,
        rng=rng,
    )
