"""The vibration effects in the joint (``InterfaceEffect``): one law at the contact points that
every route runs, mapped and fitted from an effect's modal form (docs/vibration_effects.md,
"Effects in the joint")."""

from __future__ import annotations

import math

import numpy as np
import pytest
from iwan_element.models import InterfaceEffect, resolve_interface_effects

from iwan_element import models

W1 = 2 * math.pi * 80.6  # Brake-Reuss mode 1 [rad/s]
RANGE = (2e-6, 6e-5)  # the hammer calibration's amplitudes [m]
MODAL = {
    "hardening": {"k3_per_mass": 4e-3 * W1**2 / RANGE[1] ** 2},
    "viscous_damping": {"zeta_v": 3e-4},
    "pinning_stiffness": {"k_p_per_mass": 4e-3 * W1**2, "delta": 1e-5},
    "macroslip_onset": {"kappa_2": 3e-3 * W1**2, "X_s": 1.5e-5, "shape": 0.45},
}


@pytest.fixture(scope="module")
def brb():
    return models.preset("brake-reuss")


@pytest.mark.parametrize("name", sorted(MODAL))
def test_physical_form_reproduces_the_modal_form_on_its_mode_by_qsma(brb, name):
    """Each effect fitted on mode 1 as a modal form, then given to the joint: the physical
    interface's QSMA (a law at every contact point, acting through the static solve and the
    points' own energy per cycle) against the modal form's curve at amplitudes between the
    fit's. Stated tolerance: frequency within 5 % of the effect's own frequency change (or
    5 ppm), damping within 4 % (the fit weighs 1e-4 in frequency like 3 % in damping)."""
    v = MODAL[name]
    modal = brb.with_effects({name: v}, calibrated_range=RANGE)
    phys = resolve_interface_effects(
        brb.with_effects({name: v}, calibrated_range=RANGE, form="physical")
    )
    e = phys.interface_effects[0]
    assert e.resolved and e.fitted_on.parameters == pytest.approx(v)
    X = np.geomspace(RANGE[0] * 1.1, RANGE[1] * 0.97, 17)
    c0 = models.modal_amplitude_curve(brb, amplitude=X)
    cm = models.modal_amplitude_curve(modal, amplitude=X)
    cp = models.modal_amplitude_curve(phys, amplitude=X)
    foot = float(np.max(np.abs(cm.frequency / c0.frequency - 1)))
    assert np.max(np.abs(cp.frequency / cm.frequency - 1)) <= max(0.05 * foot, 5e-6)
    assert np.max(np.abs(cp.damping_ratio / cm.damping_ratio - 1)) <= 0.04
    assert max(e.fit_misfit) <= 0.04
    # the physical form is not the modal one by another name: it acts on the other modes
    q2 = models.modal_amplitude_curve(phys, mode=2, amplitude=[2e-5])
    q2_0 = models.modal_amplitude_curve(brb, mode=2, amplitude=[2e-5])
    assert (q2.frequency[0], q2.damping_ratio[0]) != (q2_0.frequency[0], q2_0.damping_ratio[0])


def test_interface_effect_is_validated_and_shared_by_its_rule(brb):
    """Joint-level values are checked against the effect's own bounds; the shares sum to one
    (``KT``-weighted at every contact point, two points at each bolt for the pin)."""
    with pytest.raises(ValueError, match="k_p must be"):
        InterfaceEffect("pinning_stiffness", values={"k_p": -1.0})
    with pytest.raises(ValueError, match="where must be"):
        InterfaceEffect("hardening", values={"k3": 1.0}, where="edges")
    with pytest.raises(ValueError, match="give values"):
        InterfaceEffect("hardening")
    pin = InterfaceEffect("pinning_stiffness", values={"k_p": 3e6, "delta": 1e-7})
    assert pin.where == "bolts"
    w = models.modal.point_weights(brb, pin)
    assert w.sum() == pytest.approx(1.0) and np.count_nonzero(w) == 2 * len(brb.bolt_positions)
    wc = models.modal.point_weights(brb, InterfaceEffect("hardening", values={"k3": 1.0}))
    pts = models.reduced.contact_points(brb)
    np.testing.assert_allclose(wc, pts.KT / pts.KT.sum())


def _every_effect(spec):
    """The four effects in the joint at joint-level values of the size the mode-1 fits give
    (pin 78 MN/m over the bolts after 68 nm, a spread patch of 50 MN/m from 127 nm, a cubic
    spring, a dashpot)."""
    return spec.replace(
        interface_effects=(
            InterfaceEffect("pinning_stiffness", values={"k_p": 7.8e7, "delta": 6.8e-8}),
            InterfaceEffect("macroslip_onset", values={"k_2": 5e7, "u_s": 1.27e-7, "shape": 0.45}),
            InterfaceEffect("hardening", values={"k3": 1.7e20}),
            InterfaceEffect("viscous_damping", values={"c": 1.7e4}),
        )
    )


