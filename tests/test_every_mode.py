"""Every mode from one joint (issue 33): the floor per mode as a modal damping matrix, the
multi-mode ring-down through the shared interface, its energy balance, the floor per mode
from calibration, and the coupling of two modes through one Iwan element against an
independent time stepping of the exact element outside Exudyn."""

import math

import exudyn as exu
import numpy as np
import pytest
from exudyn.itemInterface import MarkerNodeCoordinate, NodeGenericODE2, ObjectGenericODE2
from iwan_element.models import mode_coupling, preset, ringdown
from iwan_element.models.calibration import modal_floor
from iwan_element.models.modal import linear_modes, modal_amplitude_curve, point_weights
from iwan_element.models.reduced import axis_rows, floor_damping
from iwan_element.models.simulation import compare_curves, solver_settings
from iwan_element.models.specimens import InterfaceEffect, SpecimenEffect

from iwan_element import AmplitudeCurve, IwanJoint, IwanParameters, amplitude_curve, models
from iwan_element.exudyn import add_iwan_interface

#: the two-bolt beam (clamped-free), contact points thinned out, its own floor per mode
TWO_BOLT = preset("two-bolt-aluminium").replace(n_points=12, modal_damping=(2e-3, 6e-4))


def test_the_floor_matrix_gives_each_stuck_mode_its_own_ratio_and_couples_none():
    """``phi_r^T C phi_s = 2 zeta_r w_r delta_rs`` with the stuck modes of qsma.linear_modes
    (their own eigen-solve), mode 3 taking ``damping_floor`` (the stated rule), and the
    free-free beam's rigid-body motions undamped."""
    s = preset("brake-reuss").replace(modal_damping=(1.3e-3, 9.6e-4))
    C = floor_damping(s).C
    shapes = [linear_modes(s, mode=r) for r in (1, 2, 3)]
    P = np.column_stack([m[1] for m in shapes])
    w = np.array([m[0] for m in shapes])
    want = np.diag(2 * np.array([1.3e-3, 9.6e-4, s.interface.damping_floor]) * w)
    np.testing.assert_allclose(P.T @ C @ P, want, atol=1e-9 * want.max())
    R = shapes[0][2]  # rigid-body modes
    assert np.max(np.abs(C @ R)) < 1e-9 * np.max(np.abs(C))
    with pytest.raises(ValueError, match="specimen"):
        floor_damping("brake-reuss")


def test_one_mode_given_as_a_dict_is_the_single_mode_call():
    """``amplitude={1: X}`` is the single-mode release; the sensor record at the specimen's
    sensor is ``sensor`` and the accelerations are the displacement's second derivative."""
    s = preset("example").replace(n_points=12)
    a = ringdown(s, amplitude=1e-4, cycles=8, steps_per_period=32)
    b = ringdown(
        s, amplitude={1: 1e-4}, cycles=8, steps_per_period=32, sensors=(s.sensor_position, 0.2)
    )
    np.testing.assert_array_equal(a.modal, b.modal)
    np.testing.assert_array_equal(a.curve.damping_ratio, b.curve.damping_ratio)
    assert (
        b.modes == (1,) and b.curves[0] is b.curve and b.sensor_displacement.shape == (2, a.t.size)
    )
    np.testing.assert_allclose(b.sensor_displacement[0], a.sensor, rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="mode must not be given"):
        ringdown(s, mode=2, amplitude={1: 1e-4})
    with pytest.raises(ValueError, match="cycles or duration"):
        ringdown(s, amplitude=1e-4, cycles=8, duration=0.1)
    with pytest.raises(ValueError, match="positions"):
        axis_rows(s, [-0.1])


