"""Connector set-up: position markers and axes, validation, chaining, reset, the example."""

from __future__ import annotations

import logging
import math
import os
import subprocess
import sys
from pathlib import Path

import exudyn as exu
import numpy as np
import pytest
from _connector_models import Chain, settings
from exudyn.itemInterface import (
    CoordinateConstraint,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    MarkerNodePosition,
    Mass1D,
    MassPoint,
    Node1D,
    NodePoint,
    NodePointGround,
    NodeRigidBody2D,
    ObjectRigidBody2D,
    SensorNode,
)

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters
from iwan_element.exudyn import IwanConnector, add_iwan_connector

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
ROOT = Path(__file__).resolve().parents[1]


# ---------------------------------------------------------------------------- position markers
def _point_mass_system(v0, *, m=1.0):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    m_ground = mbs.AddMarker(MarkerNodePosition(nodeNumber=ground))
    node = mbs.AddNode(NodePoint(referenceCoordinates=[0.0, 0.0, 0.0], initialVelocities=list(v0)))
    body = mbs.AddObject(MassPoint(mass=m, nodeNumber=node))
    m_body = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body))
    return SC, mbs, node, m_ground, m_body


def _one_dof_slip(v_axis, h, n):
    chain = Chain([1.0], v0=[v_axis])
    conn = chain.joint(-1, 0, IwanJoint(P))
    chain.solve(settings(h, n))
    return conn.slip_history


def test_position_markers_with_global_axis_equal_the_coordinate_joint():
    a = np.array([1.0, 2.0, 2.0]) / 3.0
    b = np.array([2.0, -1.0, 0.0]) / math.sqrt(5.0)  # perpendicular to a
    h, n = 5e-5, 600
    SC, mbs, node, m_ground, m_body = _point_mass_system(3.0 * a + 0.5 * b)
    conn = add_iwan_connector(mbs, [m_ground, m_body], IwanJoint(P), axis=[1.0, 2.0, 2.0])
    assert conn.kind == "position" and np.allclose(conn.axis, a)
    mbs.Assemble()
    mbs.SolveDynamic(settings(h, n))
    reference = _one_dof_slip(3.0, h, n)
    assert np.max(np.abs(reference)) > P.phi_max
    assert np.max(np.abs(conn.slip_history - reference)) / np.max(np.abs(reference)) < 1e-9
    p_end = np.array(mbs.GetNodeOutput(node, exu.OutputVariableType.Position))
    assert p_end @ b == pytest.approx(0.5 * n * h, rel=1e-9)  # free motion across the axis
    assert p_end @ a == pytest.approx(conn.slip_history[-1], rel=1e-12)


def _rigid_frame(mbs, angle, rotation=None):
    """A 2-D rigid body held at ``angle`` (or ``angle + rotation(t)``) by constraints."""
    node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, angle]))
    body = mbs.AddObject(ObjectRigidBody2D(mass=1.0, inertia=1.0, nodeNumber=node))
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for i in range(3):
        mi = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=i))
        if i == 2 and rotation is not None:
            mbs.AddObject(
                CoordinateConstraint(
                    markerNumbers=[mg, mi], offsetUserFunction=lambda m, t, item, off: rotation(t)
                )
            )
        else:
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mg, mi]))
    return mbs.AddMarker(MarkerBodyRigid(bodyNumber=body))


def test_axis_in_a_rotated_body_frame_equals_the_rotated_global_axis():
    angle = 0.7
    a = np.array([math.cos(angle), math.sin(angle), 0.0])
    h, n = 5e-5, 400
    slips = []
    for attached in (False, True):
        SC, mbs, node, m_ground, m_body = _point_mass_system(3.0 * a)
        if attached:
            frame = _rigid_frame(mbs, angle)
            conn = add_iwan_connector(
                mbs, [m_ground, m_body], IwanJoint(P), axis=[1.0, 0.0, 0.0], axisMarker=frame
            )
        else:
            conn = add_iwan_connector(mbs, [m_ground, m_body], IwanJoint(P), axis=a)
        mbs.Assemble()
        mbs.SolveDynamic(settings(h, n))
        slips.append(conn.slip_history)
    assert np.max(np.abs(slips[0])) > P.phi_max
    assert np.max(np.abs(slips[1] - slips[0])) / np.max(np.abs(slips[0])) < 1e-9