def test_every_effect_in_the_joint_keeps_the_multi_mode_ring_down_energy_balance():
    """Modes 1 and 2 released together from 60 and 3 um through the interface carrying all
    four effects (each point's stack around its IwanJoint): kinetic + strain + springs +
    joint stored + joint (with the effects') and floor dissipation stay the release energy
    to 1e-3, the rest being the integrator's quadrature of the point forces; the effects
    add to the joint's dissipation."""
    s = models.preset("brake-reuss").replace(n_points=24, modal_damping=(1.3e-3, 9.6e-4))
    kw = {"amplitude": {1: 60e-6, 2: 3e-6}, "duration": 0.16, "steps_per_period": 32}
    r = models.ringdown(_every_effect(s), record_energy=True, **kw)
    assert r.max_energy_error < 1e-3
    assert r.energy_error()[-1] == pytest.approx(r.metadata["joint_quadrature_error"], abs=1e-6)
    assert r.energy["joint_dissipated"][-1] > 0.15 * r.initial_energy  # plain joint: 0.105


def test_nonlinear_modes_with_a_pin_and_a_dashpot_in_the_joint_are_the_eigenproblem(brb):
    """EPMC on the reduced model (each point's effects beside its joint, compiled) against
    the complex eigenvalues of the full linear system with the springs and dashpots added at
    the points (``K0 + G^T diag(KT + k_i) G``, ``C_floor + G^T diag(c_i) G``), at an
    amplitude where the Iwan joints are stuck: modes 1 and 2."""
    from iwan_element.models.modal import interface_laws
    from iwan_element.models.reduced import contact_points, floor_damping, linear_system

    p = brb.replace(
        interface_effects=(
            InterfaceEffect("pinning_stiffness", values={"k_p": 3e7, "delta": 0.0}),
            InterfaceEffect("viscous_damping", values={"c": 2e4}),
        )
    )
    L, pts = linear_system(p), contact_points(p)
    k, c = pts.KT.copy(), np.zeros(len(pts))
    for i, stack in enumerate(interface_laws(p).stacks):
        for _, v in stack:
            k[i] += v.get("k_p", 0.0)
            c[i] += v.get("c", 0.0)
    K = L.K0 + L.G.T @ (k[:, None] * L.G)
    C = floor_damping(p).C + L.G.T @ (c[:, None] * L.G)
    n = K.shape[0]
    Mi = np.linalg.inv(L.M)
    lam = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]]))
    lam = lam[lam.imag > 2 * math.pi]  # the elastic modes, one of each conjugate pair
    lam = lam[np.argsort(np.abs(lam))]
    for mode in (1, 2):
        nm = models.nonlinear_mode(p, amplitude=[1e-12], mode=mode)
        plain = models.nonlinear_mode(brb, amplitude=[1e-12], mode=mode)
        lm = lam[mode - 1]
        assert nm.frequency[0] == pytest.approx(abs(lm) / (2 * math.pi), rel=1e-6)
        assert nm.damping_ratio[0] == pytest.approx(-lm.real / abs(lm), rel=1e-3)
        assert nm.damping_ratio[0] > 1.05 * plain.damping_ratio[0]  # the dashpots act


def test_augment_round_trip_recovers_a_pin_in_the_joint_and_predicts_mode_2(brb):
    """A curve generated by the beam whose joint carries a pin (50 MN/m over the bolts after
    a 0.3 um clearance), 5-275 um with 1e-5 / 1 % noise, diagnosed against the plain beam's
    QSMA; ``augment`` puts what it names into the joint: the pin comes back within 3 % in
    stiffness and clearance, mode 1's curve within 20 ppm and 0.5 %, and mode 2, which the
    diagnosis never saw, as the truth's (the modal form would leave it untouched)."""
    from iwan_element import AmplitudeCurve, diagnose_vibration

    spec = brb.replace(calibrated_range=None)
    pin = InterfaceEffect("pinning_stiffness", values={"k_p": 5e7, "delta": 3e-7})
    truth = spec.replace(interface_effects=(pin,))
    Xm = np.geomspace(5e-6, 2.75e-4, 30)
    pred = models.modal_amplitude_curve(spec, amplitude=Xm)
    meas = models.modal_amplitude_curve(truth, amplitude=Xm)
    rng = np.random.default_rng(3)
    fm = meas.frequency * np.exp(1e-5 * rng.normal(size=Xm.size))
    zm = meas.damping_ratio * np.exp(0.01 * rng.normal(size=Xm.size))
    g = diagnose_vibration(
        AmplitudeCurve(Xm, fm, zm, frequency_std=1e-5 * fm, damping_ratio_std=0.01 * zm),
        predicted_frequency=pred.frequency,
        predicted_damping_ratio=pred.damping_ratio,
        predicted_zeta0=spec.interface.damping_floor,
    )
    assert "pinning_stiffness" in g.effects, g.report()
    aug = g.augment(brb)
    assert aug.effects == () and not any(e.resolved for e in aug.interface_effects)
    got = resolve_interface_effects(aug)
    back = {e.name: e for e in got.interface_effects}["pinning_stiffness"].parameters
    assert back["k_p"] == pytest.approx(5e7, rel=0.03)
    assert back["delta"] == pytest.approx(3e-7, rel=0.03)
    q = models.modal_amplitude_curve(got, amplitude=Xm)
    assert np.max(np.abs(q.frequency / meas.frequency - 1)) < 2e-5
    assert np.max(np.abs(q.damping_ratio / meas.damping_ratio - 1)) < 5e-3
    X2 = [1e-5, 4e-5]
    q2 = models.modal_amplitude_curve(got, mode=2, amplitude=X2)
    t2 = models.modal_amplitude_curve(truth, mode=2, amplitude=X2)
    p2 = models.modal_amplitude_curve(spec, mode=2, amplitude=X2)
    assert np.max(np.abs(t2.frequency / p2.frequency - 1)) > 1e-6  # the pin acts in mode 2
    np.testing.assert_allclose(q2.frequency, t2.frequency, rtol=1e-6)
    np.testing.assert_allclose(q2.damping_ratio, t2.damping_ratio, rtol=1e-3)
    modal = g.augment(brb, form="modal")
    assert modal.interface_effects == () and modal.effects