def test_stuck_modes_do_not_couple_each_decays_with_its_own_floor():
    """The two-bolt beam with nothing slipping (friction 1e4), modes 1 and 2 released
    together with floors 0.2 % and 0.06 %: each mode rings at its stuck frequency with its
    own floor (the modal filter sees no trace of the other), the same route as a slipping
    interface."""
    s = TWO_BOLT.replace(friction=1e4)
    r = ringdown(s, amplitude={1: 1e-4, 2: 2e-5}, cycles=16, steps_per_period=32)
    for mode, floor in ((1, 2e-3), (2, 6e-4)):
        c = r.mode_curve(mode)
        f0 = linear_modes(s, mode=mode)[0] / (2 * math.pi)
        assert len(c) >= 3
        np.testing.assert_allclose(c.frequency, f0, rtol=2e-5)
        np.testing.assert_allclose(c.damping_ratio, floor, rtol=0.02)
    # the tip accelerometer's record (mode 2 dominates its acceleration) gives mode 2
    # through the measured route, at the trapezoidal rule's frequency (no period correction
    # on a raw record: atan(pi f h) / (pi h))
    h = r.metadata["h"]
    f2 = math.atan(linear_modes(s, mode=2)[0] * h / 2) / (math.pi * h)
    a = amplitude_curve(
        r.t,
        r.sensor_acceleration[0],
        quantity="acceleration",
        band=(0.5 * f2, 1.5 * f2),
        n_periods=3,
        compare=False,
    )
    assert len(a) >= 10
    assert np.median(a.frequency) == pytest.approx(f2, rel=1e-4)
    assert np.median(a.damping_ratio) == pytest.approx(6e-4, rel=0.02)
    assert r.metadata["floor"] == {1: 2e-3, 2: 6e-4}


def test_two_modes_through_the_slipping_interface_keep_the_energy_balance():
    """The Brake-Reuss beam (24 points), modes 1 and 2 released together from 60 and 3 um:
    kinetic + strain + springs + joint stored + joint and floor dissipation stay the release
    energy to 1e-3; what is left is the integrator's quadrature of the joint forces (the
    floor's work is booked exactly)."""
    s = preset("brake-reuss").replace(n_points=24, modal_damping=(1.3e-3, 9.6e-4))
    r = ringdown(
        s, amplitude={1: 60e-6, 2: 3e-6}, duration=0.16, steps_per_period=32, record_energy=True
    )
    e = r.energy
    assert e["joint_dissipated"][-1] > 0.02 * r.initial_energy
    assert e["floor_dissipated"][-1] > 0.05 * r.initial_energy
    assert r.max_energy_error < 1e-3
    assert r.energy_error()[-1] == pytest.approx(r.metadata["joint_quadrature_error"], abs=1e-6)
    assert r.modal_responses.shape == (2, r.t.size)


def test_a_mode_floor_from_its_lowest_points_removes_the_joint_share():
    """A synthetic mode-2 curve: the model's own joint share (QSMA, no floor) plus a floor of
    0.08 %; modal_floor finds the floor from the lowest decade, and warns where the joint's
    share is large."""
    s = preset("brake-reuss")
    X = np.geomspace(1e-8, 3e-6, 30)
    joint = modal_amplitude_curve(
        s.replace(damping_floor=0.0, calibrated_range=None), mode=2, amplitude=X
    )
    z = joint.damping_ratio + 8e-4
    c = AmplitudeCurve(X, joint.frequency, z, damping_ratio_std=np.full(X.size, 1e-6))
    floor, se, warns = modal_floor(s, c, mode=2)
    assert floor == pytest.approx(8e-4, rel=1e-6) and se < 1e-6 and not warns
    big = s.replace(friction=0.01, calibrated_range=None)  # a joint that slips early
    _, _, warns = modal_floor(big, AmplitudeCurve(X[-5:], joint.frequency[-5:], z[-5:]), mode=2)
    assert any("leans on the joint" in w for w in warns)


# --- two modes through one Iwan element: Exudyn against an independent time stepping -------

M2 = np.eye(2)
K2 = np.array([[8000.0, -4000.0], [-4000.0, 4000.0]])  # ground-k-m1-k-m2 [N/m], m = 1 kg
E2 = np.array([-1.0, 1.0])  # slip u = q2 - q1
JOINT = IwanParameters(Fs=0.6, KT=3000.0, chi=-0.5, beta=0.1)
H = 1.0 / (64 * 21.0)  # 64 steps per period of mode 2


def _modes():
    w2, V = np.linalg.eigh(K2 + JOINT.KT * np.outer(E2, E2))
    return np.sqrt(w2), V


def _release(amp):
    _, V = _modes()
    return sum(a * V[:, r - 1] / V[1, r - 1] for r, a in amp.items())  # amplitude at m2


