"""The energy-balance helper for a user's own Exudyn model (``iwan_element.exudyn.energy``),
each claim checked against an independent route: the initial energy in closed form, the
external work against the reference Newmark integrator's ``int F v dt``, and a damper the
balance does not book shown as an error."""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
import pytest
from _connector_models import Chain, newmark_reference, settings
from exudyn.itemInterface import CoordinateSpringDamper

from iwan_element import IwanJoint, IwanParameters
from iwan_element.exudyn import add_iwan_connector, record_energy

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
H, N = 2e-5, 1500


def test_free_decay_holds_its_initial_energy():
    m, k, v0 = 1.0, 1e5, 1.5
    chain = Chain([m], v0=[v0])
    chain.spring(-1, 0, k)
    conn = chain.joint(-1, 0, P)  # IwanParameters build the exact joint
    rec = record_energy(chain.mbs, conn)
    chain.solve(settings(H, N))
    bal = rec.balance()
    assert isinstance(conn.joint, IwanJoint)
    assert bal.kinetic[0] == pytest.approx(0.5 * m * v0**2, rel=1e-12)
    assert np.all(bal.external_work == 0.0)
    assert bal.joint_dissipated[-1] > 0.05 * bal.kinetic[0]  # the joint slipped
    assert bal.max_error < 1e-4 and bal.success  # the joint work by quadrature
    np.testing.assert_array_equal(bal.t, conn.time_history)


def test_external_work_equals_the_reference_integrators():
    f0, omega = 400.0, 2 * math.pi * 50.0
    chain = Chain([1.0])
    chain.harmonic_force(0, f0, omega)
    conn = chain.joint(-1, 0, IwanJoint(P))
    rec = record_energy(chain.mbs, [conn])
    chain.solve(settings(H, N))
    bal = rec.balance()
    t, x, _ = newmark_reference(
        [1.0],
        [(-1, 0, IwanJoint(P))],
        h=H,
        n_steps=N,
        force=lambda t: np.array([f0 * math.sin(omega * t)]),
    )
    f = f0 * np.sin(omega * t)  # the load's work over each step's travel
    work = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x[:, 0])))
    assert bal.external_work[-1] == pytest.approx(work, rel=1e-9)
    assert bal.max_error < 1e-4 and bal.success  # the joint work by quadrature
    assert "usable" in bal.report().splitlines()[0]


def test_a_damper_is_booked_by_its_own_force_and_the_balance_closes():
    """Exudyn's spring-damper: its potential energy as Exudyn reports it, its dissipation
    equal to sum (c v_n + c v_n+1) / 2 (x_n+1 - x_n) from the node's velocities read by the
    user's own post-step (the integrator's discrete dissipation), and the balance closes."""
    c, k = 50.0, 1e5
    chain = Chain([1.0], v0=[1.5])
    mbs = chain.mbs
    mbs.AddObject(
        CoordinateSpringDamper(
            markerNumbers=[chain.ground_marker, chain.markers[0]], stiffness=k, damping=c
        )
    )
    xv = []
    mbs.SetPostStepUserFunction(
        lambda m, t: (
            xv.append(
                (
                    float(
                        np.atleast_1d(
                            m.GetNodeOutput(chain.nodes[0], exu.OutputVariableType.Coordinates)
                        )[0]
                    ),
                    float(np.atleast_1d(chain.velocity(0))[0]),
                )
            )
            or True
        )
    )
    conn = chain.joint(-1, 0, P)
    rec = record_energy(mbs, conn)
    chain.solve(settings(H, N))
    bal = rec.balance()
    x, v = np.array(xv).T
    want = np.concatenate([[0.0], np.cumsum(0.5 * c * (v[1:] + v[:-1]) * np.diff(x))])
    assert np.allclose(bal.damper_dissipation, want, rtol=1e-9, atol=1e-12)
    assert np.allclose(bal.elastic, 0.5 * k * x**2, rtol=1e-12, atol=1e-15)
    assert bal.damper_dissipation[-1] > 0.1 * bal.kinetic[0]
    assert bal.success and bal.max_error < 1e-4 and not bal.not_booked
    assert bal.scale == pytest.approx(
        max(np.max(conn.work_history), np.max(conn.dissipated_energy_history)), rel=1e-12
    )


def test_what_cannot_be_booked_is_named_and_the_run_not_usable():
    """A prescribed motion does work the balance cannot book: it is named, not hidden."""
    chain = Chain([1.0, 1.0], v0=[1.5, 0.0])
    conn = chain.joint(-1, 0, P)
    chain.spring(0, 1, 1e4)
    chain.prescribe(1, lambda t: 1e-3 * math.sin(200.0 * t))
    rec = record_energy(chain.mbs, conn)
    chain.solve(settings(H, N))
    bal = rec.balance()
    assert not bal.success
    assert any("prescribed motion of object" in w for w in bal.not_booked)
    assert "not booked" in bal.verdict() and "prescribed motion" in bal.report()


