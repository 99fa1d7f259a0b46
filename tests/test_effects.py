"""The effect library: exact reduction to the Iwan joint, each force law against its own
closed form or an independent route, energy bookkeeping, stacking and bad input."""

import math

import numpy as np
import pytest
from _jenkins_bank import directional_bank

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters, backbone, dissipation
from iwan_element.effects import (
    EFFECTS,
    AsymmetricSlip,
    Backlash,
    BreakAway,
    PinningStiffness,
    SlipDegradation,
    ViscousDamping,
    base_joint,
    make_effect,
)

P = IwanParameters(1000.0, 1e6, -0.5, 0.2)
A = P.phi_max
ZERO = {
    "viscous_damping": {"c": 0.0},
    "pinning_stiffness": {"k_p": 0.0, "delta": 0.0},
    "backlash": {"gap": 0.0},
    "slip_degradation": {"rate": 0.0},
    "asymmetric_slip": {"asymmetry": 0.0},
    "breakaway": {"ratio": 1.0},
}


def history(n_cycles=4, amps=(0.3, 1.5, 0.05, 0.8), per_cycle=80):
    t = np.linspace(0, n_cycles, n_cycles * per_cycle + 1)
    amp = np.repeat(np.array(amps) * A, per_cycle)
    amp = np.append(amp, amp[-1])
    return t, amp * np.sin(2 * np.pi * t)


def run(el, u, v=None):
    v = np.zeros_like(u) if v is None else v
    F = np.empty_like(u)
    W, D = np.empty_like(u), np.empty_like(u)
    for i, (a, b) in enumerate(zip(u, v)):
        F[i] = el.trial(a, b)[0]
        el.commit()
        W[i], D[i] = el.work, el.dissipated_energy
    return F, W, D


def test_names_are_the_fixed_ones():
    assert set(EFFECTS) == {
        "viscous_damping",
        "pinning_stiffness",
        "backlash",
        "slip_degradation",
        "asymmetric_slip",
        "breakaway",
        "hardening",
        "macroslip_onset",
    }
    for cls in EFFECTS.values():  # every parameter declares its physics
        assert cls.specs and all(sp.unit and sp.meaning for sp in cls.specs)
        assert cls.__doc__ and cls.__module__.endswith(cls.effect)