def _numpy_route(q0, n):
    """Trapezoidal rule (Newmark average acceleration) with the exact IwanJoint, Newton on
    each step, the joint committed once per accepted step."""
    j = IwanJoint(JOINT)
    F, _ = j.trial(float(E2 @ q0))
    j.commit()
    q, v = q0.copy(), np.zeros(2)
    a = -np.linalg.solve(M2, K2 @ q + E2 * F)
    out = [q.copy()]
    for _ in range(n):
        qn = q + H * v
        for _ in range(50):
            an = 4 / H**2 * (qn - q - H * v) - a
            F, kt = j.trial(float(E2 @ qn))
            R = M2 @ an + K2 @ qn + E2 * F
            dq = np.linalg.solve(4 / H**2 * M2 + K2 + kt * np.outer(E2, E2), -R)
            qn += dq
            if np.max(np.abs(dq)) < 1e-14:
                break
        an = 4 / H**2 * (qn - q - H * v) - a
        F, _ = j.trial(float(E2 @ qn))
        j.commit()
        v = v + 0.5 * H * (a + an)
        q, a = qn, an
        out.append(q.copy())
    return np.array(out)


def _exudyn_route(q0, n):
    """The same two masses in Exudyn: a generic linear ODE2 object and the package's
    compiled Iwan interface between the two coordinates; generalized-alpha at spectral
    radius 1 (the trapezoidal rule)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(
        NodeGenericODE2(
            numberOfODE2Coordinates=2,
            referenceCoordinates=[0, 0],
            initialCoordinates=list(q0),
            initialCoordinates_t=[0, 0],
        )
    )
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=M2, stiffnessMatrix=K2))
    m = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=i)) for i in (0, 1)]
    rec = []
    mbs.SetPostStepUserFunction(
        lambda mbs_, t: rec.append(mbs_.systemData.GetODE2Coordinates()) or True
    )
    add_iwan_interface(mbs, [(m[0], m[1])], [JOINT])
    mbs.Assemble()
    sim = solver_settings(force_scale=float(np.max(np.abs(K2 @ q0))))
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * H
    mbs.SolveDynamic(sim)
    return np.array(rec)


def _curves(Q, modes):
    """Each mode's decay curve from its modal filter (amplitude at m2), read every k-th step
    (about 32 samples per period of the mode)."""
    w, V = _modes()
    t = np.arange(Q.shape[0]) * H
    out = {}
    for r in modes:
        y = (Q @ (M2 @ V[:, r - 1])) * V[1, r - 1]
        k = max(1, int(w[1] / w[r - 1] * 2))
        f = w[r - 1] / (2 * math.pi)
        out[r] = amplitude_curve(
            t[::k],
            y[::k],
            quantity="displacement",
            band=(0.5 * f, 1.5 * f),
            n_periods=4,
            compare=False,
        )
    return out


def test_two_modes_couple_through_one_iwan_element_as_an_independent_stepping_says():
    """Two masses with one exact Iwan element between them, released in mode 1 (slipping
    the element) and mode 2 together and each alone: the Exudyn run (compiled interface)
    follows the independent numpy stepping of IwanJoint, and the coupling figure (mode 2's
    damping with mode 1 over alone) is the same on both routes, and large: mode 1's slip
    raises mode 2's damping."""
    amp = {1: 5e-5, 2: 2e-5}
    n = int(3.0 / H)
    figs = {}
    for route in (_numpy_route, _exudyn_route):
        Qt = route(_release(amp), n)
        if route is _exudyn_route:
            np.testing.assert_allclose(Qt, figs["traj"], rtol=0, atol=1e-6 * np.max(np.abs(Qt)))
        figs["traj"] = Qt
        together = _curves(Qt, (1, 2))
        alone = {r: _curves(route(_release({r: amp[r]}), n), (r,))[r] for r in (1, 2)}
        figs[route.__name__] = {r: compare_curves(together[r], alone[r]) for r in (1, 2)}
    ex, ref = figs["_exudyn_route"][2], figs["_numpy_route"][2]
    assert len(ex["amplitude"]) >= 3
    np.testing.assert_allclose(ex["damping_ratio"], ref["damping_ratio"], rtol=1e-3)
    assert np.max(ref["damping_ratio"]) > 1.2  # the coupling is visible (1.33)


def test_mode_coupling_refuses_a_single_mode():
    with pytest.raises(ValueError, match="at least two modes"):
        mode_coupling(TWO_BOLT, amplitude={1: 1e-4}, duration=0.5)


