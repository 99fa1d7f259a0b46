"""The multi-contact interface (issue 15 items 2-3, issue 12's lap joint): one vectorised
commit per step, exact against one Python-law connector per point, energy balance, records."""

from __future__ import annotations

import gc
import math
import tracemalloc

import exudyn as exu
import numpy as np
import pytest
from _connector_models import Chain, settings
from exudyn.itemInterface import (
    CoordinateConstraint,
    LoadForceVector,
    MarkerBodyPosition,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    MassPoint,
    NodePoint,
    NodePoint2DSlope1,
    NodePointGround,
    ObjectANCFCable2D,
    ObjectConnectorCartesianSpringDamper,
    ObjectGround,
)

from iwan_element import DiscreteIwan, IwanJoint, IwanJointBank, IwanParameters
from iwan_element.exudyn import IwanInterface, add_iwan_connector, add_iwan_interface, record_energy

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
PARAMS = [
    IwanParameters(
        Fs=800.0 + 100.0 * k, KT=1e6 * (1.0 + 0.2 * k), chi=-0.5 + 0.1 * k, beta=0.2 + 0.3 * k
    )
    for k in range(4)
]


def _chain(n, *, interface: bool, record=True, law="python", post_step=None, **kw):
    chain = Chain([1.0] * n, v0=[3.0 * (k + 1) / n for k in range(n)])
    if post_step is not None:
        chain.mbs.SetPostStepUserFunction(post_step)
    params = [PARAMS[k % len(PARAMS)] for k in range(n)]
    pairs = [(chain.marker(k - 1), chain.marker(k)) for k in range(n)]
    if interface:
        handle = add_iwan_interface(chain.mbs, pairs, params, record=record, **kw)
    else:
        handle = [
            add_iwan_connector(chain.mbs, list(pr), IwanJoint(p), law=law)
            for pr, p in zip(pairs, params)
        ]
    return chain, handle


def test_interface_equals_one_python_law_connector_per_point():
    n, steps = 6, 3000
    chain, iface = _chain(n, interface=True)
    chain.solve(settings(1e-5, steps))
    ref_chain, conns = _chain(n, interface=False)
    ref_chain.solve(settings(1e-5, steps))
    assert isinstance(iface, IwanInterface) and iface.route == "symbolic"
    u_ref = np.stack([c.slip_history for c in conns], axis=1)
    F_ref = np.stack([c.force_history for c in conns], axis=1)
    amp = np.max(np.abs(u_ref))
    assert iface.slip_history.shape == (steps + 1, n)
    assert np.max(np.abs(iface.slip_history - u_ref)) <= 1e-9 * amp
    assert np.max(np.abs(iface.force_history - F_ref)) <= 1e-9 * max(p.Fs for p in PARAMS)
    np.testing.assert_allclose(
        iface.dissipated_energy_history, sum(c.dissipated_energy_history for c in conns), rtol=1e-9
    )
    np.testing.assert_array_equal(iface.time_history, conns[0].time_history)
    assert len(iface.overflow_times) == 0
    assert np.max(np.abs(iface.slip_history)) > min(p.phi_max for p in PARAMS)  # macroslip


def test_interface_energy_balance_closes():
    """Kinetic energy + stored + dissipated = initial kinetic energy (no other forces)."""
    n = 5
    kinetic = []
    holder = {}

    def post_step(mbs, t):
        v = [mbs.GetNodeOutput(nd, exu.OutputVariableType.Coordinates_t) for nd in holder["nodes"]]
        kinetic.append(0.5 * float(np.sum(np.square(v))))
        return True

    chain, iface = _chain(n, interface=True, post_step=post_step)
    holder["nodes"] = chain.nodes
    chain.solve(settings(1e-5, 4000, rel_tol=1e-12))
    rec = iface.records()
    total = np.array(kinetic) + rec["stored_energy"] + rec["dissipated_energy"]
    e0 = kinetic[0]
    assert rec["dissipated_energy"][-1] > 0.05 * e0
    assert np.max(np.abs(total - e0)) < 1e-3 * e0
    np.testing.assert_allclose(
        rec["work"], rec["stored_energy"] + rec["dissipated_energy"], rtol=1e-12, atol=1e-12 * e0
    )