def test_rotating_axis_slip_is_the_projection_on_the_current_axis():
    angle0, spin = 0.3, 20.0  # rad, rad/s
    SC, mbs, node, m_ground, m_body = _point_mass_system([2.0, 1.0, 0.0])
    frame = _rigid_frame(mbs, angle0, rotation=lambda t: spin * t)
    positions = []

    def user_post_step(mbs_, t):
        positions.append(mbs_.GetNodeOutput(node, exu.OutputVariableType.Position))
        return True

    conn = add_iwan_connector(
        mbs, [m_ground, m_body], IwanJoint(P), axis=[1.0, 0.0], axisMarker=frame
    )
    mbs.SetPostStepUserFunction(user_post_step)  # set after: chained automatically
    mbs.Assemble()
    mbs.SolveDynamic(settings(5e-5, 400))
    t = conn.time_history
    p = np.array(positions)
    axes = np.stack([np.cos(angle0 + spin * t), np.sin(angle0 + spin * t)], axis=1)
    projected = np.sum(p[:, :2] * axes, axis=1)
    assert len(p) == len(t)
    assert np.max(np.abs(conn.slip_history - projected)) < 1e-12 * max(
        1.0, np.max(np.abs(projected))
    )
    assert np.ptp(angle0 + spin * t) > 0.3  # the axis really turned


# ---------------------------------------------------------------------------- validation
@pytest.fixture()
def parts():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    n1 = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
    npnt = mbs.AddNode(NodePoint(referenceCoordinates=[0.0, 0.0, 0.0]))
    body = mbs.AddObject(MassPoint(mass=1.0, nodeNumber=npnt))
    rb_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0]))
    rb = mbs.AddObject(ObjectRigidBody2D(mass=1.0, inertia=1.0, nodeNumber=rb_node))
    d = dict(
        mbs=mbs,
        SC=SC,
        coord0=mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0)),
        coord1=mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=0)),
        pos0=mbs.AddMarker(MarkerNodePosition(nodeNumber=ground)),
        pos1=mbs.AddMarker(MarkerBodyPosition(bodyNumber=body)),
        rigid=mbs.AddMarker(MarkerBodyRigid(bodyNumber=rb)),
        body=body,
        node=n1,
    )
    return d


@pytest.mark.parametrize(
    "case, message",
    [
        (lambda d: dict(markerNumbers=[d["coord0"]]), "markerNumbers must be a list of two"),
        (
            lambda d: dict(markerNumbers=[d["coord0"], 99]),
            r"markerNumbers\[1\] = 99 is not a marker",
        ),
        (
            lambda d: dict(markerNumbers=[-1, d["coord1"]]),
            r"markerNumbers\[0\] = -1 is not a marker",
        ),
        (
            lambda d: dict(markerNumbers=["a", d["coord1"]]),
            r"markerNumbers\[0\] must be a marker number",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], 1.7]),
            r"markerNumbers\[1\] must be a marker number .*float",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], 2.0]),
            r"markerNumbers\[1\] must be a marker number .*float",
        ),
        (lambda d: dict(markerNumbers=[d["coord1"], d["coord1"]]), "two different markers"),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["pos1"]]),
            "two coordinate markers .* or two position",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["pos1"]]),
            "axis is required for position markers",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["pos1"]], axis=[0, 0, 0]),
            "axis must be a non-zero",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["pos1"]], axis=[1, 0, 0, 0]),
            "axis must be a finite vector",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["pos1"]], axis=[1, np.nan]),
            "axis must be a finite vector",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], axis=[1, 0, 0]),
            "apply to position markers only",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["pos1"]], axis=[1, 0], axisMarker=d["pos1"]),
            "axisMarker must be a marker with an orientation",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], joint=object()),
            "joint must follow",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], offset=math.nan),
            "offset must be finite",
        ),
        (
            lambda d: dict(
                markerNumbers=[d["coord0"], d["coord1"]], visualization={"colour": [1, 0, 0, 1]}
            ),
            "unknown visualization keys",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], record=1),
            "record must be True or False",
        ),
        (
            lambda d: dict(mbs=d["SC"], markerNumbers=[d["coord0"], d["coord1"]]),
            "mbs must be an exudyn.MainSystem",
        ),
        (
            lambda d: dict(markerNumbers=[d["pos0"], d["body"]], axis=[1, 0, 0]),
            r"markerNumbers\[1\] = .* is a body or object \(ObjectIndex\), but markers belong here",
        ),
        (
            lambda d: dict(markerNumbers=[d["node"], d["coord1"]]),
            r"markerNumbers\[0\] = .* is a node \(NodeIndex\), but markers belong here",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], damping=-1.0),
            r"damping must be in \[0, inf\)",
        ),
        (
            lambda d: dict(markerNumbers=[d["coord0"], d["coord1"]], offset=[0.1, 0, 0]),
            "offset must be a real number",
        ),
        (
            lambda d: dict(
                markerNumbers=[d["pos0"], d["pos1"]], axis=[1, 0, 0], offset=[0.1, math.nan, 0]
            ),
            "offset must be a number or a finite vector",
        ),
    ],
)
def test_invalid_set_up_raises_value_error_before_anything_is_added(parts, case, message):
    kw = case(parts)
    mbs = kw.pop("mbs", parts["mbs"])
    joint = kw.pop("joint", IwanJoint(P))
    n_objects = parts["mbs"].systemData.NumberOfObjects()
    with pytest.raises(ValueError, match=message):
        add_iwan_connector(mbs, kw.pop("markerNumbers"), joint, **kw)
    assert parts["mbs"].systemData.NumberOfObjects() == n_objects


