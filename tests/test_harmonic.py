"""Harmonic balance, continuation and nonlinear modes against independent routes.

* the periodic kernel against the package's history kernel run for three periods, and its
  exact Jacobian against finite differences;
* the stuck limit against the closed-form linear receptance (one mass) and the full model's
  modes (the beam);
* a single-degree-of-freedom oscillator with one Iwan joint, time-stepped to a true steady
  state with the exact :class:`IwanJoint` (Newmark, outside the code under test);
* EPMC against QSMA on the Brake-Reuss beam; continuation through a Duffing fold against the
  classical first-harmonic frequency-amplitude relation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from iwan_element import IwanJoint, IwanParameters
from iwan_element.core.masing import constants_from_arrays, masing_rows
from iwan_element.core.periodic import periodic_harmonic_jacobian, periodic_rows
from iwan_element.effects import EFFECTS
from iwan_element.harmonic import ModalSystem, harmonic_balance, trace
from iwan_element.harmonic.basis import Harmonics, check_harmonics
from iwan_element.harmonic.system import ElementPort

JOINT = IwanParameters(Fs=10.0, KT=1e5, chi=-0.5, beta=0.2)


def _basis(hs=(0, 1, 2, 3, 5), N=64):
    return Harmonics(*check_harmonics(hs, N))


@pytest.mark.parametrize("seed", range(4))
def test_periodic_kernel_is_the_steady_loop_of_the_history_kernel(seed):
    rng = np.random.default_rng(seed)
    b = _basis()
    C = constants_from_arrays(np.full(6, 100.0), np.full(6, 1e6), -0.5, 0.2)
    U = (rng.normal(size=(6, b.n_coefficients)) * 5e-5) @ b.E.T
    F, K, A, D = periodic_rows(C, U)
    F3, K3, W3, D3 = masing_rows(C, np.tile(U, 3))  # from the virgin state, 3 periods
    N = U.shape[1]
    np.testing.assert_allclose(F, F3[:, 2 * N :], rtol=0, atol=1e-12 * np.abs(F).max())
    np.testing.assert_allclose(D, D3[:, 3 * N - 1] - D3[:, 2 * N - 1], rtol=1e-10, atol=1e-18)
    # the loop's area is its dissipation: closed trapezoid of F du over the period
    loop = 0.5 * np.sum((F + np.roll(F, -1, axis=1)) * (np.roll(U, -1, axis=1) - U), axis=1)
    np.testing.assert_allclose(loop, D, rtol=0.05)


@pytest.mark.parametrize("seed", range(3))
def test_periodic_jacobian_matches_finite_differences(seed):
    rng = np.random.default_rng(10 + seed)
    b = _basis()
    C = constants_from_arrays(np.full(4, 50.0), np.full(4, 1e6), -0.3, 0.5)
    cu = rng.normal(size=(4, b.n_coefficients)) * 4e-5
    _, K, A, _ = periodic_rows(C, cu @ b.E.T)
    J = periodic_harmonic_jacobian(K, A, b.P, b.E, shift=np.full(4, 1e6))
    eps = 1e-10
    Jfd = np.zeros_like(J)
    for c in range(b.n_coefficients):
        d = np.zeros_like(cu)
        d[:, c] = eps
        Fp = periodic_rows(C, (cu + d) @ b.E.T)[0] - 1e6 * ((cu + d) @ b.E.T)
        Fm = periodic_rows(C, (cu - d) @ b.E.T)[0] - 1e6 * ((cu - d) @ b.E.T)
        Jfd[:, :, c] = ((Fp - Fm) / (2 * eps)) @ b.P.T
    np.testing.assert_allclose(J, Jfd, rtol=0, atol=1e-6 * np.abs(J).max())


def test_stuck_oscillator_is_the_linear_receptance():
    m, k, c = 2.0, 3e4, 4.0
    stuck = IwanParameters(Fs=1e12, KT=2e4, chi=1.0, beta=0.1)  # microslip ~ (u/phi_max)^2
    sysm = ModalSystem.oscillator(m, k, c, stuck)
    f = np.linspace(10, 40, 13)
    r = harmonic_balance(sysm, frequency=f, force=3.0)
    w = 2 * np.pi * f
    H = 1.0 / (k + stuck.KT - m * w * w + 1j * c * w)
    np.testing.assert_allclose(r.amplitude, 3.0 * np.abs(H), rtol=1e-9)
    np.testing.assert_allclose(r.phase, np.angle(H), atol=1e-9)
    assert r.success and np.all(np.abs(r.energy_error) < 1e-8)


def _newmark_steady(m, k, c, joint, F, f, *, periods, spp=256):
    """Average-acceleration Newmark with the exact IwanJoint; returns the fundamental's
    complex amplitude over the last 10 periods."""
    el = IwanJoint(joint)
    W = 2 * np.pi * f
    h = 1.0 / (f * spp)
    x = v = 0.0
    Fj, _ = el.trial(0.0)
    a = (F - c * v - k * x - Fj) / m
    n = periods * spp
    xs = np.empty(n + 1)
    xs[0] = x
    for i in range(1, n + 1):
        t = i * h
        xn = x
        for _ in range(30):
            an = 4 / h**2 * (xn - x - h * v) - a
            vn = v + 0.5 * h * (a + an)
            Fj, Kj = el.trial(xn)
            r = m * an + c * vn + k * xn + Fj - F * math.cos(W * t)
            dx = -r / (4 * m / h**2 + 2 * c / h + k + Kj)
            xn += dx
            if abs(dx) <= 1e-13 * max(abs(xn), 1e-12):
                break
        an = 4 / h**2 * (xn - x - h * v) - a
        v = v + 0.5 * h * (a + an)
        x, a = xn, an
        el.trial(x)
        el.commit()
        xs[i] = x
    tail = xs[-10 * spp :]
    tt = np.arange(n + 1)[-10 * spp :] * h
    return 2 * np.mean(tail * np.cos(W * tt)) - 2j * np.mean(tail * np.sin(W * tt))


@pytest.mark.parametrize("ratio", [0.9, 0.985, 1.05])
def test_oscillator_matches_a_time_integration_to_steady_state(ratio):
    m, k, c, F = 1.0, 1e5, 20.0, 4.0  # zeta 2.2 %: settles in tens of periods
    sysm = ModalSystem.oscillator(m, k, c, JOINT)
    f = ratio * sysm.omega[0] / (2 * np.pi)
    r = harmonic_balance(sysm, frequency=[f], force=F, harmonics=(1, 3, 5, 7, 9))
    Z = _newmark_steady(m, k, c, JOINT, F, f, periods=120)
    assert r.converged[0]
    assert r.amplitude[0] == pytest.approx(abs(Z), rel=5e-3)
    assert r.phase[0] == pytest.approx(np.angle(Z), abs=1e-2)


def test_energy_error_shrinks_with_the_harmonics():
    sysm = ModalSystem.oscillator(1.0, 1e5, 2.0, JOINT)
    f = 0.95 * sysm.omega[0] / (2 * np.pi)
    errs = [
        abs(harmonic_balance(sysm, frequency=[f], force=8.0, harmonics=hs).energy_error[0])
        for hs in ((1,), (1, 3, 5), (1, 3, 5, 7, 9, 11))
    ]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3


def test_continuation_traces_a_duffing_fold():
    """Continuation through the two turning points of a hardening oscillator (the package's
    hardening effect as an element port); with the fundamental alone every traced point
    satisfies the classical relation F^2 = a^2 ((w0^2 + 3/4 k3 a^2 - W^2)^2 + (c W)^2)."""
    from iwan_element.models.modal import ZeroElement

    k3, c, F = 1e10, 5.0, 1.0
    stuck = IwanParameters(Fs=1e9, KT=1e3, chi=1.0, beta=0.5)
    base = ModalSystem.oscillator(1.0, 1e4, c, stuck)
    sysd = base.with_ports([ElementPort(EFFECTS["hardening"](ZeroElement(), k3=k3), 1.0)], [[1.0]])
    f0 = base.omega[0] / (2 * np.pi)
    r = trace(sysd, force=F, band=(0.8 * f0, 2.0 * f0), harmonics=(1,))
    assert r.metadata["turning_points"] == 2
    W, a = 2 * np.pi * r.frequency, r.amplitude
    lhs = a * a * ((base.omega[0] ** 2 + 0.75 * k3 * a * a - W * W) ** 2 + (c * W) ** 2)
    np.testing.assert_allclose(np.sqrt(lhs), F, rtol=1e-7)
    assert np.any(np.diff(r.frequency) < 0)  # the traced curve runs back past the fold


@pytest.mark.parametrize(
    "bad, match",
    [
        (dict(frequency=[-1.0, 2.0]), "frequency"),
        (dict(force=[1.0, 2.0, 3.0]), "force"),
        (dict(force=0.0), "force"),
        (dict(harmonics=(3, 5)), "harmonics"),
        (dict(harmonics=0), "harmonics"),
        (dict(samples=4), "samples"),
        (dict(frequency=[np.nan]), "frequency"),
    ],
)
def test_bad_input_is_refused_naming_the_argument(bad, match):
    sysm = ModalSystem.oscillator(1.0, 1e5, 2.0, JOINT)
    kw = dict(frequency=[50.0, 51.0], force=1.0)
    kw.update(bad)
    with pytest.raises(ValueError, match=match):
        harmonic_balance(sysm, **kw)
    with pytest.raises(ValueError, match="system"):
        harmonic_balance("beam", frequency=[50.0], force=1.0)
    with pytest.raises(ValueError, match="band"):
        trace(sysm, force=1.0, band=(50.0, 50.0))


def test_specimen_response_warns_outside_its_calibrated_range():
    """``models.harmonic_balance`` says when its answer leaves the range the specimen was
    calibrated on (the Brake-Reuss preset: 2-60 um), as QSMA and the nonlinear modes do;
    inside the range it stays silent."""
    from iwan_element import models

    spec = models.preset("brake-reuss")
    lo, hi = spec.calibrated_range
    r = models.harmonic_balance(spec, frequency=[79.0, 80.0], force=[0.05, 1.5])
    assert r.converged.all() and r.amplitude[0] < hi < r.amplitude[1]
    assert any("calibrated on" in w and "extrapolated" in w for w in r.warnings), r.warnings
    quiet = models.harmonic_balance(spec, frequency=[79.0], force=[0.05])
    assert lo < quiet.amplitude[0] < hi and quiet.warnings == ()
