"""Break-away on the continuous Iwan density (effects/breakaway.py), against independent
routes: the closed-form virgin and first unloading branches written here from the density
(docs/equations.md section 2), and a bank of Jenkins sliders with static/kinetic thresholds stepped
in tests/_jenkins_bank.py, which converges to the element as the bank gets dense."""

import numpy as np
import pytest
from _helpers import stepped_sine
from _jenkins_bank import jenkins_bank

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters
from iwan_element.effects import BreakAway

P = IwanParameters(1000.0, 1e6, -0.5, 0.2)
P0 = IwanParameters(1000.0, 1e6, -0.3, 0.0)  # no spike: force continuous in time
A = P.phi_max


AMPS = (0.4, 1.6, 0.7, 2.5, 0.3, 1.1)  # fractions of phi_max


def _drive(per=150):
    return stepped_sine(A, per, AMPS)[1]


def _moments(p, x):
    """Continuous density of ``p`` (docs/equations.md section 2): ``int_0^x rho`` and
    ``int_0^x rho phi``, ``rho = R phi^chi``."""
    q = p.chi + 1.0
    C = q * p.KT / (1.0 + p.beta)  # R phi_max^(chi+1)
    r = np.minimum(x, p.phi_max) / p.phi_max
    return C * r**q / q, C * p.phi_max * r ** (q + 1) / (q + 1)


@pytest.mark.parametrize("p", [P, P0])
def test_virgin_and_first_unloading_branches_in_closed_form(p):
    """Virgin loading: sliders with ``r phi < d`` slide at ``phi``, the others carry ``d``.
    After a reversal at ``d0 < r phi_max`` (travel ``y``): the sliders that slid break again
    when ``(r + 1) phi < y``, the stuck ones (at ``d0``) when ``r phi < y - d0``."""
    r = 1.7
    pm = p.phi_max
    S = p.KT - p.KT / (1.0 + p.beta)
    d = np.linspace(0.0, 2.5 * pm, 301)[1:]
    M0_all, _ = _moments(p, pm)
    M0, M1 = _moments(p, d / r)
    F_virgin = M1 + d * (M0_all - M0) + S * np.where(d > r * pm, pm, d)
    el = BreakAway(IwanJoint(p), ratio=r)
    np.testing.assert_allclose(el.force_history(d), F_virgin, rtol=1e-12, atol=1e-9 * p.Fs)

    d0 = 0.8 * pm  # below r phi_max: the spike stays stuck
    y = np.linspace(0.0, 3.0 * pm, 301)[1:]
    b = d0 / r  # sliders below b slid on the way up
    M0b, M1b = _moments(p, b)
    x1 = np.minimum(y / (r + 1.0), b)  # those break again below x1
    M0x, M1x = _moments(p, x1)
    x2 = np.clip((y - d0) / r, b, pm)  # stuck ones (stretch d0) break below x2
    M0y, M1y = _moments(p, x2)
    F_slid = -M1x + (M1b - M1x) - y * (M0b - M0x)  # force of [0, b] (e = phi - y or -phi)
    F_stuck = -(M1y - M1b) + (d0 - y) * (M0_all - M0y)
    spike = S * np.where(y - d0 > r * pm, -pm, d0 - y)
    F_down = F_slid + F_stuck + spike
    F = el.force_history(np.concatenate([np.linspace(0, d0, 50)[1:], d0 - y]))[49:]
    np.testing.assert_allclose(F, F_down, rtol=1e-10, atol=1e-9 * p.Fs)


def test_dense_slider_banks_converge_to_the_element():
    u = _drive()
    r = 1.55
    F = BreakAway(IwanJoint(P), ratio=r).force_history(u)
    errs = []
    for n in (100, 400, 1600):
        d = DiscreteIwan(P, n)
        errs.append(
            float(
                np.sqrt(np.mean((jenkins_bank(u, d.slider_stiffness, d.slider_slip, r) - F) ** 2))
            )
            / P.Fs
        )
    # first order in 1/n (a slider breaks one sample early or late): 4x denser, about 4x closer
    assert errs[0] / errs[1] > 2.5 and errs[1] / errs[2] > 2.5, errs
    assert errs[2] < 2e-3, errs


def test_on_a_discrete_joint_it_is_that_bank():
    u = _drive(60)
    d = DiscreteIwan(P, 15)
    F = BreakAway(DiscreteIwan(P, 15), ratio=1.45).force_history(u)
    np.testing.assert_allclose(
        F, jenkins_bank(u, d.slider_stiffness, d.slider_slip, 1.45), rtol=0, atol=1e-9 * P.Fs
    )