def test_options_are_keyword_only_and_typos_are_rejected(parts):
    ms = [parts["coord0"], parts["coord1"]]
    with pytest.raises(TypeError):
        add_iwan_connector(parts["mbs"], ms, IwanJoint(P), None)  # axis positionally
    with pytest.raises(TypeError):
        add_iwan_connector(parts["mbs"], ms, IwanJoint(P), axsi=[1, 0, 0])  # misspelt keyword


def test_a_joint_instance_serves_one_connector_only(parts):
    j = IwanJoint(P)
    add_iwan_connector(parts["mbs"], [parts["coord0"], parts["coord1"]], j)
    with pytest.raises(ValueError, match="already attached"):
        add_iwan_connector(parts["mbs"], [parts["coord1"], parts["coord0"]], j)


def test_a_joint_instance_is_refused_by_a_second_system():
    """Issue 14: the same element in two systems would share its history."""
    j = IwanJoint(P)
    systems = []
    for _ in range(2):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        g = mbs.AddNode(NodePointGround())
        n = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
        mbs.AddObject(Mass1D(mass=1.0, nodeNumber=n))
        ms = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=k, coordinate=0)) for k in (g, n)]
        systems.append((SC, mbs, ms))
    conn = add_iwan_connector(systems[0][1], systems[0][2], j)
    with pytest.raises(ValueError, match="already attached"):
        add_iwan_connector(systems[1][1], systems[1][2], j)
    assert conn.joint is j


def test_visualization_and_name_reach_the_exudyn_object(parts):
    conn = add_iwan_connector(
        parts["mbs"],
        [parts["coord0"], parts["coord1"]],
        IwanJoint(P),
        name="boltJoint",
        visualization={"show": False, "drawSize": 0.01},
    )
    obj = parts["mbs"].GetObject(conn.objectNumber)
    assert obj["name"] == "boltJoint" and obj["Vshow"] is False
    assert obj["VdrawSize"] == pytest.approx(0.01, rel=1e-6)  # stored as float32
    assert obj["objectType"] == "ConnectorCoordinateSpringDamper"
    assert isinstance(conn, IwanConnector)
    assert conn.markerNumbers == (parts["coord0"], parts["coord1"])
    for attribute in ("offset", "joint", "axis", "markerNumbers", "objectNumber"):
        with pytest.raises(AttributeError):  # the set-up is read-only
            setattr(conn, attribute, None)