@pytest.mark.parametrize("name", sorted(ZERO))
def test_zero_extra_parameters_reduce_exactly_to_iwan(name):
    _, u = history()
    el = make_effect(name, IwanJoint(P), **ZERO[name])
    F, W, D = run(el, u)
    ref = IwanJoint(P)
    F_ref, W_ref, D_ref = run(ref, u)
    np.testing.assert_allclose(F, F_ref, rtol=0, atol=1e-12 * P.Fs)
    np.testing.assert_allclose(D, D_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(W, W_ref, rtol=1e-12, atol=1e-15)


def test_viscous_damping_force_and_energy():
    t, u = history()
    v = np.gradient(u, t)
    c = 50.0
    el = ViscousDamping(IwanJoint(P), c=c)
    F, W, D = run(el, u, v)
    np.testing.assert_allclose(F, IwanJoint(P).force_history(u) + c * v, rtol=1e-13, atol=1e-9)
    assert np.all(np.diff(D) >= 0)
    # dashpot part of the dissipation: trapezoid of c v du
    D_iwan = run(IwanJoint(P), u)[2][-1]
    visc = np.sum(c * 0.5 * (v[1:] + v[:-1]) * np.diff(u)) + c * 0.5 * v[0] * u[0]
    assert D[-1] == pytest.approx(D_iwan + visc, rel=1e-12)
    assert el.trial(0.0, 2.0)[0] - el.trial(0.0, 0.0)[0] == pytest.approx(2 * c)


@pytest.mark.parametrize("delta", [0.0, 0.5 * A])
def test_pinning_stiffness_virgin_curve_and_tangent(delta):
    k_p = 2e5
    el = PinningStiffness(IwanJoint(P), k_p=k_p, delta=delta)
    u = np.linspace(0, 3 * A, 301)
    F = el.force_history(u)
    expected = backbone(u, P) + k_p * np.maximum(u - delta, 0.0)
    np.testing.assert_allclose(F, expected, rtol=1e-12, atol=1e-9)
    el.trial(2 * A)
    el.commit()
    assert el.trial(2.5 * A)[1] == pytest.approx(k_p)  # macroslip: only the pin
    assert el.stored_energy >= 0.5 * k_p * (2 * A - delta) ** 2 * (1 - 1e-12)


@pytest.mark.parametrize("r", [0.3, 2.0])
def test_backlash_loop_area_and_zero_force_plateau(r):
    g = 0.2 * A
    u0 = r * A + g
    u = u0 * np.cos(np.linspace(0, 4 * np.pi, 4001))
    el = Backlash(IwanJoint(P), gap=g)
    F, W, D = run(el, u)
    half = 2000
    # the joint itself sees amplitude u0 - g: loop area = dissipation(u0 - g)
    assert W[-1] - W[half] == pytest.approx(dissipation(u0 - g, P), rel=1e-9)
    assert D[-1] - D[half] == pytest.approx(dissipation(u0 - g, P), rel=1e-9)
    # independent route: trapezoid area of the sampled loop
    assert np.trapezoid(F[half:], u[half:]) == pytest.approx(dissipation(u0 - g, P), rel=2e-4)
    # a zero-force plateau of width about 2 g on each pass
    zero = np.abs(F[half:]) < 1e-9 * P.Fs
    du = np.abs(np.diff(u[half:]))
    width = np.sum(du[zero[1:] & zero[:-1]]) / 2
    assert width == pytest.approx(2 * g, rel=0.02)
    assert np.all(np.diff(D) >= -1e-12 * P.Fs * A)


def test_backlash_virgin_gap_then_contact():
    g = 0.1 * A
    el = Backlash(IwanJoint(P), gap=g)
    assert el.trial(0.5 * g)[0] == 0.0
    assert el.trial(g + 0.3 * A)[0] == pytest.approx(backbone(0.3 * A, P), rel=1e-12)
    assert el.trial(-g - 0.3 * A)[0] == pytest.approx(-backbone(0.3 * A, P), rel=1e-12)


def test_slider_effects_match_an_independent_slider_bank():
    """On a DiscreteIwan (the bank is then exact), each slider-level effect equals a
    plain-Python bank of Jenkins sliders with the effect's thresholds."""
    base = DiscreteIwan(P, 12)
    k, phi = base.slider_stiffness, base.slider_slip
    _, u = history(amps=(0.4, 1.6, 0.2, 0.9), per_cycle=60)
    a = 0.35
    F = AsymmetricSlip(DiscreteIwan(P, 12), asymmetry=a).force_history(u)
    np.testing.assert_allclose(
        F, directional_bank(u, k, (1 + a) * phi, (1 - a) * phi), rtol=0, atol=1e-9 * P.Fs
    )
    r = 1.6
    F = BreakAway(DiscreteIwan(P, 12), ratio=r).force_history(u)
    np.testing.assert_allclose(
        F,
        directional_bank(u, k, r * phi, r * phi, kin_up=phi, kin_dn=phi),
        rtol=0,
        atol=1e-9 * P.Fs,
    )


def test_slip_degradation_lowers_capacity_keeps_stiffness():
    rate = 2.0 / dissipation(A, P)  # lambda = exp(-2) after one macroslip cycle's energy
    el = SlipDegradation(IwanJoint(P), rate=rate)
    t = np.linspace(0, 6, 6 * 400 + 1)
    u = 2.0 * A * np.sin(2 * np.pi * t)
    F, W, D = run(el, u)
    peaks = [F[(t >= k) & (t < k + 1)].max() for k in range(6)]
    assert all(b < a for a, b in zip(peaks[1:], peaks[2:]))
    lam = el.capacity_factor
    assert lam == pytest.approx(math.exp(-rate * el.dissipated_energy), rel=1e-5)
    assert F.max() <= P.Fs * (1 + 1e-9)
    assert lam * P.Fs * (1 - 1e-9) <= peaks[-1] < peaks[-2]  # macroslip at the current lambda Fs
    # the elastic stiffness after a reversal is still KT (not lambda KT)
    el.trial(u[-1] - 1e-6 * A)
    K = el.trial(u[-1] - 1e-6 * A)[1]
    el.revert()
    assert K == pytest.approx(P.KT, rel=0.02)
    # dissipation never falls by more than the 128-slider bank's discretisation error
    assert np.all(np.diff(D) >= -2e-3 * P.Fs * A)
    assert el.work == pytest.approx(el.stored_energy + el.dissipated_energy)


@pytest.mark.parametrize("rate_x", [0.0, 0.05, 2.0, 40.0])
def test_slip_degradation_run_solver_equals_the_per_sample_steps(rate_x):
    """The correction bank solved per monotone run (fixed point of the capacities) gives the
    forces of the per-sample reference loop, on a cyclic ramp with a pause and on a random
    walk (many short runs, where capacities may fall back to the reference), also through the
    element route (trial/commit): a wrong run formula (clip order, pre-clip force, pauses)
    fails this."""
    from iwan_element.effects.engine.sliders import SliderEffect

    rng = np.random.default_rng(11)
    t = np.arange(900) / 100.0
    u1 = A * np.interp(t, [0, t[-1]], [0.2, 2.5]) * np.sin(2 * np.pi * t)
    u1[100:112] = u1[100]  # a pause inside a run
    u2 = np.cumsum(rng.normal(size=400)) * 0.15 * A
    rate = rate_x / dissipation(A, P)
    for u in (u1, u2):
        D = run(IwanJoint(P), u)[2]
        fast = SlipDegradation(IwanJoint(P), rate=rate).correction_history(u, D)
        ref_el = SlipDegradation(IwanJoint(P), rate=rate)
        ref = SliderEffect._correction_energy(ref_el, u, D)
        np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-11 * P.Fs)
        if u is u2:  # the element route (trial/commit), on a record without pauses (the
            # element also commits at a pause and re-reads the energy after its clip there)
            F_el = run(SlipDegradation(IwanJoint(P), rate=rate), u)[0]
            F_in = run(IwanJoint(P), u)[0]
            np.testing.assert_allclose(F_in + fast, F_el, rtol=0, atol=1e-9 * P.Fs)


