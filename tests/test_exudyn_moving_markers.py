"""The connector's slip on moving, rotating and flexible bodies: the default (symbolic) route
against the exact read-out of the Python law and against the markers' positions as Exudyn
reports them at every accepted step (an independent read: the user's own post-step)."""

from __future__ import annotations

import exudyn as exu
import numpy as np
import pytest
from _connector_models import settings
from exudyn.itemInterface import (
    CoordinateConstraint,
    MarkerBodyPosition,
    MarkerBodyRigid,
    MarkerNodeCoordinate,
    NodePoint2DSlope1,
    NodePointGround,
    ObjectANCFCable2D,
    ObjectConnectorCartesianSpringDamper,
    ObjectGround,
)
from exudyn.utilities import InertiaCuboid

from iwan_element import IwanJoint, IwanParameters
from iwan_element.exudyn import add_iwan_connector

P = IwanParameters(Fs=40.0, KT=4e4, chi=-0.5, beta=0.3)
_OVT = exu.OutputVariableType


def _spinning_pair(mbs):
    """A rigid body spinning about z at 25 rad/s and a small rigid body at its centre moving
    across it; their rigid markers, and the spinner's (for the axis)."""
    spinner = mbs.CreateRigidBody(
        referencePosition=[0.0, 0.0, 0.0],
        inertia=InertiaCuboid(2000.0, [0.2, 0.2, 0.05]),
        initialAngularVelocity=[0.0, 0.0, 25.0],
    )
    slider = mbs.CreateRigidBody(
        referencePosition=[0.0, 0.0, 0.0],
        inertia=InertiaCuboid(2000.0, [0.05, 0.05, 0.05]),
        initialVelocity=[1.6, 0.8, 0.0],
    )
    m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=spinner, localPosition=[0.0, 0.0, 0.0]))
    m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=slider, localPosition=[0.0, 0.0, 0.0]))
    return m0, m1


def _offset_marker_on_spinner(mbs):
    """A point 0.1 m off the axis of a rigid body spinning at 25 rad/s (position not affine in
    the coordinates), and a ground point; the joint acts along global x."""
    spinner = mbs.CreateRigidBody(
        referencePosition=[0.0, 0.0, 0.0],
        inertia=InertiaCuboid(2000.0, [0.3, 0.3, 0.05]),
        initialAngularVelocity=[0.0, 0.0, 25.0],
    )
    g = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0.1, 0.0, 0.0]))
    mb = mbs.AddMarker(MarkerBodyPosition(bodyNumber=spinner, localPosition=[0.1, 0.0, 0.0]))
    mbs.AddObject(
        ObjectConnectorCartesianSpringDamper(  # holds the spinner's centre
            markerNumbers=[
                mbs.AddMarker(MarkerBodyPosition(bodyNumber=g)),
                mbs.AddMarker(MarkerBodyPosition(bodyNumber=spinner)),
            ],
            stiffness=[1e5, 1e5, 1e5],
        )
    )
    return mg, mb


def _ancf_surface_marker(mbs):
    """A two-element ANCF Cable2D cantilever (steel strip 0.4 m x 20 x 4 mm) swinging from
    an initial velocity; the joint acts across it (y) at the tip's upper surface, where the
    position is not affine in the coordinates (it follows the slope's normal)."""
    L, b, h, E, rho = 0.4, 0.02, 0.004, 2.1e11, 7850.0
    A, I = b * h, b * h**3 / 12.0
    nodes = [
        mbs.AddNode(
            NodePoint2DSlope1(
                referenceCoordinates=[x, 0.0, 1.0, 0.0],
                initialVelocities=[0.0, 6.0 * x / L, 0.0, 6.0 / L if x else 0.0],
            )
        )
        for x in (0.0, 0.5 * L, L)
    ]
    elems = [
        mbs.AddObject(
            ObjectANCFCable2D(
                nodeNumbers=[nodes[i], nodes[i + 1]],
                length=0.5 * L,
                massPerLength=rho * A,
                bendingStiffness=E * I,
                axialStiffness=E * A,
            )
        )
        for i in range(2)
    ]
    ground = mbs.AddNode(NodePointGround())
    mgc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    for c in range(4):  # clamp the root node
        mbs.AddObject(
            CoordinateConstraint(
                markerNumbers=[
                    mgc,
                    mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c)),
                ]
            )
        )
    g = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[L, 0.5 * h, 0.0]))
    mt = mbs.AddMarker(
        MarkerBodyPosition(bodyNumber=elems[1], localPosition=[0.5 * L, 0.5 * h, 0.0])
    )
    return mg, mt


def _run(build, law, *, axis, body_axis=False, h=2e-4, n=400, rho=1.0, abs_tol=1e-10):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    m0, m1 = build(mbs)
    kw = {"axisMarker": m0} if body_axis else {}
    conn = add_iwan_connector(mbs, [m0, m1], IwanJoint(P), axis=axis, law=law, **kw)
    reads = []

    def read(mbs_, t):  # the user's own read-out
        d = mbs_.GetMarkerOutput(m1, _OVT.Position) - mbs_.GetMarkerOutput(m0, _OVT.Position)
        a = np.asarray(axis, float) / np.linalg.norm(axis)
        if body_axis:
            a = np.asarray(mbs_.GetMarkerOutput(m0, _OVT.RotationMatrix)).reshape(3, 3) @ a
        reads.append(float(a @ d))
        return True

    mbs.SetPostStepUserFunction(read)  # set after: chained behind
    mbs.Assemble()
    mbs.SolveDynamic(settings(h, n, rho=rho, rel_tol=1e-10, abs_tol=abs_tol))
    return conn, np.array(reads)


CASES = {
    "body-fixed axis on a spinning rigid body": (
        _spinning_pair,
        dict(axis=[1.0, 0.0, 0.0], body_axis=True),
    ),
    "point off the axis of a spinning rigid body": (
        _offset_marker_on_spinner,
        dict(axis=[1.0, 0.0, 0.0]),
    ),
    "ANCF cable surface point": (
        _ancf_surface_marker,
        dict(axis=[0.0, 1.0, 0.0], h=1e-4, rho=0.8, abs_tol=1e-6),
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_default_route_reads_the_exact_slip_on_moving_markers(case):
    build, kw = CASES[case]
    default, reads = _run(build, "auto", **kw)
    exact, _ = _run(build, "python", **kw)
    assert default.route == "symbolic" and exact.route == "python"
    u, ue = default.slip_history, exact.slip_history
    scale = np.max(np.abs(ue))
    assert scale > 2 * P.phi_max  # the joint slipped through macroslip
    assert np.max(np.abs(u - reads)) <= 1e-12 * scale  # the slip is the markers' projection
    assert np.max(np.abs(u - ue)) <= 1e-9 * scale  # and the run is the exact one
    De, D = exact.dissipated_energy_history[-1], default.dissipated_energy_history[-1]
    assert De > 0 and abs(D - De) <= 1e-8 * De