# ---------------------------------------------------------------------------- chaining, reset
@pytest.mark.parametrize("law", ["symbolic", "python"])
def test_post_step_function_set_after_the_connector_is_chained_by_the_next_solve(law):
    chain = Chain([1.0], v0=[3.0])
    conn = chain.joint(-1, 0, IwanJoint(P), law=law)
    calls = []
    chain.mbs.SetPostStepUserFunction(lambda mbs, t: calls.append(t) or True)
    chain.solve(settings(1e-4, 50))
    assert len(calls) == 51 and conn.n_records == 51
    replay = IwanJoint(P).force_history(conn.slip_history)
    assert np.max(np.abs(replay - conn.force_history)) < 1e-12 * P.Fs


def test_symbolic_route_refuses_records_when_its_post_step_was_replaced():
    """Without a solver stored in mbs.sys (storeSolver=False) nothing re-chains the
    dispatcher before the run, and the symbolic law has no Python call that could: the
    records are refused instead of returning an uncommitted history."""
    chain = Chain([1.0], v0=[3.0])
    conn = chain.joint(-1, 0, IwanJoint(P))
    assert conn.route == "symbolic"
    chain.mbs.SetPostStepUserFunction(lambda mbs, t: True)
    chain.mbs.Assemble()
    chain.mbs.SolveDynamic(settings(1e-4, 50), storeSolver=False)
    with pytest.raises(RuntimeError, match="post-step dispatcher was replaced"):
        _ = conn.slip_history


def test_post_step_function_set_after_the_connectors_is_chained_and_can_stop_the_run():
    chain = Chain([1.0], v0=[3.0])
    conn = chain.joint(-1, 0, IwanJoint(P), law="python")
    seen = []

    def user_post_step(mbs, t):
        seen.append((t, conn.time_history[-1]))
        return t < 0.01 - 1e-12  # stop after t = 0.01

    chain.mbs.SetPostStepUserFunction(user_post_step)
    chain.solve(settings(1e-4, 400))
    assert chain.mbs.systemData.GetTime() == pytest.approx(0.01, rel=1e-9)
    assert len(seen) == 101 and all(t == tc for t, tc in seen)
    assert conn.n_records == 101


def test_user_function_that_calls_the_previous_one_by_hand_does_not_commit_twice():
    chain = Chain([1.0], v0=[3.0])
    conn = chain.joint(-1, 0, IwanJoint(P), law="python")
    got = chain.mbs.GetPostStepUserFunction()
    previous = got["function"] if isinstance(got, dict) else got
    calls = [0]

    def user_post_step(mbs, t):
        calls[0] += 1
        return previous(mbs, t)

    chain.mbs.SetPostStepUserFunction(user_post_step)
    chain.solve(settings(1e-4, 200))
    assert calls[0] == 201
    assert conn.n_records == 201 and np.all(np.diff(conn.time_history) > 0)


@pytest.mark.parametrize("law", ["symbolic", "python"])
def test_a_second_solve_starts_a_fresh_history_by_itself(caplog, law):
    """reset() gives an identical second run; a solve started again from t = 0 without it
    does the same by itself (the joint was virgin again before the first step: same records
    to the last bit, with either solver), and says so in the log."""
    chain = Chain([1.0], v0=[3.0])
    chain.spring(-1, 0, 2e5)
    element = IwanJoint(P) if law == "symbolic" else DiscreteIwan(P, 20)
    conn = chain.joint(-1, 0, element)
    assert conn.route == law
    sim = settings(1e-4, 300)
    runs = {}
    for solver in (exu.DynamicSolverType.GeneralizedAlpha, exu.DynamicSolverType.RK44):
        chain.solve(sim, solver)
        first = conn.records()
        conn.reset()
        assert conn.n_records == 0 and conn.joint.dissipated_energy == 0.0
        chain.mbs.SolveDynamic(sim, solverType=solver)
        second = conn.records()
        caplog.clear()
        with caplog.at_level(logging.INFO, logger="iwan_element.exudyn"):
            chain.mbs.SolveDynamic(sim, solverType=solver)  # no reset()
        assert any("fresh history" in r.getMessage() for r in caplog.records), solver
        third = conn.records()
        for key in first:
            assert np.array_equal(first[key], second[key]), key
            assert np.array_equal(first[key], third[key]), key
        runs[solver] = first
    assert runs[exu.DynamicSolverType.RK44]["dissipated_energy"][-1] > 0


