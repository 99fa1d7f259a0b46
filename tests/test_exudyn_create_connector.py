"""``create_iwan_connector``: Exudyn's idiom (markers made from bodies and nodes, items checked
by their type), the Cartesian form (a law per axis, Exudyn's springs on the remaining axes)
and the body-fixed frame, each against an independent route."""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
import pytest
from _connector_models import Chain, settings
from exudyn.itemInterface import MarkerNodeCoordinate, NodePointGround
from exudyn.utilities import InertiaCuboid

from iwan_element import IwanJoint, IwanParameters
from iwan_element.exudyn import create_iwan_connector

P = IwanParameters(Fs=40.0, KT=4e4, chi=-0.5, beta=0.3)
Q = IwanParameters(Fs=25.0, KT=2e4, chi=-0.3, beta=0.8)
_OVT = exu.OutputVariableType


def _system():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround(referencePosition=[0.0, 0.0, 0.0])
    return SC, mbs, ground


def test_markers_are_made_as_exudyn_makes_them():
    SC, mbs, ground = _system()
    body = mbs.CreateMassPoint(referencePosition=[1.0, 0.0, 0.0], mass=1.0)
    node = mbs.GetObject(body)["nodeNumber"]
    a = create_iwan_connector(
        mbs,
        bodyNumbers=[ground, body],
        localPosition0=[1.0, 0.5, 0.0],
        axis=[1, 0, 0],
        parameters=P,
        name="bolt",
    )
    m0, m1 = (mbs.GetMarker(m) for m in a.markerNumbers)
    assert (m0["markerType"], m0["name"], list(m0["localPosition"])) == (
        "BodyPosition",
        "Marker0:bolt",
        [1.0, 0.5, 0.0],
    )
    assert (m1["markerType"], m1["name"]) == ("BodyPosition", "Marker1:bolt")
    b = create_iwan_connector(
        mbs, bodyNumbers=[int(ground), exu.NodeIndex(int(node))], axis=[0, 1, 0], parameters=P
    )  # an int is a body
    assert mbs.GetMarker(b.markerNumbers[1])["markerType"] == "NodePosition"
    c = create_iwan_connector(
        mbs, bodyNumbers=list(a.markerNumbers), axis=[0, 0, 1], parameters=P
    )  # markers as they are
    assert c.markerNumbers == a.markerNumbers and c.springDamper is None
    assert [mbs.GetObject(o)["objectType"] for o in a.objectNumbers] == [
        "ConnectorCartesianSpringDamper"
    ]


@pytest.fixture()
def parts():
    SC, mbs, ground = _system()
    body = mbs.CreateMassPoint(referencePosition=[1.0, 0.0, 0.0], mass=1.0)
    g = mbs.AddNode(NodePointGround())
    coord = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=g, coordinate=0))
    coord1 = mbs.AddMarker(
        MarkerNodeCoordinate(nodeNumber=mbs.GetObject(body)["nodeNumber"], coordinate=0)
    )
    return dict(
        SC=SC,
        mbs=mbs,
        ground=ground,
        body=body,
        coord=coord,
        coord1=coord1,
        node=exu.NodeIndex(int(mbs.GetObject(body)["nodeNumber"])),
    )


