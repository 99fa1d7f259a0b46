"""Vibration effects (hardening, macroslip onset, whole or spread): their modal forms against
independent routes (the time-domain elements driven through steady cycles, first harmonic and
loop area by quadrature; adaptive quadrature over the patch's thresholds; the Duffing
oscillator integrated in time), energy bookkeeping, neutral values and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from iwan_element import IwanJoint, IwanParameters, dissipation
from iwan_element.effects import EFFECTS, Hardening, MacroslipOnset

P = IwanParameters(400.0, 2.5266e5, -0.5, 1.0)
K_INF = 1.4212e5
W0 = math.sqrt(K_INF + P.KT)


def cycle(el, x, n=1440):
    """Steady driven cycle of amplitude x through element el: first-harmonic stiffness
    [N/m] and loop area [J] by quadrature of the simulated force."""
    th = np.linspace(0.0, 0.5 * np.pi + 2 * np.pi, n // 4 + n + 1)
    u = x * np.sin(th)
    F = el.force_history(u)
    Fc, uc, thc = F[-(n + 1) :], u[-(n + 1) :], th[-(n + 1) :]
    return np.trapezoid(Fc * np.sin(thc), thc) / (np.pi * x), abs(np.trapezoid(Fc, uc))


def curve(make, X):
    """(f [Hz], zeta) of the unit-mass mode K_INF + element, by harmonic balance."""
    f, z = [], []
    for x in X:
        k1, D = cycle(make(), x)
        w2 = K_INF + k1
        f.append(math.sqrt(w2) / (2 * math.pi))
        z.append(D / (2 * math.pi * w2 * x * x))
    return np.array(f), np.array(z)


X = np.geomspace(0.02, 2.0, 9) * P.phi_max


@pytest.mark.parametrize("eps", [0.01, 0.05])
def test_hardening_modal_form_is_the_elements_first_harmonic(eps):
    k3 = eps * W0**2 / X.max() ** 2
    fb, zb = curve(lambda: IwanJoint(P), X)
    fe, ze = curve(lambda: Hardening(IwanJoint(P), k3=k3), X)
    fm, zm = Hardening.modal_form(X, fb, zb, 0.0, k3_per_mass=k3)
    np.testing.assert_allclose(fm, fe, rtol=1e-9)
    np.testing.assert_allclose(zm, ze, rtol=1e-7)
    assert fe[-1] > fb[-1] * (1 + 0.3 * eps)  # it hardens


def test_hardening_first_harmonic_against_duffing_time_integration():
    """Free Duffing oscillator q'' + w0^2 q + k3 q^3 = 0 integrated in time: its period at
    amplitude A against the modal form; they differ only at second order in
    eps = k3 A^2 / w0^2 (Lindstedt: (3/256) eps^2 relative in frequency)."""
    w0 = 2 * math.pi * 100.0
    A = 1e-3
    for eps in (0.005, 0.02):
        k3 = eps * w0**2 / A**2
        sol = solve_ivp(
            lambda t, y, k3=k3: [y[1], -(w0**2) * y[0] - k3 * y[0] ** 3],
            (0, 0.2),
            [A, 0.0],
            rtol=1e-11,
            atol=1e-16,
            dense_output=True,
            events=lambda t, y: y[1],
        )
        t_max = sol.t_events[0]
        t_max = t_max[np.abs(sol.sol(t_max)[0] - A) < 1e-3 * A]  # maxima only
        T = np.mean(np.diff(t_max))
        f_sim = 1.0 / T
        f_mod, _ = Hardening.modal_form(
            np.array([A]), np.array([100.0]), np.array([1e-3]), 0.0, k3_per_mass=k3
        )
        assert f_mod[0] == pytest.approx(f_sim, rel=2 * 3 / 256 * eps**2 + 1e-9)
        assert f_sim > 100.0 * (1 + 0.3 * eps)


def test_hardening_is_conservative_and_neutral_at_zero():
    u = 0.8 * P.phi_max * np.sin(np.linspace(0, 6 * np.pi, 600))
    el = Hardening(IwanJoint(P), k3=1e12)
    ref = IwanJoint(P)
    for x in u:
        el.trial(x)
        el.commit()
        ref.trial(x)
        ref.commit()
    assert el.dissipated_energy == pytest.approx(ref.dissipated_energy, rel=1e-12)
    assert el.stored_energy == pytest.approx(ref.stored_energy + 0.25e12 * u[-1] ** 4, rel=1e-9)
    np.testing.assert_array_equal(
        Hardening(IwanJoint(P), k3=0.0).force_history(u), IwanJoint(P).force_history(u)
    )


@pytest.mark.parametrize("xs_frac", [0.2, 0.6])
def test_macroslip_modal_form_is_the_elements_first_harmonic_and_loop_area(xs_frac):
    ks = 0.04 * W0**2
    us = xs_frac * X.max()
    fb, zb = curve(lambda: IwanJoint(P), X)
    fe, ze = curve(lambda: MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us), X)
    fm, zm = MacroslipOnset.modal_form(X, fb, zb, 0.0, kappa_2=ks, X_s=us)
    np.testing.assert_allclose(fm, fe, rtol=1e-6)
    np.testing.assert_allclose(zm, ze, rtol=1e-5)
    above = X > us
    assert np.all(fe[above] < fb[above]) and np.all(ze[above] > zb[above])
    np.testing.assert_allclose(fe[~above], fb[~above], rtol=1e-12)


@pytest.mark.parametrize("shape,u_e", [(0.2, None), (0.3, 8.0), (0.5, 8.0), (0.7, 8.0)])
def test_spread_patch_modal_form_converges_to_the_driven_jenkins_bank(shape, u_e):
    """The spread patch's modal form (stiffness by quadrature over its thresholds,
    dissipation in closed form) against a bank of Jenkins elements driven through steady
    cycles (first harmonic and loop area by quadrature of the simulated force): the gap is
    the bank's binning error, and it shrinks at least 5x from 32 to 128 bins. Thresholds that
    thin out (whole law), spread evenly and crowd in (bank up to ``u_e`` onsets)."""
    ks, us = 0.02 * W0**2, 0.2 * X.max()
    fb, zb = curve(lambda: IwanJoint(P), X)
    fm, zm = MacroslipOnset.modal_form(X, fb, zb, 0.0, kappa_2=ks, X_s=us, shape=shape)
    gaps = []
    for bins in (32, 128):
        fe, ze = curve(
            lambda bins=bins: MacroslipOnset(
                IwanJoint(P),
                k_2=ks,
                u_s=us,
                shape=shape,
                u_e=None if u_e is None else u_e * us,
                bins=bins,
            ),
            X,
        )
        gaps.append((np.max(np.abs(fm / fe - 1)), np.max(np.abs(zm / ze - 1))))
    assert gaps[1][0] < 5e-6 and gaps[1][1] < 2e-4, gaps
    assert gaps[1][0] < 0.2 * gaps[0][0] and gaps[1][1] < 0.2 * gaps[0][1], gaps
    above = X > us
    assert np.all(fm[above] < fb[above]) and np.all(zm[above] > zb[above])
    np.testing.assert_allclose(fm[~above], fb[~above], rtol=1e-12)


@pytest.mark.parametrize("shape", [0.02, 0.2, 0.25, 1 / 3, 0.4, 0.5, 0.8, 1.0])
def test_spread_patch_integrals_against_adaptive_quadrature(shape):
    """Lost stiffness and dissipation per cycle of the patch against scipy's adaptive
    quadrature of the Jenkins element's first harmonic and of ``4 phi (X - phi)`` over the
    threshold density ``dK/dphi = (phi / X_s)^-(q + 1) / (X_s B(2))``, ``q = 1/shape - 3``
    (written out here from the law, not from the module's functions); the log cases
    ``q = 1`` (shape 1/4) and ``q = 0`` (shape 1/3), evenly spread thresholds (shape 1/2)
    and the Hertzian end (shape 1) included, and ``K(2 X_s) = 1``."""
    from scipy.integrate import quad

    from iwan_element.effects.engine.jenkins import jenkins_gain
    from iwan_element.effects.macroslip_onset import (
        patch_cumulative,
        patch_dissipation,
        patch_stiffness_loss,
    )

    Xs = 1e-5
    q = 1.0 / shape - 3.0
    b2 = math.log(2.0) if abs(q) < 1e-12 else (1.0 - 2.0**-q) / q
    dens = lambda p: (p / Xs) ** (-q - 1.0) / (Xs * b2)  # noqa: E731
    assert float(patch_cumulative(2 * Xs, Xs, shape)) == pytest.approx(1.0, rel=1e-12)
    Xa = Xs * np.array([0.5, 1.01, 1.5, 3.0, 10.0])
    L = patch_stiffness_loss(Xa, Xs, shape)
    D = patch_dissipation(Xa, Xs, shape)
    for x, l, d in zip(Xa, L, D):
        # phi = X_s exp(t): dphi = phi dt, smooth in t even for a steep density
        top = max(math.log(x / Xs), 0.0)
        f = lambda t: dens(Xs * math.exp(t)) * Xs * math.exp(t)  # noqa: E731
        lq = quad(
            lambda t, x=x, f=f: (1.0 - jenkins_gain(x, Xs * math.exp(t))) * f(t),
            0.0,
            top,
            limit=200,
            epsabs=1e-14,
        )[0]
        dq = quad(
            lambda t, x=x, f=f: 4.0 * Xs * math.exp(t) * (x - Xs * math.exp(t)) * f(t),
            0.0,
            top,
            limit=200,
            epsabs=1e-24,
        )[0]
        assert l == pytest.approx(lq, rel=2e-5, abs=2e-5)
        assert d == pytest.approx(dq, rel=1e-9, abs=1e-24)


def test_spread_patch_tends_to_the_jenkins_patch_and_keeps_damping_growing():
    """``shape -> 0`` is the patch sliding as a whole; a spread patch's added damping
    keeps growing beyond ``2 X_s``, where the whole patch's has its peak, and with evenly
    spread thresholds (shape 1/2) it grows in proportion to the amplitude far above ``X_s``."""
    Xa = np.geomspace(0.05, 10.0, 60) * 1e-4
    f0, z0 = np.full(Xa.size, 80.0), np.full(Xa.size, 1e-3)
    kw = dict(kappa_2=0.02 * (2 * np.pi * 80.0) ** 2, X_s=1e-4)
    fj, zj = MacroslipOnset.modal_form(Xa, f0, z0, 0.0, **kw)
    fs, zs = MacroslipOnset.modal_form(Xa, f0, z0, 0.0, shape=1e-7, **kw)
    np.testing.assert_allclose(fs, fj, rtol=1e-6)
    np.testing.assert_allclose(zs, zj, rtol=1e-5)
    assert Xa[np.argmax(zj)] == pytest.approx(2e-4, rel=0.1)
    _, z2 = MacroslipOnset.modal_form(Xa, f0, z0, 0.0, shape=0.28, **kw)
    assert np.argmax(z2) > np.argmax(zj) and np.max(z2[Xa > 2e-4] - z2[np.argmax(zj)]) > 0
    Xb = np.array([1e-2, 2e-2])  # 100 and 200 X_s, small kappa: w nearly w_base
    _, z1 = MacroslipOnset.modal_form(Xb, 80.0, 1e-3, 0.0, kappa_2=1.0, X_s=1e-4, shape=0.5)
    assert (z1[1] - 1e-3) / (z1[0] - 1e-3) == pytest.approx(2.0, rel=0.03)


def test_macroslip_dissipation_and_energy_balance():
    """Loop area = Iwan dissipation (closed form) + 4 k_2 u_s (X - u_s); work = stored +
    dissipated along the history; identical to the joint below u_s."""
    ks, us, x = 2e4, 0.3 * P.phi_max, 0.9 * P.phi_max
    k1, D = cycle(MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us), x, n=2880)
    assert D == pytest.approx(float(dissipation(x, P)) + 4 * ks * us * (x - us), rel=1e-4)
    th = np.linspace(0, 0.5 * np.pi + 4 * np.pi, 3000)
    el = MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us)
    F = el.force_history(x * np.sin(th))
    W = np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(x * np.sin(th)))
    el2 = MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us)
    for ui in x * np.sin(th):
        el2.trial(ui)
        el2.commit()
    assert el2.work == pytest.approx(W, rel=1e-3)
    assert el2.dissipated_energy > 0 and el2.stored_energy == pytest.approx(
        el2.work - el2.dissipated_energy
    )
    small = 0.9 * us * np.sin(th)
    np.testing.assert_allclose(
        MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us).force_history(small),
        IwanJoint(P).force_history(small),
        rtol=1e-12,
        atol=1e-12,
    )


@pytest.mark.parametrize("shape,u_e", [(0.28, None), (0.5, 6.0)])
def test_spread_patch_bank_dissipation_and_energy_balance(shape, u_e):
    """The bank of a spread patch: loop area of a driven cycle = Iwan dissipation (closed
    form) + sum over its sliding elements of 4 k_i phi_i (X - phi_i), the elements at the
    medians of equal-stiffness bins of the law (written out here); work = stored +
    dissipated; identical to the joint below u_s; ``k_2`` between u_s and 2 u_s."""
    ks, us, x, n = 2e4, 0.2 * P.phi_max, 0.9 * P.phi_max, 16
    q = 1.0 / shape - 3.0
    b2 = (1.0 - 2.0**-q) / q
    top = 1.0 / (q * b2) if u_e is None else (1.0 - u_e**-q) / (q * b2)
    el = MacroslipOnset(
        IwanJoint(P), k_2=ks, u_s=us, shape=shape, u_e=None if u_e is None else u_e * us, bins=n
    )
    kap = (np.arange(n) + 0.5) / n * top
    phi = us * (1.0 - q * b2 * kap) ** (-1.0 / q)
    slid = phi < x
    k1, D = cycle(el, x, n=2880)
    want = float(dissipation(x, P)) + np.sum(4 * ks * top / n * phi[slid] * (x - phi[slid]))
    assert D == pytest.approx(want, rel=1e-4)
    th = np.linspace(0, 0.5 * np.pi + 4 * np.pi, 3000)
    u = x * np.sin(th)
    F = el.force_history(u)
    W = np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(u))
    for ui in u:
        el.trial(ui)
        el.commit()
    assert el.work == pytest.approx(W, rel=1e-3)
    assert el.stored_energy == pytest.approx(el.work - el.dissipated_energy)
    small = 0.9 * us * np.sin(th)
    kw = dict(k_2=ks, u_s=us, shape=shape, u_e=None if u_e is None else u_e * us)
    np.testing.assert_allclose(
        MacroslipOnset(IwanJoint(P), **kw).force_history(small),
        IwanJoint(P).force_history(small),
        rtol=1e-12,
        atol=1e-12,
    )
    fresh = MacroslipOnset(IwanJoint(P), **kw)
    assert fresh.trial(1e-3 * us)[1] == pytest.approx(IwanJoint(P).trial(1e-3 * us)[1], rel=1e-12)
    with pytest.raises(ValueError, match="u_e"):
        MacroslipOnset(IwanJoint(P), k_2=ks, u_s=us, shape=1 / 3)


def test_effects_declare_kind_units_and_bounds():
    for name in ("hardening", "macroslip_onset", "pinning_stiffness", "viscous_damping"):
        cls = EFFECTS[name]
        assert cls.kind in ("stiffness", "dissipation")
        for sp in cls.specs + cls.modal_specs:
            assert sp.unit and sp.meaning and sp.fit_bounds[0] < sp.fit_bounds[1]
    # a stiffness effect leaves the dissipation per cycle unchanged: zeta_hyst * f^2 is kept
    f, z = EFFECTS["hardening"].modal_form(
        X, np.full(X.size, 90.0), np.full(X.size, 0.01), 1e-3, k3_per_mass=1e9
    )
    np.testing.assert_allclose((z - 1e-3) * f**2, 0.009 * 90.0**2, rtol=1e-12)


def test_bad_parameters_raise_naming_them():
    with pytest.raises(ValueError, match="k3"):
        Hardening(IwanJoint(P), k3=-1.0)
    with pytest.raises(ValueError, match="k3"):
        Hardening(IwanJoint(P), k3=float("nan"))
    with pytest.raises(ValueError, match="u_s"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=0.0)
    with pytest.raises(ValueError, match="k_2"):
        MacroslipOnset(IwanJoint(P), k_2=-1e4, u_s=1e-5)
    with pytest.raises(ValueError, match="shape"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=-0.1)
    with pytest.raises(ValueError, match="shape"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=float("nan"))
    with pytest.raises(ValueError, match="u_e"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=0.3, u_e=1e-5)
    with pytest.raises(ValueError, match="u_e"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=0.3, u_e=float("inf"))
    with pytest.raises(ValueError, match="shape"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=1.5, u_e=1e-4)
    with pytest.raises(ValueError, match="bins"):
        MacroslipOnset(IwanJoint(P), k_2=1e4, u_s=1e-5, shape=0.3, bins=0)


def test_augmented_specimen_rings_down_in_exudyn_with_its_energy_balanced():
    """The Brake-Reuss specimen carrying hardening + a macroslip patch with evenly spread
    thresholds (modal form; its bank up to 8 onsets) in the
    Exudyn transient: the energy balance (beams, springs, joints, effects) closes to 1e-3,
    the patch dissipates, and the decay's frequency and damping follow the augmented QSMA
    curve (an independent route: time integration of the beam vs quasi-static analysis)."""
    from iwan_element import models

    s = models.preset("brake-reuss").replace(damping_floor=0.0, n_points=24, calibrated_range=None)
    X0 = 60e-6
    w2 = (2 * np.pi * 80.5) ** 2
    aug = s.with_effects(
        {
            "hardening": {"k3_per_mass": 0.01 * w2 / X0**2},
            "macroslip_onset": {"kappa_2": 0.01 * w2, "X_s": 20e-6, "shape": 0.5},
        }
    )
    r = models.ringdown(aug, amplitude=X0, cycles=8, steps_per_period=96, record_energy=True)
    assert r.metadata["effects"] == ("hardening", "macroslip_onset")
    assert np.max(np.abs(r.energy_error())) < 1e-3
    assert r.energy["effect_dissipated"][-1] > 0.05 * r.initial_energy
    q = models.modal_amplitude_curve(aug, amplitude=r.curve.amplitude)
    np.testing.assert_allclose(r.curve.frequency, q.frequency, rtol=3e-4)
    np.testing.assert_allclose(r.curve.damping_ratio, q.damping_ratio, rtol=0.1)
    plain = models.ringdown(s, amplitude=X0, cycles=8, steps_per_period=96)
    assert r.curve.damping_ratio[0] > 2 * plain.curve.damping_ratio[0]