def test_ratio_one_is_the_plain_joint_and_the_run_route_is_the_element():
    rng = np.random.default_rng(5)
    u = np.concatenate([_drive(40), np.cumsum(rng.normal(size=400)) * 0.2 * A])
    u[300:310] = u[300]  # a pause inside a run
    F1 = BreakAway(IwanJoint(P), ratio=1.0).force_history(u)
    np.testing.assert_allclose(F1, IwanJoint(P).force_history(u), rtol=0, atol=1e-10 * P.Fs)
    for inner in (IwanJoint(P), DiscreteIwan(P, 20)):
        el = BreakAway(inner, ratio=1.8)
        F_el = el.force_history(u)
        F_run = inner.force_history(u) + el.correction_history(u)
        np.testing.assert_allclose(F_run, F_el, rtol=0, atol=1e-9 * P.Fs)


@pytest.mark.parametrize("p", [P, P0])
def test_energy_balance_and_tangent(p):
    u = p.phi_max * np.array([0.0, 0.7, -0.3, 1.2, 0.5, 2.0, -1.4, 0.1, -0.2])
    works = []
    for m in (200, 2000):
        uf = np.concatenate(
            [np.linspace(a, b, m, endpoint=False) for a, b in zip(u[:-1], u[1:])] + [u[-1:]]
        )
        el = BreakAway(IwanJoint(p), ratio=1.8)
        F, D = np.empty(uf.size), np.empty(uf.size)
        for i, x in enumerate(uf):
            F[i] = el.trial(x)[0]
            el.commit()
            D[i] = el.dissipated_energy
        works.append((el.work, float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(uf)))))
        assert np.all(np.diff(D) >= -1e-12 * p.Fs * p.phi_max)
        assert el.work == pytest.approx(el.stored_energy + el.dissipated_energy, rel=1e-12)
    # the element's exact work and the trapezoidal rule over its forces agree as the steps
    # shrink: second order without the spike; with it, each break of the spike is a force
    # jump S (r - 1) phi_max inside one step, which the trapezoid misses by up to half of it
    gaps = [abs(w - trap) for w, trap in works]
    if p.beta == 0.0:
        assert gaps[1] < 0.02 * gaps[0] and gaps[1] < 1e-6 * works[1][0]
    else:
        jump = (p.KT - p.KT / (1 + p.beta)) * 0.8 * p.phi_max
        for m, g in zip((200, 2000), gaps):
            assert g < 4 * jump * 3.4 * p.phi_max / m
    # consistent tangent: the derivative of the trial force, also on the softening part
    # just after a slider group breaks
    h = 1e-7 * p.phi_max
    for x in (-1.3 * p.phi_max, -0.25 * p.phi_max, 0.5 * p.phi_max, 2.2 * p.phi_max):
        F0, K = el.trial(x)
        assert K == pytest.approx(
            (el.trial(x + h)[0] - el.trial(x - h)[0]) / (2 * h), rel=1e-4, abs=1e-6 * p.KT
        )
    el.revert()


def test_force_is_continuous_in_the_ratio():
    """The reason for the continuous form: a difference quotient in the ratio does not change
    as the step shrinks (a slider bank's does: each slider breaks at one sample or the next,
    a staircase that a least-squares fit cannot climb)."""
    u = _drive(100)
    r = 1.43

    def slope(h, el_of):
        return np.max(np.abs(el_of(r + h) - el_of(r - h))) / (2 * h)

    cont = lambda x: BreakAway(IwanJoint(P0), ratio=x).correction_history(u)  # noqa: E731
    s_big, s_small = slope(1e-2, cont), slope(1e-5, cont)
    assert s_small == pytest.approx(s_big, rel=0.2)
    d = DiscreteIwan(P0, 128)
    bank = lambda x: jenkins_bank(u, d.slider_stiffness, d.slider_slip, x)  # noqa: E731
    # the bank's quotient is zero between breaks and jump/step across one: never the slope
    assert abs(slope(1e-5, bank) / slope(1e-2, bank) - 1.0) > 0.5


def test_pieces_stay_few_on_a_random_walk():
    rng = np.random.default_rng(2)
    el = BreakAway(IwanJoint(P), ratio=1.6)
    count = []
    for x in np.cumsum(rng.normal(size=3000)) * 0.1 * A:
        el.trial(x)
        el.commit()
        count.append(el.n_pieces)
    assert max(count) < 200