def test_asymmetric_slip_thresholds_not_a_scaled_force():
    a = 0.3
    el = AsymmetricSlip(IwanJoint(P), asymmetry=a)
    t = np.linspace(0, 3, 3 * 2000 + 1)
    u = 2.0 * A * np.sin(2 * np.pi * t)
    F, W, D = run(el, u)
    assert F.max() == pytest.approx((1 + a) * P.Fs, rel=1e-9)
    assert F.min() == pytest.approx(-(1 - a) * P.Fs, rel=1e-9)
    # the initial stiffness is KT in both directions (a scaled force would give (1 +- a) KT)
    e2 = AsymmetricSlip(IwanJoint(P), asymmetry=a)
    assert e2.trial(1e-6 * A)[1] == pytest.approx(P.KT, rel=1e-3)
    assert e2.trial(-1e-6 * A)[1] == pytest.approx(P.KT, rel=1e-3)
    i0, i1 = 2000, 4000
    area = np.trapezoid(F[i0 : i1 + 1], u[i0 : i1 + 1])
    assert W[i1] - W[i0] == pytest.approx(area, rel=1e-3)


def test_breakaway_peak_after_each_reversal():
    r = 1.8
    t = np.linspace(0, 3, 3 * 2000 + 1)
    u = 3.0 * A * np.sin(2 * np.pi * t)
    F = BreakAway(
        IwanJoint(
            P,
        ),
        ratio=r,
    ).force_history(u)
    cyc = F[2000:4000]
    assert cyc.max() > 1.05 * P.Fs and cyc.max() <= r * P.Fs * (1 + 1e-9)
    assert F[3000 - 600] == pytest.approx(P.Fs, rel=1e-6)  # sliding again at Fs mid-stroke


def test_effects_stack_and_describe():
    el = ViscousDamping(PinningStiffness(IwanJoint(P), k_p=1e5), c=10.0)
    assert "viscous_damping" in el.describe() and "pinning_stiffness" in el.describe()
    assert base_joint(el).params == P
    F, K = el.trial(2 * A, 1.0)
    assert F == pytest.approx(P.Fs + 1e5 * 2 * A + 10.0)
    el.commit()
    bl = Backlash(ViscousDamping(IwanJoint(P), c=0.0), gap=0.1 * A)
    _, u = history()
    np.testing.assert_allclose(
        bl.force_history(u), Backlash(IwanJoint(P), gap=0.1 * A).force_history(u), atol=1e-12 * P.Fs
    )


