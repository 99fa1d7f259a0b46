"""Slider laws that compose (effects/engine/law.py): asymmetric slip and break-away on one joint.

Independent routes: a plain-Python bank of Jenkins sliders with static and kinetic thresholds
per direction (tests/_jenkins_bank.py), to which the element is equal on a DiscreteIwan and to
which dense banks converge on the continuous joint; the element's exact work against the
trapezoidal rule over its forces; the diagnosis evaluator's run route against the element."""

import numpy as np
import pytest
from _helpers import stepped_sine
from _jenkins_bank import directional_bank

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters
from iwan_element.effects import AsymmetricSlip, BreakAway, SlipDegradation
from iwan_element.effects.engine.evaluate import Evaluator

P = IwanParameters(1000.0, 1e6, -0.5, 0.2)
A = P.phi_max
R, ASYM = 1.7, 0.3


AMPS = (0.4, 1.6, 0.7, 2.5, 0.3, 1.1)  # fractions of phi_max


def _drive(per=80):
    return stepped_sine(A, per, AMPS)[1]


def _bank(u, d, r=R, a=ASYM):
    k, phi = d.slider_stiffness, d.slider_slip
    return directional_bank(
        u, k, r * (1 + a) * phi, r * (1 - a) * phi, kin_up=(1 + a) * phi, kin_dn=(1 - a) * phi
    )


@pytest.mark.parametrize("order", ["breakaway_outside", "asymmetry_outside"])
def test_on_a_discrete_joint_the_product_law_is_that_bank(order):
    u = _drive(40)
    d = DiscreteIwan(P, 12)
    if order == "breakaway_outside":
        el = BreakAway(AsymmetricSlip(DiscreteIwan(P, 12), asymmetry=ASYM), ratio=R)
    else:
        el = AsymmetricSlip(BreakAway(DiscreteIwan(P, 12), ratio=R), asymmetry=ASYM)
    assert el.law() == pytest.approx((R * (1 + ASYM), R * (1 - ASYM), 1 + ASYM, 1 - ASYM))
    np.testing.assert_allclose(el.force_history(u), _bank(u, d), rtol=0, atol=1e-9 * P.Fs)
    # the chain is not the sum of the two effects alone: the laws multiply
    alone = (
        AsymmetricSlip(DiscreteIwan(P, 12), asymmetry=ASYM).force_history(u)
        + BreakAway(DiscreteIwan(P, 12), ratio=R).force_history(u)
        - DiscreteIwan(P, 12).force_history(u)
    )
    assert np.max(np.abs(alone - _bank(u, d))) > 0.05 * P.Fs


def test_dense_banks_converge_to_the_composed_element():
    u = _drive()
    F = BreakAway(AsymmetricSlip(IwanJoint(P), asymmetry=ASYM), ratio=R).force_history(u)
    errs = [
        float(np.sqrt(np.mean((_bank(u, DiscreteIwan(P, n)) - F) ** 2))) / P.Fs
        for n in (100, 400, 1600)
    ]
    # about first order in 1/n (a slider breaks one sample early or late), not smoothly:
    # whether the spike breaks in a half cycle flips with the discretisation
    assert errs[0] > errs[1] > errs[2] and errs[0] / errs[2] > 6.0, errs
    assert errs[2] < 3e-3, errs


def test_energy_balance_of_the_chain():
    u = A * np.array([0.0, 0.7, -0.3, 1.2, 0.5, 2.0, -1.4, 0.1, -0.2])
    uf = np.concatenate(
        [np.linspace(a, b, 3000, endpoint=False) for a, b in zip(u[:-1], u[1:])] + [u[-1:]]
    )
    el = AsymmetricSlip(BreakAway(IwanJoint(P), ratio=R), asymmetry=-ASYM)
    F, D = np.empty(uf.size), np.empty(uf.size)
    for i, x in enumerate(uf):
        F[i] = el.trial(x)[0]
        el.commit()
        D[i] = el.dissipated_energy
    assert np.all(np.diff(D) >= -1e-12 * P.Fs * A)
    assert el.work == pytest.approx(el.stored_energy + el.dissipated_energy, rel=1e-12)
    trap = float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(uf)))
    # each break of the spike is a jump inside one step (the trapezoid misses up to half)
    jump = (P.KT - P.KT / (1 + P.beta)) * R * (1 + ASYM) * A
    assert abs(el.work - trap) < 8 * jump * A * 2.0 / 3000


def test_run_route_of_the_evaluator_is_the_element():
    rng = np.random.default_rng(3)
    u = np.concatenate([_drive(30), np.cumsum(rng.normal(size=300)) * 0.2 * A])
    keep = np.arange(0, u.size, 3)
    ev = Evaluator(u, np.zeros_like(u), keep, np.arange(u.size), tol=1e-12 * A)
    names = ("asymmetric_slip", "breakaway")
    assert ev.fast(names) and not ev.fast(("slip_degradation", "breakaway"))
    p1 = IwanParameters(1.0, P.KT / P.Fs, P.chi, P.beta)
    F = ev.unit_force((p1.phi_max, p1.chi, p1.beta), names, ({"asymmetry": ASYM}, {"ratio": R}))
    F_el = BreakAway(AsymmetricSlip(IwanJoint(p1), asymmetry=ASYM), ratio=R).force_history(u)
    np.testing.assert_allclose(F, F_el[keep], rtol=0, atol=1e-10)


def test_slip_degradation_does_not_compose():
    with pytest.raises(ValueError, match="plain Iwan joint"):
        BreakAway(SlipDegradation(IwanJoint(P), rate=1.0), ratio=1.5)
    with pytest.raises(ValueError, match="plain Iwan joint"):
        SlipDegradation(AsymmetricSlip(IwanJoint(P), asymmetry=0.1), rate=1.0)