def test_reset_repeats_the_run_and_record_false_stores_nothing():
    chain, iface = _chain(3, interface=True)
    chain.solve(settings(1e-5, 500))
    first = iface.records()
    iface.reset()
    assert iface.n_records == 0
    chain.solve(settings(1e-5, 500))
    second = iface.records()
    for key in first:
        np.testing.assert_array_equal(first[key], second[key])
    chain, quiet = _chain(3, interface=True, record=False)
    chain.solve(settings(1e-5, 500))
    assert quiet.n_records == 0 and quiet.slip_history.shape == (0, 3)


def _forced_oscillators(n, steps, record):
    chain = Chain([1.0] * n)
    for k in range(n):
        chain.spring(-1, k, 2e5)
        chain.harmonic_force(k, 1500.0 * (1.0 + 0.1 * k), 700.0)
    iface = add_iwan_interface(
        chain.mbs, [(chain.marker(-1), chain.marker(k)) for k in range(n)], [P] * n, record=record
    )
    chain.mbs.Assemble()
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    chain.mbs.SolveDynamic(settings(1e-5, steps))
    gc.collect()
    kept = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    return kept, iface


def test_record_false_keeps_the_heap_bounded():
    """Issue 14: with record=False nothing grows per step (the joints' reversal stacks stay
    bounded in forced vibration); benchmarks/bench_memory.py runs the 1e6-step version."""
    short, _ = _forced_oscillators(2, 400, record=False)
    long_, iface = _forced_oscillators(2, 1600, record=False)
    assert iface.n_records == 0
    assert long_ - short < 4 * 1024  # < 3.4 B/step over 1200 steps
    recorded, _ = _forced_oscillators(2, 1600, record=True)
    assert recorded - long_ > 1600 * 2 * 8  # records do take memory


def test_position_markers_with_an_oblique_axis_equal_the_python_law():
    a = np.array([0.6, 0.8, 0.0])
    results = []
    for use_interface in (True, False):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        pairs = []
        for k in range(3):
            nd = mbs.AddNode(NodePoint(initialVelocities=list((2.0 + k) * a)))
            body = mbs.AddObject(MassPoint(nodeNumber=nd, mass=1.0))
            m0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[k, 0, 0]))
            m1 = (
                mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
                if k == 2
                else mbs.AddMarker(MarkerBodyPosition(bodyNumber=body))
            )
            mbs.AddObject(
                ObjectConnectorCartesianSpringDamper(
                    markerNumbers=[m0, m1], stiffness=[0.0, 0.0, 1e5]
                )
            )
            pairs.append((m0, m1))
        if use_interface:
            h = add_iwan_interface(mbs, pairs, [P] * 3, axis=a)
            slips = lambda h=h: h.slip_history  # noqa: E731
        else:
            cs = [
                add_iwan_connector(mbs, list(pr), IwanJoint(P), axis=a, law="python")
                for pr in pairs
            ]
            slips = lambda cs=cs: np.stack([c.slip_history for c in cs], axis=1)  # noqa: E731
        mbs.Assemble()
        mbs.SolveDynamic(settings(1e-5, 2000))
        results.append(slips())
    amp = np.max(np.abs(results[1]))
    assert amp > P.phi_max
    assert np.max(np.abs(results[0] - results[1])) <= 1e-9 * amp