def test_an_impact_leaves_each_mode_ringing_at_its_linear_impulse_amplitude():
    """A half-sine pulse on the stuck two-bolt beam: mode 2 rings at ``|S phi| |phi(x_F)|
    |F^(w)| / w`` (the pulse's Fourier magnitude, the linear impulse response), and the
    energy balance books the pulse's work."""
    s = TWO_BOLT.replace(friction=1e4)
    imp = models.Impact(position=0.3, peak_force=50.0, contact_time=2e-3)
    r = ringdown(s, impact=imp, modes=(2,), duration=0.2, steps_per_period=32, record_energy=True)
    w, phi, _, L, _ = linear_modes(s, mode=2)
    X = (
        abs(float(L.S @ phi))
        * abs(float(axis_rows(s, [0.3])[0] @ phi))
        * float(imp.spectrum(w))
        / w
    )
    after = (r.t > 0.01) & (r.t < 0.01 + 4 * math.pi / w)
    peak = np.max(np.abs(r.modal[after])) * math.exp(s.floor(2) * w * 0.01)
    assert peak == pytest.approx(X, rel=0.01)
    assert r.max_energy_error < 1e-4 and r.energy["input_work"][-1] > 0
    assert r.metadata["h"] <= imp.contact_time / 16
    for kw, match in (({"amplitude": 1e-4}, "one of them"), ({"mode": 2}, "mode is for a release")):
        with pytest.raises(ValueError, match=match):
            ringdown(s, impact=imp, duration=0.1, **kw)
    with pytest.raises(ValueError, match="contact_time"):
        models.Impact(position=0.3, peak_force=50.0, contact_time=0.0)


def test_mode_coupling_shows_what_each_named_effect_adds_to_each_mode():
    """A modal viscous effect on mode 1 (``zeta_v``, added to mode 1's damping ratio and to
    no other mode's: its declared modal form) seen through ``effects=True``: mode 1's damping
    with it minus without it is ``zeta_v``, mode 2's unchanged."""
    zv = 5e-4
    s = TWO_BOLT.replace(effects=(SpecimenEffect("viscous_damping", (("zeta_v", zv),), mode=1),))
    with pytest.raises(ValueError, match="carries none"):
        mode_coupling(TWO_BOLT, amplitude={1: 1e-4, 2: 1e-5}, duration=0.5, effects=True)
    c = mode_coupling(s, amplitude={1: 1e-4, 2: 1e-5}, duration=0.8, effects=True)
    assert set(c.without) == {"viscous_damping"}
    f1, f2 = c.effect_figures[(1, "viscous_damping")], c.effect_figures[(2, "viscous_damping")]
    assert len(f1["amplitude"]) >= 3 and len(f2["amplitude"]) >= 3
    np.testing.assert_allclose(f1["damping"] - f1["damping_reference"], zv, rtol=0.05)
    np.testing.assert_allclose(f2["damping_ratio"], 1.0, atol=2e-3)
    assert c.effect_summary()[(1, "viscous_damping")]["max_damping_ratio"] > 1.1
    assert "mode 1, viscous_damping: damping x" in c.report()
    assert len(c.to_dataframe("effects")) == len(f1["amplitude"]) + len(f2["amplitude"])
    assert "1:viscous_damping" in c.to_dict()["effect_summary"]


def test_an_effect_in_the_joint_shows_in_every_mode_it_slips():
    """A dashpot in the joint (``InterfaceEffect``, shared by ``KT_i``) seen through
    ``effects=True`` adds to each mode ``sum_i c_i (G phi_r)_i^2 / (2 w_r)`` (light damping,
    mass-normalised stuck modes; an independent first-order route): to mode 2 as well,
    which the modal form on mode 1 never reaches."""
    c = 2e4
    eff = InterfaceEffect("viscous_damping", values={"c": c})
    s = TWO_BOLT.replace(interface_effects=(eff,))
    res = mode_coupling(s, amplitude={1: 1e-4, 2: 1e-5}, duration=0.8, effects=True)
    share = point_weights(s, eff)
    for r in (1, 2):
        w, phi, _, L, _ = linear_modes(s, mode=r)
        added = float(np.sum(c * share * (L.G @ phi) ** 2) / (2 * w))
        f = res.effect_figures[(r, "viscous_damping")]
        assert len(f["amplitude"]) >= 3
        np.testing.assert_allclose(f["damping"] - f["damping_reference"], added, rtol=0.06)