def test_a_second_solve_without_the_solver_hook_still_starts_afresh(caplog):
    """storeSolver=False: SolveDynamic does not announce itself; the restart is seen at its
    first step, the history starts again there, and the log says what that costs."""
    chain = Chain([1.0], v0=[3.0])
    chain.spring(-1, 0, 2e5)
    conn = chain.joint(-1, 0, IwanJoint(P))
    sim = settings(1e-4, 300)
    chain.solve(sim)
    first = conn.records()
    with caplog.at_level(logging.WARNING, logger="iwan_element.exudyn"):
        chain.mbs.SolveDynamic(sim, storeSolver=False)
    assert any("storeSolver" in r.getMessage() for r in caplog.records)
    second = conn.records()
    assert conn.n_records == 301 and second["time"][0] == 0.0 and second["force"][0] == 0.0
    # not exact: the first step's initial acceleration saw the old history (1.6 % measured)
    gap = np.max(np.abs(second["slip"] - first["slip"])) / np.max(np.abs(first["slip"]))
    assert 0.0 < gap < 0.05


def test_generic_route_equals_the_node_coordinate_shortcut():
    """Coordinate markers other than MarkerNodeCoordinate take the generic route (Exudyn
    evaluates the force at the accepted state); forced onto it, a run is unchanged."""
    results = []
    for generic in (False, True):
        chain = Chain([1.0], v0=[3.0])
        chain.spring(-1, 0, 2e5)
        conn = chain.joint(-1, 0, IwanJoint(P), law="python")
        if generic:
            conn._fast_nodes = None
        chain.solve(settings(1e-4, 300), exu.DynamicSolverType.RK44)
        assert (conn._read is None) == generic
        results.append(conn.records())
    for key in results[0]:
        assert np.array_equal(results[0][key], results[1][key]), key


# ---------------------------------------------------------------------------- example
def test_quickstart_example_runs():
    env = dict(os.environ, IWAN_QUICKSTART_STEPS="400")
    out = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "connector_quickstart.py")],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert "dissipated" in out.stdout and "peak slip" in out.stdout


# ---------------------------------------------------------------------------- offset
def test_offset_shifts_the_unloaded_position():
    d, h, n = 1e-3, 5e-5, 300
    runs = {}
    for offset in (0.0, d):
        chain = Chain([1.0], x0=[offset], v0=[3.0])
        conn = chain.joint(-1, 0, IwanJoint(P), offset=offset, law="python")
        positions = []
        chain.mbs.SetPostStepUserFunction(
            lambda mbs, t, positions=positions, chain=chain: (
                positions.append(
                    mbs.GetNodeOutput(chain.nodes[0], exu.OutputVariableType.Coordinates)
                )
                or True
            )
        )
        chain.solve(settings(h, n))
        runs[offset] = (conn.slip_history, np.array(positions))
    (u0, x0), (ud, xd) = runs[0.0], runs[d]
    assert conn.slip_history[0] == 0.0 and np.max(np.abs(u0)) > P.phi_max
    assert np.max(np.abs(ud - u0)) < 1e-12 * np.max(np.abs(u0)) + 1e-15
    assert np.allclose(xd - d, x0, rtol=0, atol=1e-12 * np.max(np.abs(x0)) + 1e-15)
    # position markers: the offset is measured along the axis
    a = np.array([0.6, 0.8, 0.0])
    for off in (-d, [0.0, 0.0, 5.0], -d * a + [0.8, -0.6, 2.0]):  # a vector: Exudyn's d0
        SC, mbs, node, m_ground, m_body = _point_mass_system(3.0 * a)
        conn = add_iwan_connector(mbs, [m_ground, m_body], IwanJoint(P), axis=a, offset=off)
        mbs.Assemble()
        mbs.SolveDynamic(settings(h, n))
        want = d if np.ndim(off) == 0 else -float(a @ off)  # u = a.(p1 - p0 - d0)
        assert conn.offset == pytest.approx(-want, rel=1e-12)
        assert conn.slip_history[0] == pytest.approx(want, rel=1e-12, abs=1e-15)
        assert conn.force_history[0] == pytest.approx(IwanJoint(P).trial(want)[0], rel=1e-12)