def _ancf_strip(use_interface):
    """A cantilever ANCF strip whose lower surface sticks to ground through 3 joints (surface
    markers are not affine in the coordinates: the slip is read through Exudyn)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    L, n_el, h = 0.4, 4, 0.01
    EI, EA, rhoA = 50.0, 2e6, 0.8
    le = L / n_el
    nodes = [
        mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * le, 0.0, 1.0, 0.0]))
        for i in range(n_el + 1)
    ]
    elems = [
        mbs.AddObject(
            ObjectANCFCable2D(
                massPerLength=rhoA,
                bendingStiffness=EI,
                axialStiffness=EA,
                length=le,
                nodeNumbers=[nodes[i], nodes[i + 1]],
            )
        )
        for i in range(n_el)
    ]
    gnode = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=gnode, coordinate=0))
    for c in range(4):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mc]))
    ground = mbs.AddObject(ObjectGround())
    pairs = []
    for x in (0.15, 0.25, 0.35):
        e = int(x / le)
        m_beam = mbs.AddMarker(
            MarkerBodyPosition(bodyNumber=elems[e], localPosition=[x - e * le, -0.5 * h, 0.0])
        )
        m_ground = mbs.AddMarker(
            MarkerBodyPosition(bodyNumber=ground, localPosition=[x, -0.5 * h, 0.0])
        )
        pairs.append((m_ground, m_beam))
    tip = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mbs.AddLoad(
        LoadForceVector(
            markerNumber=tip,
            loadVectorUserFunction=lambda mbs_, t, load: [0.0, 40.0 * math.sin(300.0 * t), 0.0],
        )
    )
    params = [IwanParameters(Fs=20.0, KT=2e5, chi=-0.5, beta=0.3)] * 3
    if use_interface:
        h_ = add_iwan_interface(mbs, pairs, params, axis=[1.0, 0.0, 0.0])
        get = lambda: h_.slip_history  # noqa: E731
    else:
        cs = [
            add_iwan_connector(mbs, list(pr), IwanJoint(p), axis=[1, 0, 0], law="python")
            for pr, p in zip(pairs, params)
        ]
        get = lambda: np.stack([c.slip_history for c in cs], axis=1)  # noqa: E731
    mbs.Assemble()
    mbs.SolveDynamic(settings(4e-5, 400, rel_tol=1e-9, abs_tol=1e-6))
    return get(), params


def test_beam_surface_markers_equal_the_python_law():
    (u_if, params), (u_py, _) = _ancf_strip(True), _ancf_strip(False)
    amp = np.max(np.abs(u_py))
    assert amp > 0.2 * params[0].phi_max  # the joints do work
    assert np.max(np.abs(u_if - u_py)) <= 1e-9 * amp


def test_protocol_elements_take_the_python_route():
    chain = Chain([1.0, 1.0], v0=[1.0, 2.0])
    elems = [DiscreteIwan(P, 20), DiscreteIwan(P, 20)]
    iface = add_iwan_interface(
        chain.mbs, [(chain.marker(-1), chain.marker(0)), (chain.marker(0), chain.marker(1))], elems
    )
    chain.solve(settings(1e-5, 300))
    assert iface.route == "python" and len(iface.connectors) == 2
    assert iface.slip_history.shape == (301, 2)
    replay = elems[0].__class__(P, 20)
    forces = []
    for u in iface.slip_history[:, 0]:
        forces.append(replay.trial(u)[0])
        replay.commit()
    np.testing.assert_allclose(iface.force_history[:, 0], forces, rtol=0, atol=1e-9 * P.Fs)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(joints=[P]), "joints must be a sequence of 2 items"),
        (dict(pairs=[]), "at least one"),
        (dict(pairs=[(0,)]), r"markerPairs\[0\] must be a pair"),
        (dict(joints=[P, "x"]), r"joints\[1\]"),
        (dict(depth=1), "depth must be an int in"),
        (dict(offsets=[0.0]), "offsets must have 2 entries"),
        (dict(offsets=[0.0, math.nan]), r"offsets\[1\]"),
        (dict(axis=[1, 0, 0]), "apply to position markers only"),
        (dict(record=1), "record must be True or False"),
    ],
)
def test_bad_arguments_are_refused_with_the_argument_named(kw, match):
    chain = Chain([1.0, 1.0])
    pairs = kw.pop(
        "pairs", [(chain.marker(-1), chain.marker(0)), (chain.marker(0), chain.marker(1))]
    )
    joints = kw.pop("joints", [P, P])
    with pytest.raises(ValueError, match=match):
        add_iwan_interface(chain.mbs, pairs, joints, **kw)


def test_mixed_marker_kinds_and_missing_axis_are_refused():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    nd = mbs.AddNode(NodePoint())
    body = mbs.AddObject(MassPoint(nodeNumber=nd, mass=1.0))
    p0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground))
    p1 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body))
    c1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nd, coordinate=0))
    with pytest.raises(ValueError, match="axis is required"):
        add_iwan_interface(mbs, [(p0, p1)], [P])
    with pytest.raises(ValueError, match=r"markerPairs\[0\] must be two coordinate markers"):
        add_iwan_interface(mbs, [(p0, c1)], [P], axis=[1, 0, 0])


def test_an_element_used_twice_is_refused():
    chain = Chain([1.0, 1.0])
    j = IwanJoint(P)
    with pytest.raises(ValueError, match="already attached"):
        add_iwan_interface(
            chain.mbs,
            [(chain.marker(-1), chain.marker(0)), (chain.marker(0), chain.marker(1))],
            [j, j],
        )


def test_post_step_function_set_after_the_interface_is_chained():
    chain, iface = _chain(2, interface=True)
    calls = []
    chain.mbs.SetPostStepUserFunction(lambda mbs, t: calls.append(t) or True)
    chain.solve(settings(1e-5, 50))
    assert len(calls) == 51 and iface.n_records == 51


def test_bank_equals_separate_joints_on_random_histories():
    rng = np.random.default_rng(11)
    bank = IwanJointBank(PARAMS)
    joints = [IwanJoint(p) for p in PARAMS]
    u = (
        np.cumsum(rng.normal(size=(2000, 4)), axis=0) * 2e-4
        + 3e-3 * np.sin(np.linspace(0.0, 40.0, 2000))[:, None]
    )
    for row in u:
        bank.commit(row)
        for j, x in zip(joints, row):
            j.trial(x)
            j.commit()
        assert np.max(np.abs(bank.force - [j.force for j in joints])) <= 1e-12 * 1e3
    np.testing.assert_allclose(bank.work, [j.work for j in joints], rtol=1e-11)
    np.testing.assert_allclose(
        bank.dissipated_energy, [j.dissipated_energy for j in joints], rtol=1e-11
    )
    assert [bank.depth(i) for i in range(4)] == [j.reversal_depth for j in joints]
    np.testing.assert_allclose(bank.force_history(u)[-1], bank.force, rtol=0, atol=1e-12)


def test_bank_keeps_tiny_reversals_and_the_joint_tolerance_bound():
    """The bank walks reversals like IwanJoint: by signs, not products (the product of two
    differences of ~1e-160 m underflows and lost the reversal), and with the joint's bound on
    reversal_tol (a larger tolerance erases real reversals)."""
    p = IwanParameters(Fs=1.0, KT=1e160, chi=-0.5, beta=0.2)  # phi_max = 2.25e-160 m
    j, bank = IwanJoint(p), IwanJointBank([p])
    for r in (0.3, 0.3 + 1e-7, 0.3 - 1e-7, -0.1, 0.25, -0.2, 0.1):
        j.trial(r * p.phi_max)
        j.commit()
        bank.commit(np.array([r * p.phi_max]))
        assert bank.force[0] == pytest.approx(j.force, rel=1e-12, abs=0.0)
    with pytest.raises(ValueError, match="reversal_tol"):
        IwanJointBank([P], reversal_tol=1e-3)


def _two_tone(n, *, interface, amplitude=1.0):
    """n oscillators on a joint and a spring to ground, each driven by its own two-frequency
    force: the points reverse at different steps and close inner loops (the fast symbolic
    path and the lazy bank must hand every such step to the exact law)."""
    chain = Chain([1.0] * n)
    for k in range(n):
        chain.spring(-1, k, 2e5)
        chain.harmonic_force(k, amplitude * 1400.0 * (1.0 + 0.15 * k), 700.0 * (1.0 + 0.07 * k))
        chain.harmonic_force(k, amplitude * 600.0, 4100.0 + 300.0 * k)
    params = [PARAMS[k % len(PARAMS)] for k in range(n)]
    pairs = [(chain.marker(-1), chain.marker(k)) for k in range(n)]
    if interface:
        handle = add_iwan_interface(chain.mbs, pairs, params)
    else:
        handle = [
            add_iwan_connector(chain.mbs, list(pr), IwanJoint(p), law="python")
            for pr, p in zip(pairs, params)
        ]
    chain.mbs.Assemble()
    return chain, handle, params


def _events(u, p):
    """(steps with a new reversal point, steps that closed a loop) of an IwanJoint driven
    through the slips ``u``."""
    j = IwanJoint(p)
    rev, closed = [], []
    for k, x in enumerate(u):
        d0 = j.reversal_depth
        j.trial(float(x))
        j.commit()
        if j.reversal_depth > d0:
            rev.append(k)
        elif j.reversal_depth < d0:
            closed.append(k)
    return rev, closed


def test_points_reversing_at_different_steps_and_closing_inner_loops_equal_the_python_law():
    n, steps = 4, 1500
    chain, iface, params = _two_tone(n, interface=True, amplitude=0.15)  # microslip loops
    chain.mbs.SolveDynamic(settings(3e-5, steps))
    ref, conns, _ = _two_tone(n, interface=False, amplitude=0.15)
    ref.mbs.SolveDynamic(settings(3e-5, steps))
    u_ref = np.stack([c.slip_history for c in conns], axis=1)
    amp = np.max(np.abs(u_ref))
    assert np.max(np.abs(iface.slip_history - u_ref)) <= 1e-9 * amp
    F_ref = np.stack([c.force_history for c in conns], axis=1)
    assert np.max(np.abs(iface.force_history - F_ref)) <= 1e-9 * max(p.Fs for p in params)
    ev = [_events(u_ref[:, k], params[k]) for k in range(n)]
    first = [e[0][:3] for e in ev]
    assert len({tuple(f) for f in first}) == n  # each point reverses on its own steps
    assert sum(len(e[1]) for e in ev) >= n  # inner loops were closed
    assert amp < max(p.phi_max for p in params)  # ... in microslip
    assert len(iface.overflow_times) == 0


def test_reset_between_different_solves_equals_a_fresh_interface():
    n, steps = 3, 800
    chain, iface, _ = _two_tone(n, interface=True)
    chain.mbs.SolveDynamic(settings(1e-5, steps))
    iface.reset()
    chain.mbs.SolveDynamic(settings(5e-6, 2 * steps))  # another run, other step
    again = iface.records()
    assert len(iface.overflow_times) == 0  # every step of the new run exact
    fresh_chain, fresh, _ = _two_tone(n, interface=True)
    fresh_chain.mbs.SolveDynamic(settings(5e-6, 2 * steps))
    want = fresh.records()
    assert np.max(np.abs(want["slip"])) > min(p.phi_max for p in PARAMS[:n]) * 0.1
    for key in want:
        np.testing.assert_allclose(
            again[key], want[key], rtol=0, atol=1e-12 * np.max(np.abs(want[key])) + 1e-300
        )


def test_records_read_during_the_run_equal_records_read_once():
    """The forces and energies are replayed from the recorded slips when read; reading them
    during the run (incremental replay) gives what one read at the end gives."""
    seen = []
    holder = {}

    def post_step(mbs, t):
        if "iface" in holder and holder["iface"].n_records % 97 == 5:
            seen.append(holder["iface"].dissipated_energy_history[-1])
        return True

    chain, iface = _chain(3, interface=True, post_step=post_step)
    holder["iface"] = iface
    chain.solve(settings(1e-5, 1500))
    once_chain, once = _chain(3, interface=True)
    once_chain.solve(settings(1e-5, 1500))
    assert len(seen) >= 10 and seen[-1] > 0.0
    a, b = iface.records(), once.records()
    for key in b:
        np.testing.assert_array_equal(a[key], b[key])
    idx = [k - 1 for k in range(1, iface.n_records + 1) if k % 97 == 5][: len(seen)]  # row k-1
    np.testing.assert_array_equal(np.array(seen), b["dissipated_energy"][idx])


def test_springs_carried_by_the_interface_equal_built_in_springs():
    """``stiffness`` puts linear springs along the global axes into the joints' own objects:
    the trajectory equals the same model with built-in Cartesian springs (to round-off), and
    linear_energy equals Exudyn's potential energy of those springs; the Python route adds
    built-in springs instead, with the same result."""
    a = np.array([0.6, 0.8, 0.0])
    k = [[2e5, 0.0, 1e5], [0.0, 3e5, 1e5], [1e5, 1e5, 0.0]]
    results, energies, balances = [], [], []
    for variant in ("builtin", "carried", "python"):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.AddObject(ObjectGround())
        pairs, springs = [], []
        for i in range(3):
            v0 = list((2.0 + i) * a + np.array([0.0, 0.0, 0.5]))
            nd = mbs.AddNode(NodePoint(initialVelocities=v0))
            mbs.AddObject(MassPoint(nodeNumber=nd, mass=1.0))
            m0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[i, 0, 0]))
            m1 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
            if variant == "builtin":
                springs.append(
                    mbs.AddObject(
                        ObjectConnectorCartesianSpringDamper(markerNumbers=[m0, m1], stiffness=k[i])
                    )
                )
            pairs.append((m0, m1))
        joints = [IwanJoint(P) for _ in range(3)] if variant == "python" else [P] * 3
        h = add_iwan_interface(
            mbs, pairs, joints, axis=a, stiffness=None if variant == "builtin" else k
        )
        assert h.route == ("python" if variant == "python" else "symbolic")
        if variant == "carried":
            assert mbs.systemData.NumberOfObjects() == 7  # ground, 3 masses, 3 joints
        rec = record_energy(mbs, h)
        mbs.Assemble()
        mbs.SolveDynamic(settings(1e-5, 2000))
        balances.append(rec.balance())
        if variant == "carried":  # the overflow probe sees the joint alone
            u, F = h.slip_history[-1], h.force_history[-1]
            for i, st in enumerate(h._states):
                assert abs(st.probe(float(u[i])) - F[i]) <= 1e-9 * P.Fs
        results.append(h.slip_history)
        if variant == "builtin":
            energies.append(
                sum(mbs.GetObjectOutput(s, exu.OutputVariableType.PotentialEnergy) for s in springs)
            )
        else:
            energies.append(h.linear_energy())
    amp = np.max(np.abs(results[0]))
    assert amp > P.phi_max
    for r in results[1:]:
        assert np.max(np.abs(r - results[0])) <= 1e-9 * amp
    assert energies[0] > 0.0
    for e in energies[1:]:
        assert e == pytest.approx(energies[0], rel=1e-9)
    # the energy balance books each spring once, whoever carries it, and closes
    for bal in balances:
        assert bal.success, bal.report()
        assert np.allclose(bal.elastic, balances[0].elastic, rtol=1e-8, atol=1e-12)


def test_bad_stiffness_is_refused_with_the_argument_named():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddObject(ObjectGround())
    nd = mbs.AddNode(NodePoint())
    mbs.AddObject(MassPoint(nodeNumber=nd, mass=1.0))
    m0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground))
    m1 = mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
    for bad, match in (
        ([[1.0, 2.0]], "shape"),
        ([[1.0, -2.0, 0.0]], ">= 0"),
        ([[1.0, math.nan, 0.0]], "finite"),
        ("x", "stiffness"),
    ):
        with pytest.raises(ValueError, match=match):
            add_iwan_interface(mbs, [(m0, m1)], [P], axis=[1, 0, 0], stiffness=bad)
    chain = Chain([1.0])
    with pytest.raises(ValueError, match="stiffness applies to position markers"):
        add_iwan_interface(
            chain.mbs, [(chain.marker(-1), chain.marker(0))], [P], stiffness=[[1.0, 0.0, 0.0]]
        )


def test_a_second_solve_of_an_interface_starts_a_fresh_history():
    chain, iface = _chain(4, interface=True)
    sim = settings(1e-5, 1500)
    chain.solve(sim)
    first = iface.records()
    assert np.max(np.abs(first["slip"])) > 0 and first["dissipated_energy"][-1] > 0
    chain.mbs.SolveDynamic(sim)  # no reset(): fresh by itself
    second = iface.records()
    for key in first:
        np.testing.assert_array_equal(first[key], second[key])
