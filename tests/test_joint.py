"""The exact IwanJoint against independent routes: a dense slider model written here, the
closed-form dissipation, Masing branches (paper eqs. 13-15) and finite differences."""

import math

import numpy as np
import pytest

from iwan_element import (
    IwanJoint,
    IwanParameters,
    backbone,
    dissipation,
    masing_ascending,
    masing_descending,
)

PARAMS = [
    IwanParameters(3.0, 2.0, -0.1, 0.1),
    IwanParameters(400.0, 2.5266e5, -0.5, 1.0),
    IwanParameters(1000.0, 1e6, -0.5, 0.2),
    IwanParameters(50.0, 4e4, -0.8, 0.0),
    IwanParameters(2.0, 7.0, -0.25, 2.0),
]


class DenseSliders:
    """Independent reference: N log-spaced, moment-matched Jenkins sliders (not the package's)."""

    def __init__(self, p, n=20000, lowest=1e-10):
        edges = np.concatenate([[0.0], p.phi_max * np.logspace(np.log10(lowest), 0.0, n)])
        c = p.chi
        m0 = p.R * (edges[1:] ** (c + 1) - edges[:-1] ** (c + 1)) / (c + 1)
        m1 = p.R * (edges[1:] ** (c + 2) - edges[:-1] ** (c + 2)) / (c + 2)
        self.k = np.append(m0, p.S)
        self.phi = np.append(m1 / m0, p.phi_max)

    def run(self, u):
        z = np.zeros_like(self.k)
        F = np.empty(len(u))
        E = np.empty(len(u))
        prev = 0.0
        for i, x in enumerate(u):
            z = np.clip(z + (x - prev), -self.phi, self.phi)
            F[i] = self.k @ z
            E[i] = 0.5 * self.k @ (z * z)
            prev = x
        return F, E


def random_history(rng, p, n_rev=40, per_segment=4):
    """Piecewise-linear history through random reversal points: the direction alternates and
    the excursions span deep microslip to macroslip (1e-4 to 4 phi_max), so inner loops open
    and close (Madelung's rule) and macroslip wipes the memory."""
    steps = p.phi_max * 10 ** rng.uniform(-4, math.log10(4.0), n_rev)
    pts = [0.0]
    sign = rng.choice([-1.0, 1.0])
    for s in steps:
        pts.append(float(np.clip(pts[-1] + sign * s, -3 * p.phi_max, 3 * p.phi_max)))
        sign = -sign
    pts = np.array(pts)
    segs = [np.linspace(a, b, per_segment + 1)[1:] for a, b in zip(pts[:-1], pts[1:])]
    return np.concatenate(segs)


def run_joint(j, u):
    F = np.empty(len(u))
    E = np.empty(len(u))
    D = np.empty(len(u))
    for i, x in enumerate(u):
        F[i] = j.trial(x)[0]
        j.commit()
        E[i] = j.stored_energy
        D[i] = j.dissipated_energy
    return F, E, D


@pytest.mark.parametrize("pi", range(len(PARAMS)))
def test_exact_matches_dense_sliders_on_random_histories(pi):
    """20 random histories in total (4 per parameter set): max |dF| <= 1e-6 Fs, and the stored
    energy agrees with the sliders' spring energy."""
    p = PARAMS[pi]
    rng = np.random.default_rng(100 + pi)
    ref = DenseSliders(p)
    j = IwanJoint(p)
    reached_macro = False
    for _ in range(4):
        u = random_history(rng, p)
        reached_macro |= bool(np.any(np.abs(np.diff(u)) > 0) and np.ptp(u) > 2 * p.phi_max)
        j.reset()
        F, E, _ = run_joint(j, u)
        F_ref, E_ref = ref.run(u)
        assert np.max(np.abs(F - F_ref)) <= 1e-6 * p.Fs
        assert np.max(np.abs(E - E_ref)) <= 1e-6 * p.Fs * p.phi_max
    assert reached_macro


@pytest.mark.parametrize("p", PARAMS)
@pytest.mark.parametrize("r", [1e-6, 1e-3, 0.5, 1.0, 3.0])
def test_steady_cycle_loop_area_equals_dissipation(p, r):
    u0 = r * p.phi_max
    t = np.linspace(0.0, 3.0, 3 * 64 + 1)  # three cycles, peaks on samples
    u = u0 * np.sin(2 * np.pi * t + np.pi / 2) * np.minimum(1.0, t * 4)  # ramp in, then steady
    j = IwanJoint(p)
    for x in u[: 2 * 64 + 1]:
        j.trial(x)
        j.commit()
    W0, D0 = j.work, j.dissipated_energy
    for x in u[2 * 64 + 1 :]:
        j.trial(x)
        j.commit()
    D = dissipation(u0, p)
    assert (j.work - W0) == pytest.approx(D, rel=1e-9)  # loop area = closed-path work
    assert (j.dissipated_energy - D0) == pytest.approx(D, rel=1e-9)