@pytest.mark.parametrize(
    "case, message",
    [
        (
            lambda d: dict(bodyNumbers=[d["ground"], 1.5]),
            r"bodyNumbers\[1\] must be a body .* got 1.5",
        ),
        (lambda d: dict(bodyNumbers=[d["ground"]]), "bodyNumbers must be a list of two items"),
        (
            lambda d: dict(bodyNumbers=[d["ground"], exu.LoadIndex(0)]),
            r"bodyNumbers\[1\] must be a body",
        ),
        (
            lambda d: dict(bodyNumbers=[d["ground"], d["node"]], localPosition1=[0.1, 0, 0]),
            r"localPosition1 must be \(0, 0, 0\) for a node",
        ),
        (
            lambda d: dict(bodyNumbers=[d["ground"], d["body"]], axis=[[1, 0, 0], [1, 1, 0]]),
            "mutually orthogonal",
        ),
        (
            lambda d: dict(
                bodyNumbers=[d["ground"], d["body"]], axis=[1, 0, 0], stiffness=[1e3, 1e3, 1e3]
            ),
            "has a spring along the Iwan axis",
        ),
        (
            lambda d: dict(
                bodyNumbers=[d["ground"], d["body"]], axis=[[1, 0, 0], [0, 1, 0]], parameters=[P]
            ),
            "a list of 2 of them",
        ),
        (
            lambda d: dict(
                bodyNumbers=[d["ground"], d["body"]], axis=[1, 0, 0], useGlobalFrame=False
            ),
            r"bodyNumbers\[1\] = .* has no orientation",
        ),
        (lambda d: dict(bodyNumbers=[d["ground"], d["body"]]), "axis is required"),
        (
            lambda d: dict(
                bodyNumbers=[d["ground"], d["body"]], axis=[1, 0, 0], damping=[1, -1, 0]
            ),
            "damping must be >= 0",
        ),
        (
            lambda d: dict(bodyNumbers=[d["coord"], d["coord1"]], axis=[1, 0, 0]),
            "axis applies to position",
        ),
        (
            lambda d: dict(bodyNumbers=[d["coord"], d["coord1"]], stiffness=[1, 0, 0]),
            "coordinate markers take a number as damping and no stiffness",
        ),
        (
            lambda d: dict(bodyNumbers=[d["coord"], d["coord1"]], offset=[0.5, 0, 0]),
            "offset must be a real",
        ),
        (
            lambda d: dict(bodyNumbers=[d["ground"], d["body"]], axis=[1, 0, 0], law="exact"),
            "law must be",
        ),
        (
            lambda d: dict(bodyNumbers=[d["ground"], d["body"]], axis=[1, 0, 0], parameters="P"),
            "parameters must be IwanParameters",
        ),
    ],
)
def test_invalid_items_are_refused_before_anything_is_added(parts, case, message):
    kw = {"parameters": P, **case(parts)}
    mbs = parts["mbs"]
    counts = (mbs.systemData.NumberOfObjects(), mbs.systemData.NumberOfMarkers())
    with pytest.raises(ValueError, match=message):
        create_iwan_connector(mbs, **kw)
    assert (mbs.systemData.NumberOfObjects(), mbs.systemData.NumberOfMarkers()) == counts


def test_a_law_per_axis_each_as_a_one_dimensional_joint():
    """Three Iwan axes on a mass point moving diagonally: each axis's slip is that of the
    one-dimensional joint with its own parameters and velocity component (the laws are
    independent), and the diagonal motion reaches the per-axis friction limits."""
    v0 = np.array([3.0, -2.0, 1.5])
    axes = np.eye(3)
    params = [P, Q, P]
    h, n = 5e-5, 800
    SC, mbs, ground = _system()
    body = mbs.CreateMassPoint(
        referencePosition=[0.0, 0.0, 0.0], mass=1.0, initialVelocity=list(v0)
    )
    conn = create_iwan_connector(mbs, bodyNumbers=[ground, body], axis=axes, parameters=params)
    mbs.Assemble()
    mbs.SolveDynamic(settings(h, n))
    u = conn.slip_history
    assert u.shape == (n + 1, 3)
    for k in range(3):
        chain = Chain([1.0], v0=[v0[k]])
        ref = chain.joint(-1, 0, IwanJoint(params[k]))
        chain.solve(settings(h, n))
        assert np.max(np.abs(u[:, k] - ref.slip_history)) <= 1e-9 * np.max(np.abs(ref.slip_history))
        assert np.max(np.abs(u[:, k])) > params[k].phi_max
    total = sum(c.dissipated_energy_history[-1] for c in conn.connectors)
    assert conn.dissipated_energy_history[-1] == pytest.approx(total, rel=1e-12)


