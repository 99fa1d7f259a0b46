"""The slim per-step path of the symbolic connector (issue 15): the joint committed lazily
along a branch, records replayed, and steps that need more reversal points than the law
holds re-solved exactly. Every case is compared with the Python law (the reference route,
``joint.trial`` in the force function, committed at every step)."""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
import pytest
from _connector_models import Chain, settings

from iwan_element import IwanJoint, IwanParameters

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)


def _multisine(chain, rng, n=6):
    """A random multi-sine force: a random history with nested loops."""
    for f0, w in zip(rng.uniform(200.0, 1500.0, n), rng.uniform(300.0, 9000.0, n)):
        chain.harmonic_force(0, float(f0), float(w))


def _run(law, *, seed=3, n=3000, h=5e-5, depth=8, record=True):
    chain = Chain([1.0])
    chain.spring(-1, 0, 1e5)
    _multisine(chain, np.random.default_rng(seed))
    conn = chain.joint(-1, 0, IwanJoint(P), law=law, depth=depth, record=record)
    chain.solve(settings(h, n))
    return chain, conn


def _same_joint(a, b):
    ua, Fa = a.reversal_points()
    ub, Fb = b.reversal_points()
    np.testing.assert_allclose(ua, ub, rtol=0, atol=1e-9 * P.phi_max)
    np.testing.assert_allclose(Fa, Fb, rtol=0, atol=1e-9 * P.Fs)
    assert abs(a.displacement - b.displacement) <= 1e-9 * P.phi_max
    assert abs(a.force - b.force) <= 1e-9 * P.Fs
    assert a.dissipated_energy == pytest.approx(b.dissipated_energy, rel=1e-9, abs=1e-15)
    assert a.work == pytest.approx(b.work, rel=1e-9, abs=1e-15)


def test_steps_beyond_the_law_depth_are_re_solved_exactly():
    """Depth 2 on a random history: many steps close loops beyond the two points held; each
    is re-solved (post-Newton discontinuous iteration) and the trajectory equals the Python
    law. (Before: such steps were only listed, the trajectory drifted.)"""
    _, py = _run("python", depth=2)
    _, sym = _run("symbolic", depth=2)
    amp = np.max(np.abs(py.slip_history))
    assert sym.joint.reversal_depth > 2 or sym._n_resolved > 0
    assert sym._n_resolved > 0  # the case was exercised
    assert len(sym.overflow_times) == 0
    assert np.max(np.abs(sym.slip_history - py.slip_history)) <= 1e-9 * amp
    assert np.max(np.abs(sym.force_history - py.force_history)) <= 1e-9 * P.Fs
    _same_joint(sym.joint, py.joint)


@pytest.mark.parametrize("record", [True, False])
def test_lazy_joint_ends_every_run_in_the_python_law_state(record):
    """Nested inner loops: the joint (committed lazily along branches) ends in the state of
    the joint committed at every step, with records on or off."""
    _, py = _run("python", seed=5)
    _, sym = _run("symbolic", seed=5, record=record)
    j = sym._joint  # the caller's reference, not the property
    _same_joint(j, py.joint)
    assert sym.n_records == (py.n_records if record else 0)


def test_records_equal_a_per_step_commit():
    """Records are (t, u) replayed on a copy of the joint: equal to committing every
    accepted slip in turn, and to the Python law's records."""
    _, py = _run("python", seed=8, n=1500)
    _, sym = _run("symbolic", seed=8, n=1500)
    rec = sym.records()
    np.testing.assert_array_equal(rec["force"], IwanJoint(P).force_history(rec["slip"]))
    for key in ("force", "dissipated_energy", "work"):
        np.testing.assert_allclose(rec[key], py.records()[key], rtol=1e-9, atol=1e-9)


def test_reversal_exactly_at_a_step_and_two_solves_in_a_row():
    """Prescribed slip with reversals exactly at step times, solved as two consecutive runs
    (the second continues from the first): the joint's history equals the per-step commit
    of the same slips."""
    h = 1e-4
    s = 2.0 * P.phi_max
    knots = np.array([0.0, 1.0, 0.3, 0.7, 0.5, -0.2, 0.6]) * s
    times = np.arange(len(knots)) * 10 * h  # kinks at step times
    chain = Chain([1.0])
    chain.prescribe(0, lambda t: float(np.interp(t, times, knots)))
    conn = chain.joint(-1, 0, IwanJoint(P))
    n1 = 25
    sim = settings(h, n1)
    chain.solve(sim)
    mid = IwanJoint(P).force_history(conn.slip_history)[-1]
    assert conn.joint.force == pytest.approx(mid, abs=1e-9 * P.Fs)
    sim2 = settings(h, len(times) * 10 - 10 - n1)
    sim2.timeIntegration.startTime = n1 * h
    sim2.timeIntegration.endTime = times[-1]
    sd = chain.mbs.systemData  # continue from the end of run 1
    sd.SetODE2Coordinates(sd.GetODE2Coordinates(), configuration=exu.ConfigurationType.Initial)
    sd.SetODE2Coordinates_t(sd.GetODE2Coordinates_t(), configuration=exu.ConfigurationType.Initial)
    chain.mbs.SolveDynamic(sim2)
    u = conn.slip_history
    assert conn.time_history[-1] == pytest.approx(times[-1])
    np.testing.assert_allclose(u, np.interp(conn.time_history, times, knots), atol=1e-12 * s)
    ref = IwanJoint(P)
    F = ref.force_history(u)
    for x in u:
        ref.trial(x)
        ref.commit()
    np.testing.assert_array_equal(conn.force_history, F)
    _same_joint(conn.joint, ref)
    assert ref.reversal_depth >= 2


def test_reset_between_solves_repeats_the_run_and_a_reader_during_the_run_sees_each_step():
    chain = Chain([1.0])
    chain.spring(-1, 0, 1e5)
    _multisine(chain, np.random.default_rng(11), n=4)
    conn = chain.joint(-1, 0, IwanJoint(P))
    seen = []

    def reader(mbs, t):  # a post-step function set after: chained, reads the joint
        seen.append((conn.joint.displacement, conn.joint.force))
        return True

    chain.solve(settings(5e-5, 800))
    first = conn.records()
    state1 = (conn.joint.displacement, conn.joint.work)
    conn.reset()
    chain.mbs.SetPostStepUserFunction(reader)
    chain.mbs.SolveDynamic(settings(5e-5, 800))
    second = conn.records()
    for key in first:
        np.testing.assert_array_equal(first[key], second[key])
    assert (conn.joint.displacement, conn.joint.work) == pytest.approx(state1, rel=1e-12)
    u, F = np.array(seen).T
    np.testing.assert_array_equal(u, second["slip"])
    np.testing.assert_allclose(F, second["force"], rtol=0, atol=1e-12 * P.Fs)
    assert math.isfinite(F[-1])