@pytest.mark.parametrize("r", [1e-3, 0.5, 3.0])
def test_loop_area_by_quadrature_of_sampled_forces(r):
    """Trapezoid area of a densely sampled steady loop (no energy counters involved)."""
    p = PARAMS[2]
    u0 = r * p.phi_max
    u = u0 * np.cos(np.linspace(0, 4 * np.pi, 400001))
    F = IwanJoint(p).force_history(u)
    half = len(u) // 2
    area = np.trapezoid(F[half:], u[half:])
    assert area == pytest.approx(dissipation(u0, p), rel=1e-6)


@pytest.mark.parametrize("p", PARAMS)
def test_masing_branches_eq13_eq15(p):
    """From the virgin tip (s0, f(s0)) down to -s0 (eq. 13) and back up (eq. 15, corrected)."""
    s0 = 0.7
    s = np.linspace(s0, -s0, 51)
    j = IwanJoint(p)
    j.trial(s0 * p.phi_max)
    j.commit()
    down = [j.trial(x * p.phi_max)[0] for x in s]
    # trial without commit is a pure evaluation from the tip
    np.testing.assert_allclose(
        np.array(down) / p.Fs, masing_descending(s, s0, p.chi, p.beta), rtol=1e-12, atol=1e-13
    )
    for x in s:
        j.trial(x * p.phi_max)
        j.commit()
    up = np.linspace(-s0, s0, 51)
    Fu = []
    for x in up:
        Fu.append(j.trial(x * p.phi_max)[0])
        j.commit()
    np.testing.assert_allclose(
        np.array(Fu) / p.Fs, masing_ascending(up, s0, p.chi, p.beta), rtol=1e-12, atol=1e-13
    )
    # after the loop closes the joint is back on the virgin curve
    j.trial(0.9 * p.phi_max)
    assert j.trial(0.9 * p.phi_max)[0] == pytest.approx(backbone(0.9 * p.phi_max, p), rel=1e-12)


def test_nested_loop_closes_and_rejoins_outer_branch():
    """Madelung's rule: an inner loop closed by passing its start returns to the outer branch."""
    p = PARAMS[1]
    a = p.phi_max
    j = IwanJoint(p)
    for x in [0.8 * a, -0.2 * a, 0.3 * a]:  # outer descent, inner reversal, inner ascent
        j.trial(x)
        j.commit()
    assert j.reversal_depth == 2
    F_outer = IwanJoint(p).force_history(np.array([0.8 * a, -0.5 * a]))[-1]
    j.trial(-0.5 * a)  # passes -0.2 a: the inner loop (0.3a, -0.2a) closes
    j.commit()
    assert j.force == pytest.approx(F_outer, rel=1e-13)
    assert j.reversal_depth == 1


@pytest.mark.parametrize("p", PARAMS)
def test_properties_odd_bounded_rate_independent_passive(p):
    rng = np.random.default_rng(7)
    u = random_history(rng, p, n_rev=60, per_segment=3)
    j = IwanJoint(p)
    F = j.force_history(u)
    np.testing.assert_allclose(j.force_history(-u), -F, rtol=0, atol=1e-12 * p.Fs)
    assert np.all(np.abs(F) <= p.Fs * (1 + 1e-12))
    # sub-stepping: split every step into 7; forces at the original samples agree
    pts = np.concatenate([[0.0], u])
    fine = np.concatenate([np.linspace(a, b, 8)[1:] for a, b in zip(pts[:-1], pts[1:])])
    np.testing.assert_allclose(j.force_history(fine)[6::7], F, rtol=0, atol=1e-11 * p.Fs)
    # passivity: dissipation never decreases; stored energy non-negative; W = E + D
    j.reset()
    _, E, D = run_joint(j, u)
    assert np.all(np.diff(D) >= -1e-15 * p.Fs * p.phi_max)
    assert np.all(E >= -1e-12 * p.Fs * p.phi_max)
    assert j.work == pytest.approx(j.stored_energy + j.dissipated_energy, rel=1e-12)


@pytest.mark.parametrize("p", PARAMS)
def test_tangent_equals_finite_difference_of_trial(p):
    rng = np.random.default_rng(3)
    u = random_history(rng, p, n_rev=15, per_segment=2)
    j = IwanJoint(p)
    checked = 0
    for a, b in zip(u[:-1], u[1:]):
        j.trial(a)
        j.commit()
        step = b - a
        if step == 0:
            continue
        F1, K1 = j.trial(a + 0.5 * step)
        h = 1e-6 * abs(step)
        Fp, _ = j.trial(a + 0.5 * step + math.copysign(h, step))
        Fm, _ = j.trial(a + 0.5 * step - math.copysign(h, step))
        fd = (Fp - Fm) / (2 * math.copysign(h, step))
        assert K1 == pytest.approx(fd, rel=1e-4, abs=1e-6 * p.KT)
        checked += 1
    j.revert()
    assert checked > 10


