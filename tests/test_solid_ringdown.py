"""The Exudyn ring-down of a solid specimen (models.simulation.transient, issue 36) on the
coarse mesh.

Independent routes: the energy balance (the bodies' kinetic and strain energy from the reduced
matrices, the joints' exact records, the floor's work); the stuck interface against the stuck
eigenproblem and the per-mode floor (each mode decays at its own floor at its stuck
frequency); the slipping mode 1 against QSMA of the same solid.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip(
    "ngsolve", reason="the solid specimens need the extra iwan-element[fem] (ngsolve)"
)

from iwan_element.models import Impact, modal_amplitude_curve, natural_frequencies, preset, ringdown
from iwan_element.models.simulation import port_basis
from iwan_element.models.solid import (
    lap_beam_parts,
    solid_specimen,
)


@pytest.fixture(scope="module")
def solid():
    """The coarse Brake-Reuss solid of tests/test_solid.py (104 reduced coordinates, 30
    patches): stuck modes 1 (first height bending), 2 (in-plane), 3 (second height)."""
    s = preset("brake-reuss")
    parts = lap_beam_parts(s, mesh_size=0.012, lap_mesh_size=0.0051)
    return solid_specimen(s, parts, patch_size=0.0085, n_modes=8)


def test_the_slip_basis_makes_the_slips_coordinates(solid):
    G = solid.linear_system().G
    T, T_inv, n_eta = port_basis(G)
    m = G.shape[0]
    assert n_eta == G.shape[1] - m
    assert np.allclose(G @ T, np.hstack([np.zeros((m, n_eta)), np.eye(m)]), atol=1e-12)
    assert np.allclose(T_inv @ T, np.eye(T.shape[1]), atol=1e-12)
    with pytest.raises(ValueError, match="full row rank"):
        port_basis(np.vstack([G, G[:1]]))


def test_a_two_mode_solid_ring_down_closes_its_energy_balance(solid):
    r = ringdown(
        solid, amplitude={1: 60e-6, 3: 8e-6}, duration=0.16, steps_per_period=32, record_energy=True
    )
    e = r.energy
    assert r.metadata["tangential"] == "iwan"
    assert r.metadata["n_coordinates"] == solid.model.info["n_reduced"]
    assert e["joint_dissipated"][-1] > 0.01 * r.initial_energy  # the joints slipped
    assert e["floor_dissipated"][-1] > 0.01 * r.initial_energy  # and the floor acted
    assert r.metadata["overflow_steps"] == 0
    # measured 9e-5 (the trapezoidal rule's quadrature of the joint forces: the same 9e-5)
    assert r.max_energy_error < 1e-3 and r.success
    assert abs(r.max_energy_error - abs(r.metadata["joint_quadrature_error"])) < 2e-4


def test_the_compiled_law_on_slip_coordinates_equals_the_python_joints(solid):
    kw = {"amplitude": 60e-6, "duration": 0.1, "record_energy": True}
    a, b = ringdown(solid, **kw), ringdown(solid, joint_elements=True, **kw)
    # measured 7e-14 of the amplitude with two attachment shapes per patch, 4e-10 to 1.5e-9
    # with the normal gaps' shapes too (the two routes then part at Newton's tolerance, 1e-10
    # relative, not in the law); the same energy balance (9.4e-5)
    assert np.max(np.abs(a.sensor - b.sensor)) < 1e-8 * np.max(np.abs(a.sensor))
    assert abs(a.max_energy_error - b.max_energy_error) < 1e-9


def test_a_stuck_solid_rings_each_mode_at_its_own_floor_and_stuck_frequency(solid):
    # a friction so high that the patches never leave their linear range: the Iwan route
    # and the linear springs must give the stuck modes with their own floors
    stuck = solid.replace(friction=1e4, modal_damping=(0.002, 0.01, 0.004))
    f = natural_frequencies(stuck, n_modes=9)[6:]
    for tangential in ("iwan", "linear"):
        r = ringdown(
            stuck,
            amplitude={1: 20e-6, 3: 4e-6},
            duration=0.25,
            steps_per_period=32,
            tangential=tangential,
        )
        for mode, zeta in ((1, 0.002), (3, 0.004)):
            c = r.mode_curve(mode)
            # measured: frequency within 7e-6, damping within 0.63 % (iwan and linear)
            assert np.all(np.abs(c.frequency / f[mode - 1] - 1) < 2e-5), (tangential, mode)
            assert np.all(np.abs(c.damping_ratio / zeta - 1) < 0.02), (tangential, mode)


def test_mode_1_of_the_solid_rings_down_as_qsma_says(solid):
    r = ringdown(
        solid, amplitude=60e-6, cycles=16, steps_per_period=64, sensors=(0.1, solid.sensor_position)
    )
    # the sensor rows along the axis read the sensor as S does (interpolated between the
    # stored millimetres: the read-out's curvature over 1 mm); the release amplitude is met
    assert np.allclose(
        r.sensor_displacement[1], r.sensor, rtol=0, atol=1e-4 * np.max(np.abs(r.sensor))
    )
    assert abs(r.sensor[0] / 60e-6 - 1) < 1e-9 and abs(r.sensor_displacement[0, 0]) > 1e-6
    c = r.curve
    q = modal_amplitude_curve(solid, amplitude=c.amplitude)
    assert len(c) >= 3
    # measured: frequency within 4e-5, damping within 0.3 % (QSMA neglects the inertia of
    # the joint's microslip and holds the load shape fixed)
    assert np.all(np.abs(c.frequency / q.frequency - 1) < 2e-4)
    assert np.all(np.abs(c.damping_ratio / q.damping_ratio - 1) < 0.02)
    drop = 1 - c.frequency / natural_frequencies(solid, n_modes=7)[-1]
    assert np.all(drop > 1e-3)  # it slips: well above the tolerance


def test_the_solid_ring_down_refuses_what_it_cannot_do(solid):
    with pytest.raises(ValueError, match="in-plane"):
        ringdown(solid, amplitude={2: 1e-5}, cycles=4)
    with pytest.raises(ValueError, match="tangential"):
        ringdown(solid, amplitude=1e-5, tangential="stuck")
    with pytest.raises(ValueError, match="positions"):
        ringdown(solid, amplitude=1e-5, sensors=[-0.1])


def test_the_solid_takes_a_hammer_impact_and_books_its_work(solid):
    """The host is the 1-D beams' (models/simulation/host.py): an impact is a force on the struck
    point's port coordinate; its work (the trapezoidal rule's) balances the energy."""
    r = ringdown(
        solid,
        impact=Impact(position=0.6438, peak_force=50.0, contact_time=1e-3),
        modes=(1,),
        cycles=8,
        record_energy=True,
    )
    assert r.max_energy_error < 1e-3
    assert r.energy["input_work"][-1] > 0
    assert r.curve.amplitude.size >= 1


def _replayed_interface(spec, X=60e-6, n=150):
    """A free decay of ``spec`` from mode 1's static state at ``X`` [m] in Exudyn (the host of
    the transient, 32 steps a period), then every contact point's law (its effects around its
    IwanJoint) replayed alone on the point's recorded slips: the largest force difference
    over the largest force, and the points' stacks."""
    import exudyn as exu
    from iwan_element.models.modal import interface_laws, static_modal_load
    from iwan_element.models.simulation import build_host
    from iwan_element.models.simulation.solver import solver_settings

    from iwan_element import IwanJoint

    model = build_host(spec)
    rel = static_modal_load(spec, [X], mode=1)
    model.set_state(rel["x"][0])
    h = 2 * np.pi / rel["omega0"] / 32
    z0 = model.T_inv @ rel["x"][0]
    sim = solver_settings(force_scale=float(np.max(np.abs((model.Kb + model.Ks) @ z0))))
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    model.mbs.SolveDynamic(sim)
    u, F = model.interface.slip_history, model.interface.force_history
    laws = interface_laws(spec)
    worst = 0.0
    for i, p in enumerate(model.points.params):
        el = laws.stack(i, IwanJoint(p))
        again = []
        for ui in u[:, i]:
            again.append(el.trial(float(ui))[0])
            el.commit()
        worst = max(worst, float(np.max(np.abs(np.array(again) - F[:, i]))))
    return worst / float(np.max(np.abs(F))), laws.stacks, float(np.max(np.abs(u)))


