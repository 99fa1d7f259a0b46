"""Three Exudyn scripts (the examples' own from-scratch versions of Exudyn's spring-damper
user-function test, Cartesian spring-damper example and reduced-order rotor test), each with
one spring-damper swapped for ``create_iwan_connector`` in one call, checked against
independent routes: the exact read-out of the Python law, Exudyn's own sensors and the
unswapped model's motion on the axes the swap leaves to Exudyn's springs."""

from __future__ import annotations

import sys
from pathlib import Path

import exudyn as exu
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import exudyn_cartesian_mass as cartesian
import exudyn_duffing_sweep as duffing
import exudyn_rotor_bearing as rotor

import iwan_element.exudyn.slips.slip_map as slip_map
from iwan_element.exudyn import IwanCartesianConnector

_OVT = exu.OutputVariableType


def _objects(model):
    return model.mbs.systemData.NumberOfObjects()


@pytest.fixture(scope="module")
def fem():
    return rotor.truss_rotor()


# ---------------------------------------------------------------------------- rotor
def test_rotor_joint_dissipation_by_the_default_route_equals_the_exact_read_out(fem, monkeypatch):
    """The bearing joint rides on a spinning reduced flexible body (a marker position that
    is affine in each coordinate alone, not jointly). Over 0.05 s the default route must
    dissipate what the exact read-out (law="python") does, within 5 % (measured: 5e-10),
    and its slip is the y displacement of the bearing marker that Exudyn's sensor records.
    The affine shortcut the route took before (the map frozen at the start) is shown to be
    far off on the same model, so the comparison can fail."""
    runs = {}
    for law in ("auto", "python"):
        model = rotor.build("iwan", law=law, fem=fem)
        rotor.run(model)
        runs[law] = model
    d, e = (runs[k].connector for k in ("auto", "python"))
    assert d.connectors[0].route == "symbolic" and e.connectors[0].route == "python"
    D, De = d.dissipated_energy_history[-1], e.dissipated_energy_history[-1]
    assert De > 0 and abs(D - De) <= 0.05 * De
    assert abs(D - De) <= 1e-6 * De  # in fact to round-off
    y = runs["auto"].mbs.GetSensorStoredData(runs["auto"].sensor)[:, 2]
    u = d.slip_history[:, 0]
    assert np.max(np.abs(u)) > 1.2 * rotor.JOINT.phi_max  # macroslip
    assert np.max(np.abs(u + (y - y[0]))) <= 1e-9 * np.max(np.abs(u))  # markers [rotor, ground]
    mbs = runs["auto"].mbs  # the force Exudyn applied at the end
    applied = mbs.GetObjectOutput(d.connectors[0].objectNumber, _OVT.Force)
    assert np.allclose(applied, [0.0, d.force_history[-1, 0], 0.0], rtol=1e-12, atol=1e-12)
    monkeypatch.setattr(slip_map, "JOINT_CHECKS", 0)  # the old one-coordinate test
    frozen = rotor.build("iwan", fem=fem)
    rotor.run(frozen)
    assert frozen.connector.dissipated_energy_history[-1] > 10 * De


def test_rotor_energy_balance_books_the_strain_energy_and_names_the_numerical_damping(fem):
    """The rotor holds 250 J of spin; the joint dissipates 0.2 mJ. The balance books the
    body's strain energy (its reduced stiffness) and the bearings' dampers, is judged
    against the joint's own energy, and at the script's spectral radius 0.5 says why it is
    not usable."""
    model = rotor.build("iwan", energy=True, fem=fem)
    rotor.run(model)
    bal = model.recorder.balance()
    assert bal.kinetic[0] > 1e5 * bal.scale
    assert np.max(bal.elastic) > 0 and bal.damper_dissipation[-1] > 0
    assert not bal.not_booked
    assert not bal.success and "spectralRadius 0.5" in bal.verdict()