def test_trial_commits_nothing():
    for name, extra in [
        ("viscous_damping", {"c": 10.0}),
        ("pinning_stiffness", {"k_p": 1e5}),
        ("backlash", {"gap": 0.1 * A}),
        ("slip_degradation", {"rate": 1.0}),
        ("asymmetric_slip", {"asymmetry": 0.2}),
        ("breakaway", {"ratio": 1.5}),
    ]:
        el = make_effect(name, IwanJoint(P), **extra)
        el.trial(0.7 * A, 0.1)
        el.commit()
        state = (el.force, el.work, el.dissipated_energy)
        F_probe = el.trial(-0.2 * A, 0.0)[0]
        el.trial(1.9 * A, 0.3)
        el.trial(-3 * A, -0.3)
        el.revert()
        assert (el.force, el.work, el.dissipated_energy) == state, name
        assert el.trial(-0.2 * A, 0.0)[0] == F_probe, name


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: make_effect("friction", IwanJoint(P)), "unknown effect"),
        (lambda: make_effect("backlash", IwanJoint(P), gap=1e-5, c=1.0), "takes parameters"),
        (lambda: ViscousDamping(IwanJoint(P), c=-1.0), "c must be"),
        (lambda: PinningStiffness(IwanJoint(P), k_p=1.0, delta=-1.0), "delta"),
        (lambda: Backlash(IwanJoint(P), gap=math.nan), "gap"),
        (lambda: SlipDegradation(IwanJoint(P), rate=-0.1), "rate"),
        (lambda: AsymmetricSlip(IwanJoint(P), asymmetry=1.0), "asymmetry"),
        (lambda: ViscousDamping(object(), c=1.0), "inner"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


@pytest.mark.parametrize(
    "name,extra",
    [
        ("pinning_stiffness", {"k_p": 2e5, "delta": 0.3 * A}),
        ("backlash", {"gap": 0.15 * A}),
        ("asymmetric_slip", {"asymmetry": 0.3}),
    ],
)
def test_rate_independence_with_coarse_steps(name, extra):
    """Coarse steps (crossing the whole gap or a force zero in one step) give the same forces
    as the same piecewise-linear path sub-stepped 50 times."""
    rng = np.random.default_rng(4)
    pts = np.concatenate([[0.0], rng.uniform(-2.5, 2.5, 40) * A])
    fine = np.concatenate([np.linspace(a, b, 51)[1:] for a, b in zip(pts[:-1], pts[1:])])
    el = make_effect(name, IwanJoint(P), **extra)
    np.testing.assert_allclose(
        el.force_history(fine)[49::50], el.force_history(pts[1:]), rtol=0, atol=1e-9 * P.Fs
    )


def test_make_effect_missing_parameter_and_bare_element():
    with pytest.raises(ValueError, match="needs parameter"):
        make_effect("backlash", IwanJoint(P))
    assert make_effect("pinning_stiffness", IwanJoint(P), k_p=1.0).delta == 0.0  # delta defaults

    class Bare:  # energies but no force/displacement read-outs
        work = stored_energy = dissipated_energy = 0.0

        def trial(self, u, v=0.0):
            return 0.0, 0.0

        def commit(self):
            pass

        def revert(self):
            pass

        def reset(self):
            pass

    with pytest.raises(ValueError, match="force"):
        Backlash(Bare(), gap=0.1)
    with pytest.raises(ValueError, match="plain Iwan joint"):
        AsymmetricSlip(Backlash(IwanJoint(P), gap=1e-6), asymmetry=0.1)


def _drag_loop_by_parametric_route(g, fd, w_r):
    """Independent route for a virgin loading to joint displacement ``w_r`` and the full
    unloading to ``-w_r`` of a joint in series with a gap ``g`` crossed against a friction
    ``fd``: on a fine grid of the joint displacement ``w`` the joint force is the closed-form
    backbone / Masing branch (docs/equations.md section 2, eq. 13) and the drive is explicit,
    ``u = w + g`` against the forward stop and ``u = w - g`` against the back stop, with a
    plateau at ``F = -fd`` between (the joint stands still while the gap slides open)."""
    w_up = np.linspace(0.0, w_r, 40001)
    F_up = backbone(w_up, P)
    u_up = np.where(F_up < fd, w_up, w_up + g)  # stuck in the middle, then slid open
    w_dn = np.linspace(w_r, -w_r, 80001)
    F_dn = backbone(w_r, P) - 2.0 * backbone((w_r - w_dn) / 2.0, P)
    fwd = F_dn > -fd
    u_dn = np.concatenate([w_dn[fwd] + g, w_dn[~fwd] - g])
    return (u_up, F_up), (u_dn[::-1], F_dn[::-1])


@pytest.mark.parametrize("w_r", [0.4 * A, 1.6 * A])
def test_backlash_drag_against_explicit_series_route(w_r):
    g, fd = 0.2 * A, 0.05 * P.Fs
    (u_up, F_up), (u_dn, F_dn) = _drag_loop_by_parametric_route(g, fd, w_r)
    up = np.linspace(0.0, u_up[-1], 301)[1:]
    dn = np.linspace(u_up[-1], u_dn[0], 601)[1:]
    el = Backlash(IwanJoint(P), gap=g, drag=fd)
    F = el.force_history(np.concatenate([up, dn]))
    np.testing.assert_allclose(F[: up.size], np.interp(up, u_up, F_up), rtol=0, atol=2e-4 * P.Fs)
    np.testing.assert_allclose(F[up.size :], np.interp(dn, u_dn, F_dn), rtol=0, atol=2e-4 * P.Fs)
    # the plateau sits at -drag, against the motion, over a travel of 2 gap
    on = np.abs(F[up.size :] + fd) < 1e-9 * P.Fs
    assert np.sum(on) * abs(dn[1] - dn[0]) == pytest.approx(2 * g, abs=2 * abs(dn[1] - dn[0]))


def test_backlash_drag_tends_to_the_free_gap_and_energy_balances():
    g = 0.15 * A
    _, u = history()
    free = Backlash(IwanJoint(P), gap=g).force_history(u)
    for fd in (1e-3 * P.Fs, 1e-9 * P.Fs):
        np.testing.assert_allclose(
            Backlash(IwanJoint(P), gap=g, drag=fd).force_history(u),
            free,
            rtol=0,
            atol=1.01 * fd + 1e-12 * P.Fs,
        )
    # over a closed cycle the loop area is the joint's dissipation plus 2 crossings of the
    # gap against the drag, 4 gap drag (the joint sees amplitude u0 - g)
    fd = 0.08 * P.Fs
    u0 = 2.5 * A
    uc = u0 * np.cos(np.linspace(0, 4 * np.pi, 8001))
    el = Backlash(IwanJoint(P), gap=g, drag=fd)
    F, W, D = run(el, uc)
    half = 4000
    expected = dissipation(u0 - g, P) + 4 * g * fd
    assert D[-1] - D[half] == pytest.approx(expected, rel=1e-9)
    assert W[-1] - W[half] == pytest.approx(expected, rel=1e-9)
    assert np.trapezoid(F[half:], uc[half:]) == pytest.approx(expected, rel=2e-4)
    np.testing.assert_allclose(
        W[1:] - W[0], np.cumsum(0.5 * (F[1:] + F[:-1]) * np.diff(uc)), rtol=0, atol=2e-4 * P.Fs * A
    )
    assert np.all(np.diff(D) >= -1e-12 * P.Fs * A)


def test_backlash_drag_coarse_steps_and_bad_drag():
    rng = np.random.default_rng(5)
    pts = np.concatenate([[0.0], rng.uniform(-2.5, 2.5, 30) * A])
    fine = np.concatenate([np.linspace(a, b, 51)[1:] for a, b in zip(pts[:-1], pts[1:])])
    el = Backlash(IwanJoint(P), gap=0.1 * A, drag=0.05 * P.Fs)
    np.testing.assert_allclose(
        el.force_history(fine)[49::50], el.force_history(pts[1:]), rtol=0, atol=1e-9 * P.Fs
    )
    for bad in (-1e-9, math.nan, math.inf):
        with pytest.raises(ValueError, match="drag"):
            Backlash(IwanJoint(P), gap=0.1 * A, drag=bad)


@pytest.mark.parametrize("drag", [0.0, 30.0, 200.0])
@pytest.mark.parametrize("gap_x", [0.0, 0.05, 0.5])
def test_backlash_joint_path_is_the_per_sample_steps(drag, gap_x):
    """The run-by-run joint path (one trial per monotone run) against the element stepped
    sample by sample, on a plain joint and on a chain of slider laws; forces along the path
    are the backlash element's."""
    rng = np.random.default_rng(1)
    t = np.linspace(0, 6, 6 * 80 + 1)
    u = A * np.sin(2 * np.pi * t) * np.linspace(0.3, 3, t.size) + 0.02 * A * rng.normal(size=t.size)
    u = np.concatenate([u, u[-1] + np.cumsum(rng.normal(size=150)) * 0.2 * A])
    for inner in (IwanJoint(P), BreakAway(AsymmetricSlip(IwanJoint(P), asymmetry=0.2), ratio=1.6)):
        el = Backlash(inner, gap=gap_x * A, drag=drag)
        stepped = Backlash(inner, gap=gap_x * A, drag=drag)
        stepped.reset()
        w_ref = []
        for x in u:
            stepped.trial(x)
            stepped.commit()
            w_ref.append(stepped.joint_displacement)
        w = el.joint_path(u)
        np.testing.assert_allclose(w, w_ref, rtol=0, atol=1e-12 * A)
        np.testing.assert_allclose(
            inner.force_history(w), el.force_history(u), rtol=0, atol=1e-10 * P.Fs
        )
    assert el.joint_displacement == 0.0  # the element itself is untouched