def test_the_interface_effects_run_the_same_law_on_the_beam_and_on_the_solid(solid):
    """One element, two hosts: the same interface effects (a pin at the bolts, a spread patch
    that starts to slide, a cubic spring) on the 1-D beam's strips and on the solid's patches.
    In a free decay from 60 um each point's recorded force is its law (the effect classes
    around its IwanJoint) replayed alone on its recorded slips, to the last bit, on both; the
    pin sits at the two points nearest each bolt (the solid's along-beam elements), the rest
    at every point."""
    from iwan_element.models import InterfaceEffect

    effects = (
        InterfaceEffect("pinning_stiffness", values={"k_p": 7.8e7, "delta": 6.8e-8}),
        InterfaceEffect("macroslip_onset", values={"k_2": 5e7, "u_s": 1.27e-7, "shape": 0.45}),
        InterfaceEffect("hardening", values={"k3": 1.7e20}),
    )
    for spec in (preset("brake-reuss").replace(n_points=24), solid):
        err, stacks, umax = _replayed_interface(spec.replace(interface_effects=effects))
        assert umax > 2 * 1.27e-7  # the patches slid
        assert err < 1e-12
        pinned = [i for i, s in enumerate(stacks) if any(n == "pinning_stiffness" for n, _ in s)]
        assert len(pinned) == 2 * len(spec.bolt_positions)
        assert all(len(s) >= 2 for s in stacks)