def test_the_balance_is_judged_against_the_joints_own_energy():
    """A joint that dissipates a little beside a big oscillator damped numerically
    (generalized-alpha at spectral radius 0.5): small against the model's energy, the error
    is large against the joint's own, and the verdict names the numerical damping."""
    chain = Chain([1.0, 100.0], v0=[0.3, 10.0])
    conn = chain.joint(-1, 0, P)
    chain.spring(-1, 1, 1e7)  # 5 kJ oscillating at 50 Hz
    rec = record_energy(chain.mbs, conn)
    chain.solve(settings(H, N, rho=0.5))
    bal = rec.balance()
    drift = abs(bal.total[-1] - bal.total[0])
    assert drift / bal.energy_level < 1e-3 < drift / bal.scale
    assert not bal.success and "spectralRadius 0.5" in bal.verdict()
    assert bal.scale < 1e-3 * bal.energy_level


def test_a_new_run_and_a_reset_start_the_recording_again():
    chain = Chain([1.0], v0=[1.5])
    chain.spring(-1, 0, 1e5)
    conn = chain.joint(-1, 0, P)
    rec = record_energy(chain.mbs, conn)
    sim = settings(H, 300)
    chain.solve(sim)
    first = rec.balance()
    chain.mbs.SolveDynamic(sim)  # a new run: both start again
    second = rec.balance()
    assert rec.n_records == conn.n_records == 301
    for name in ("kinetic", "elastic", "joint_dissipated", "total"):
        assert np.array_equal(getattr(first, name), getattr(second, name)), name
    conn.reset()
    assert rec.n_records == 0
    with pytest.raises(RuntimeError, match="nothing recorded"):
        rec.balance()


def test_bad_arguments_are_refused():
    chain = Chain([1.0])
    with pytest.raises(ValueError, match="joints must be"):
        record_energy(chain.mbs, [])
    with pytest.raises(ValueError, match="mbs must be"):
        record_energy(None, [])
    with pytest.raises(ValueError, match="IwanParameters"):
        add_iwan_connector(chain.mbs, [chain.ground_marker, chain.markers[0]], object())
    conn = chain.joint(-1, 0, P)
    rec = record_energy(chain.mbs, conn)
    with pytest.raises(RuntimeError, match="nothing recorded"):
        rec.balance()


def test_a_pendulum_on_a_revolute_joint_with_gravity_balances():
    """A rigid rod on Exudyn's revolute joint under gravity, its tip held up by an Iwan
    joint it slides down through; the user's own post-step (set after the recorder: still
    chained, the recorder still called) reads the kinetic energy and the centre of mass:
    the balance books the same kinetic energy and the gravity work ``-m g dy``, the
    constraint does no work, and the balance closes against the joint's energy, better as
    the step falls (TrapezoidalIndex2: no numerical damping)."""
    from exudyn.utilities import InertiaCuboid

    from iwan_element.exudyn import create_iwan_connector

    errors = []
    for steps in (2000, 8000):
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        ground = mbs.CreateGround()
        rod = mbs.CreateRigidBody(
            referencePosition=[0.5, 0.0, 0.0],
            inertia=InertiaCuboid(1000.0, [1.0, 0.05, 0.05]),
            gravity=[0.0, -9.81, 0.0],
            initialVelocity=[0.0, 1.0, 0.0],
            initialAngularVelocity=[0.0, 0.0, 2.0],
        )
        mbs.CreateRevoluteJoint(
            itemNumbers=[ground, rod], position=[0.0, 0.0, 0.0], axis=[0.0, 0.0, 1.0]
        )
        conn = create_iwan_connector(
            mbs,
            bodyNumbers=[ground, rod],
            localPosition0=[1.0, 0.0, 0.0],
            localPosition1=[0.5, 0.0, 0.0],
            axis=[0, 1, 0],
            parameters=IwanParameters(Fs=5.0, KT=2e3, chi=-0.5, beta=0.5),
        )
        rec = record_energy(mbs, conn)
        seen = []
        mbs.SetPostStepUserFunction(
            lambda m, t, seen=seen, rod=rod: (
                seen.append(
                    (
                        m.GetObjectOutputBody(
                            rod, exu.OutputVariableType.Position, localPosition=[0, 0, 0]
                        )[1],
                        m.GetObjectOutputBody(
                            rod, exu.OutputVariableType.KineticEnergy, localPosition=[0, 0, 0]
                        ),
                    )
                )
                or True
            )
        )
        mbs.Assemble()
        sim = settings(2.0 / steps, steps)
        mbs.SolveDynamic(sim, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
        bal = rec.balance()
        y, kin = np.array(seen).T
        assert len(y) == len(bal.t)
        assert np.allclose(bal.kinetic, kin, rtol=1e-13, atol=1e-15)
        assert np.allclose(bal.external_work, -2.5 * 9.81 * (y - y[0]), rtol=1e-12, atol=1e-12)
        assert bal.joint_dissipated[-1] > 5.0 and not bal.not_booked and not bal.notes
        errors.append(bal.max_error)
    assert errors[1] < errors[0] < 1e-3