def test_nonlinear_mode_with_a_sliding_patch_and_a_cubic_spring_is_the_ring_down():
    """The nonlinear laws in the frequency domain against the time domain: EPMC (each
    point's macroslip bank as Masing rows and its cubic spring, compiled beside its joint)
    against the Exudyn ring-down of the same interface (each point's stack stepped around its
    IwanJoint) from 50 um at the tip, read at amplitudes inside the decay. Measured (40
    cycles, 64 steps a period): frequency within 4e-6, damping within 0.6 %, where the patch
    lowers the frequency by up to 350 ppm and raises the damping by up to 40 %."""
    s = models.preset("brake-reuss").replace(n_points=24)
    p = s.replace(
        interface_effects=(
            InterfaceEffect("macroslip_onset", values={"k_2": 5e7, "u_s": 1.27e-7, "shape": 0.45}),
            InterfaceEffect("hardening", values={"k3": 1.7e20}),
        )
    )
    c = models.ringdown(p, amplitude=5e-5, cycles=24, steps_per_period=48).curve
    X = np.geomspace(c.amplitude.min() * 1.1, c.amplitude.max() * 0.9, 4)
    order = np.argsort(c.amplitude)
    f_r = np.interp(np.log(X), np.log(c.amplitude[order]), c.frequency[order])
    z_r = np.interp(np.log(X), np.log(c.amplitude[order]), c.damping_ratio[order])
    e = models.nonlinear_mode(p, amplitude=X)
    plain = models.nonlinear_mode(s, amplitude=X)
    assert np.all(e.damping_ratio > 1.15 * plain.damping_ratio)  # the patch slides
    np.testing.assert_allclose(e.frequency, f_r, rtol=2e-5)
    np.testing.assert_allclose(e.damping_ratio, z_r, rtol=0.02)


def test_the_joint_forms_exact_jacobian_is_the_finite_difference_one(brb):
    """Harmonic balance's residual with every effect in the joint (the points' forms batched
    beside their joints): its exact Jacobian (the Masing rows' reversal columns, the laws'
    displacement and velocity derivatives) against central differences, at a state where
    the patches slide and the pins bear."""
    from iwan_element.models.modal import specimen_system

    from iwan_element.harmonic.balance import residual
    from iwan_element.harmonic.basis import Harmonics

    s = specimen_system(_every_effect(brb))
    assert s.form_batch is not None
    basis = Harmonics((1, 3, 5), 64)
    W = 2 * math.pi * 80.4
    rng = np.random.default_rng(1)
    nj = len(s.joints)
    cz = np.zeros((s.n_z, basis.n_coefficients))
    r1 = models.reduced_model(brb).mode_index(1)
    a = s.modes[:nj, r1]
    cz[:nj, 0] = a * 4e-7 / np.abs(a).max()  # mode 1's slips, up to 0.4 um: beyond the onsets
    cz[:nj, 1:] = 2e-9 * rng.normal(size=(nj, basis.n_coefficients - 1))
    _, J, _, _ = residual(s, basis, W, 1.0, cz)
    h = 1e-12
    cols = rng.choice(cz.size, 12, replace=False)
    for col in cols:
        d = np.zeros(cz.size)
        d[col] = h
        Rp = residual(s, basis, W, 1.0, cz + d.reshape(cz.shape), jacobian=False)[0].ravel()
        Rm = residual(s, basis, W, 1.0, cz - d.reshape(cz.shape), jacobian=False)[0].ravel()
        fd = (Rp - Rm) / (2 * h)
        assert np.max(np.abs(J[:, col] - fd)) <= 1e-4 * max(np.max(np.abs(fd)), 1.0)