# ---------------------------------------------------------------------------- coordinate views
def test_continued_run_after_reassemble_reads_the_moved_coordinates():
    """The node-coordinate route reads the accepted state through views of Exudyn's
    coordinate vectors taken at the start of each run. A run continuing at the last
    accepted time, after items were added and the system re-assembled (which may move those
    vectors), must still commit exactly the accepted states."""
    chain = Chain([1.0], v0=[3.0])
    chain.spring(-1, 0, 2e5)
    conn = chain.joint(-1, 0, IwanJoint(P))
    h, n = 1e-4, 200
    chain.solve(settings(h, n))
    mbs = chain.mbs
    q_end = mbs.systemData.GetODE2Coordinates()
    v_end = mbs.systemData.GetODE2Coordinates_t()
    for _ in range(50):  # grow the coordinate vectors
        nd = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
        mbs.AddObject(Mass1D(mass=1.0, nodeNumber=nd))
    mbs.Assemble()
    q0 = mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Initial)
    v0 = mbs.systemData.GetODE2Coordinates_t(configuration=exu.ConfigurationType.Initial)
    q0[: q_end.size] = q_end
    v0[: v_end.size] = v_end
    mbs.systemData.SetODE2Coordinates(q0, configuration=exu.ConfigurationType.Initial)
    mbs.systemData.SetODE2Coordinates_t(v0, configuration=exu.ConfigurationType.Initial)
    sensor = mbs.AddSensor(
        SensorNode(
            nodeNumber=chain.nodes[0],
            storeInternal=True,
            outputVariableType=exu.OutputVariableType.Coordinates,
        )
    )
    mbs.Assemble()
    sim = settings(h, n)
    sim.timeIntegration.startTime = n * h
    sim.timeIntegration.endTime = 2 * n * h
    sim.solution.sensors.writePeriod = h
    n_before = conn.n_records
    mbs.SolveDynamic(sim)
    accepted = mbs.GetSensorStoredData(sensor)
    u = conn.slip_history
    k = conn.n_records - n_before  # n steps, plus the initial state if the start time
    assert k in (n, n + 1)  # differs in the last bit from the last accepted time
    assert np.array_equal(conn.time_history[n_before:], accepted[-k:, 0])
    assert np.array_equal(u[n_before:], accepted[-k:, 1])
    assert np.max(np.abs(IwanJoint(P).force_history(u) - conn.force_history)) / P.Fs < 1e-12


@pytest.mark.parametrize(
    "solver", [exu.DynamicSolverType.GeneralizedAlpha, exu.DynamicSolverType.RK44]
)
def test_post_step_function_set_between_runs_of_a_continued_simulation_is_chained(solver):
    """Run 1, then the user sets a post-step function and continues from the last time: the
    connector must keep committing (its dispatcher put back in front) and the user's function
    must run."""
    chain = Chain([1.0], v0=[3.0])
    conn = chain.joint(-1, 0, IwanJoint(P), law="python")
    sim = settings(1e-4, 200)
    chain.solve(sim, solver)
    n1, t1 = conn.n_records, conn.time_history[-1]
    seen = []
    chain.mbs.SetPostStepUserFunction(lambda mbs, t: seen.append(t) or True)
    ti = sim.timeIntegration
    ti.startTime, ti.endTime = t1, t1 + 200 * 1e-4
    chain.mbs.SolveDynamic(sim, solverType=solver, updateInitialValues=True)
    assert len(seen) >= 200
    assert conn.n_records >= n1 + 200
    assert conn.time_history[-1] == pytest.approx(t1 + 0.02, rel=1e-9)
    # the joint followed the motion: its committed slip is the final coordinate
    x_end = float(
        np.atleast_1d(chain.mbs.GetNodeOutput(chain.nodes[0], exu.OutputVariableType.Coordinates))[
            0
        ]
    )
    assert conn.joint.displacement == pytest.approx(x_end, rel=1e-12, abs=1e-15)