def test_body_fixed_frame_turns_the_axis_and_the_springs_with_body_zero():
    """useGlobalFrame=False: on a spinning rigid body, the Iwan slip is the relative position
    of the second body in the first body's frame (read by the user's post-step), the
    default route equals the Python law, and the remaining axes carry Exudyn's own
    rigid-body spring-damper in that frame (its local force is k times the local
    displacement)."""
    k = 5e3
    runs = {}
    for law in ("auto", "python"):
        SC, mbs, ground = _system()
        spinner = mbs.CreateRigidBody(
            referencePosition=[0.0, 0.0, 0.0],
            inertia=InertiaCuboid(2000.0, [0.2, 0.2, 0.05]),
            initialAngularVelocity=[0.0, 0.0, 25.0],
        )
        slider = mbs.CreateRigidBody(
            referencePosition=[0.0, 0.0, 0.0],
            inertia=InertiaCuboid(2000.0, [0.05, 0.05, 0.05]),
            initialVelocity=[1.6, 0.8, 0.2],
        )
        conn = create_iwan_connector(
            mbs,
            bodyNumbers=[spinner, slider],
            axis=[1, 0, 0],
            parameters=P,
            stiffness=[0.0, k, k],
            damping=[0.0, 2.0, 2.0],
            useGlobalFrame=False,
            law=law,
        )
        m0, m1 = conn.markerNumbers
        reads = []

        def read(mbs_, t, m0=m0, m1=m1, reads=reads):
            A = np.asarray(mbs_.GetMarkerOutput(m0, _OVT.RotationMatrix)).reshape(3, 3)
            d = mbs_.GetMarkerOutput(m1, _OVT.Position) - mbs_.GetMarkerOutput(m0, _OVT.Position)
            reads.append(A.T @ d)
            return True

        mbs.SetPostStepUserFunction(read)
        mbs.Assemble()
        mbs.SolveDynamic(settings(2e-4, 400, rel_tol=1e-10))
        runs[law] = (conn, np.array(reads), mbs)
    (d, reads, mbs), (e, _, _) = runs["auto"], runs["python"]
    assert d.frame == "body0" and d.connectors[0].route == "symbolic"
    assert e.connectors[0].route == "python"
    u = d.slip_history[:, 0]
    assert np.max(np.abs(u)) > P.phi_max
    assert np.max(np.abs(u - reads[:, 0])) <= 1e-12 * np.max(np.abs(u))
    assert np.max(np.abs(u - e.slip_history[:, 0])) <= 1e-9 * np.max(np.abs(u))
    local = mbs.GetObjectOutput(d.springDamper, _OVT.DisplacementLocal)
    assert np.allclose(local, reads[-1], rtol=0, atol=1e-12)
    force = mbs.GetObjectOutput(d.springDamper, _OVT.ForceLocal)
    vel = mbs.GetObjectOutput(d.springDamper, _OVT.VelocityLocal)
    assert force[0] == 0.0
    assert np.allclose(force[1:], k * local[1:] + 2.0 * vel[1:], rtol=1e-12)
    A = np.asarray(mbs.GetMarkerOutput(d.markerNumbers[0], _OVT.RotationMatrix)).reshape(3, 3)
    assert math.atan2(A[1, 0], A[0, 0]) == pytest.approx(25.0 * 0.08 - 2 * math.pi * 0, abs=0.05)


def test_exudyn_has_no_potential_energy_route_for_a_user_function_connector():
    """Evidence for the docs: Exudyn 1.13.6 refuses ``PotentialEnergy`` for a connector whose
    force a user function (symbolic or Python) defines, so the joint's stored energy cannot
    be reported to Exudyn (it is in the connector's records and in ``record_energy``). The
    Cartesian form's springs are Exudyn's own object, which reports theirs. Should a later
    Exudyn offer a route, this test fails and the connector should use it."""
    SC, mbs, ground = _system()
    body = mbs.CreateMassPoint(
        referencePosition=[0.0, 0.0, 0.0], mass=1.0, initialDisplacement=[0.0, 1e-3, 0.0]
    )
    conn = create_iwan_connector(
        mbs, bodyNumbers=[ground, body], axis=[1, 0, 0], parameters=P, stiffness=[0.0, 2e3, 0.0]
    )
    mbs.Assemble()
    for law_object in conn.objectNumbers[:-1]:
        with pytest.raises(Exception, match="no PotentialEnergy, its springForceUserFunction"):
            mbs.GetObjectOutput(law_object, _OVT.PotentialEnergy)
    assert mbs.GetObjectOutput(conn.springDamper, _OVT.PotentialEnergy) == pytest.approx(
        0.5 * 2e3 * 1e-6, rel=1e-12
    )