# ---------------------------------------------------------------------------- Cartesian
@pytest.mark.parametrize("gravity", [False, True])
def test_cartesian_mass_swap_keeps_the_other_axes_and_balances(gravity):
    steps = 20_000
    spring = cartesian.build("spring", steps=steps, gravity=gravity)
    cartesian.run(spring)
    model = cartesian.build("iwan", steps=steps, energy=True, gravity=gravity)
    n0 = _objects(model)
    cartesian.run(model)
    conn = model.connector
    assert isinstance(conn, IwanCartesianConnector) and len(conn.objectNumbers) == 2
    assert n0 == _objects(spring) + 1  # the law, beside Exudyn's springs
    p = [m.mbs.GetObjectOutputBody(m.body, _OVT.Displacement) for m in (spring, model)]
    assert np.allclose(p[1][1:], p[0][1:], rtol=1e-10, atol=1e-14)  # y, z: Exudyn's springs
    u = conn.slip_history[:, 0]
    assert u[0] == pytest.approx(cartesian.U0, rel=1e-12)  # offset [L, 0, 0]
    assert np.max(np.abs(u)) > cartesian.JOINT.phi_max
    pe = model.mbs.GetObjectOutput(conn.springDamper, _OVT.PotentialEnergy)
    y, z = p[1][1], p[1][2]
    assert pe == pytest.approx(0.5 * cartesian.K * (y * y + z * z), rel=1e-9)  # reported
    bal = model.recorder.balance()
    assert bal.success and bal.max_error < 1e-3, bal.report()
    assert bal.damper_dissipation[-1] > 0 and bal.external_work[-1] != 0


def test_cartesian_mass_default_route_equals_the_python_law():
    runs = [cartesian.build("iwan", steps=4000, law=law) for law in ("auto", "python")]
    for m in runs:
        cartesian.run(m)
    u = [m.connector.slip_history for m in runs]
    assert runs[0].connector.connectors[0].route == "symbolic"
    assert np.max(np.abs(u[0] - u[1])) <= 1e-9 * np.max(np.abs(u[1]))


# ---------------------------------------------------------------------------- Duffing
def test_duffing_sweep_swap_is_one_call_and_its_balance_converges_with_the_step():
    """At the script's own step (12.6 steps a period at the end of the sweep) the balance
    is outside 1e-3 of the joint's energy and says the step is too large; four times finer
    it is within; the joint with its dashpot is the spring-damper's one object."""
    spring = duffing.build("spring")
    errors = {}
    for steps in (5000, 40_000):
        model = duffing.build("iwan", steps=steps, energy=True)
        assert _objects(model) == _objects(spring)
        duffing.run(model)
        bal = model.recorder.balance()
        errors[steps] = bal.max_error
        assert not bal.not_booked and bal.connector_work[-1] == 0.0
    assert errors[5000] > 1e-3 > errors[40_000]
    assert errors[5000] / errors[40_000] > 30  # second order: 64


def test_duffing_sweep_default_route_equals_the_python_law():
    runs = [duffing.build("iwan", steps=5000, law=law) for law in ("auto", "python")]
    for m in runs:
        duffing.run(m)
    c = [m.connector for m in runs]
    assert c[0].connectors[0].route == "symbolic" and c[1].connectors[0].route == "python"
    u = [x.slip_history for x in c]  # Newton's tolerance over 50 s of sweep:
    assert np.max(np.abs(u[0] - u[1])) <= 1e-7 * np.max(np.abs(u[1]))  # measured 2e-9
    D = [x.dissipated_energy_history[-1] for x in c]
    assert D[0] == pytest.approx(D[1], rel=1e-7)


def test_the_unswapped_duffing_script_is_booked_through_its_force_function():
    """Without the joint the user's own spring function is booked as work into the
    connector (stored and dissipated together), so even the script as it is balances."""
    from exudyn.itemInterface import MarkerNodeCoordinate, NodePointGround

    from iwan_element import IwanParameters
    from iwan_element.exudyn import add_iwan_connector, record_energy

    model = duffing.build("spring", steps=40_000)
    mbs = model.mbs
    g = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=model.node, coordinate=1))  # idle y joint
    conn = add_iwan_connector(mbs, [g, m], IwanParameters(Fs=1.0, KT=10.0, chi=-0.5, beta=0.5))
    rec = record_energy(mbs, conn)
    mbs.Assemble()
    duffing.run(model)
    bal = rec.balance()
    assert bal.connector_work[-1] > 100.0 and not bal.not_booked
    assert abs(bal.total[-1] - bal.total[0]) < 1e-3 * bal.connector_work[-1]


@pytest.mark.parametrize(
    "module, args",
    [
        (rotor, ["--t-end", "0.005"]),
        (cartesian, ["--steps", "2000", "--gravity"]),
        (duffing, ["--steps", "2000"]),
    ],
)
def test_the_examples_run_as_scripts(module, args, capsys):
    module.main(args)
    out = capsys.readouterr().out
    assert ("dissipated" in out) and ("Energy balance" in out or "relative" in out)