def test_trial_does_not_commit_and_revert_restores():
    p = PARAMS[2]
    j = IwanJoint(p)
    j.trial(0.4 * p.phi_max)
    j.commit()
    state = (j.displacement, j.force, j.stiffness, j.work, j.dissipated_energy, j.reversal_depth)
    F_back = j.trial(0.1 * p.phi_max)[0]
    for x in [-2 * p.phi_max, 0.9 * p.phi_max, 0.0]:
        j.trial(x)
    assert (
        j.displacement,
        j.force,
        j.stiffness,
        j.work,
        j.dissipated_energy,
        j.reversal_depth,
    ) == state
    j.revert()
    j.commit()  # nothing to commit after a revert
    assert j.displacement == state[0]
    assert j.trial(0.1 * p.phi_max)[0] == F_back
    j.reset()
    assert (j.displacement, j.force, j.work, j.reversal_depth) == (0.0, 0.0, 0.0, 0)


def test_force_history_leaves_element_untouched():
    p = PARAMS[0]
    j = IwanJoint(p)
    j.trial(0.3)
    j.commit()
    u = np.array([0.1, 0.5, -0.2])
    keep = u.copy()
    j.force_history(u)
    np.testing.assert_array_equal(u, keep)
    assert j.displacement == 0.3


def test_reversal_stack_bounded_on_long_random_histories():
    p = PARAMS[2]
    rng = np.random.default_rng(11)
    j = IwanJoint(p)
    depth = []
    # i.i.d. random targets (heavy-tailed amplitudes) and a bounded random walk
    u1 = p.phi_max * rng.standard_t(3, 50000) * 0.5
    u2 = np.clip(
        np.cumsum(rng.normal(size=50000)) * 0.01 * p.phi_max, -2 * p.phi_max, 2 * p.phi_max
    )
    for u in (u1, u2):
        j.reset()
        for x in u:
            j.trial(x)
            j.commit()
            depth.append(j.reversal_depth)
    assert max(depth) < 60


def test_round_off_jitter_is_ignored():
    """Reversals below reversal_tol * phi_max (solver round-off) do not grow the stack."""
    p = PARAMS[2]
    j = IwanJoint(p)
    j.trial(0.5 * p.phi_max)
    j.commit()
    F0 = j.force
    rng = np.random.default_rng(0)
    for x in 0.5 * p.phi_max + rng.normal(scale=1e-16 * p.phi_max, size=1000):
        j.trial(x)
        j.commit()
    assert j.reversal_depth <= 1
    assert j.force == pytest.approx(F0, abs=1e-10 * p.Fs)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_bad_trial_input(bad):
    j = IwanJoint(PARAMS[0])
    with pytest.raises(ValueError, match="u must be finite"):
        j.trial(bad)
    with pytest.raises(ValueError, match="u"):
        j.force_history([0.0, bad])


def test_bad_construction():
    with pytest.raises(ValueError, match="params"):
        IwanJoint({"Fs": 1.0})
    with pytest.raises(ValueError, match="reversal_tol"):
        IwanJoint(PARAMS[0], reversal_tol=-1.0)
    with pytest.raises(ValueError, match="reversal_tol"):
        IwanJoint(PARAMS[0], reversal_tol=0.1)


@pytest.mark.parametrize("p", PARAMS)
def test_fast_paths_equal_the_general_walk_bit_for_bit(p):
    """trial() and commit() take a shortcut when the motion continues the current branch;
    force, tangent, work and dissipation must be exactly those of the general walk."""
    rng = np.random.default_rng(5)
    j = IwanJoint(p)
    u = np.concatenate(
        [
            random_history(rng, p),
            p.phi_max * 1.5 * np.sin(np.arange(3000) / 40.0) * np.exp(-np.arange(3000) / 1500.0),
        ]
    )
    fast = 0
    for i, x in enumerate(u.tolist()):
        step = abs(x - j.displacement) + 1e-9 * p.phi_max
        for y in [x + step * z for z in rng.normal(scale=0.5, size=2)] + [x]:
            n, e, eF, F, K = j._walk(y, None)
            assert j.trial(y) == (F, K)
        fast += j._tfast
        acc = [0.0, 0.0, 0.0, 0.0]
        j._walk(x, acc)
        W, D = j.work + acc[0], j.dissipated_energy + acc[1]
        j.commit()
        assert (j.work, j.dissipated_energy) == (W, D), i
    assert 0.3 * len(u) < fast < len(u)  # both routes were exercised


def test_force_history_takes_velocities_like_every_element_and_checks_them():
    """The plain joints are rate independent: velocities change nothing, but a velocity
    history of the wrong length or with NaN is refused naming ``v``."""
    from iwan_element import DiscreteIwan

    p = IwanParameters(400.0, 2.5e5, -0.5, 1.0)
    u = 1.5 * p.phi_max * np.sin(np.linspace(0, 4 * np.pi, 200))
    v = np.gradient(u)
    for el in (IwanJoint(p), DiscreteIwan(p, n_sliders=50)):
        np.testing.assert_array_equal(el.force_history(u, v), el.force_history(u))
        with pytest.raises(ValueError, match="v"):
            el.force_history(u, v[:-1])
        with pytest.raises(ValueError, match="v"):
            el.force_history(u, np.full_like(u, np.nan))
