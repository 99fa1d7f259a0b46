"""The lap-jointed beam's virtual tests on a Specimen: natural frequencies against an
independent Euler-Bernoulli model, the quasi-static machine test against the closed-form
dissipation, the stuck (linear) limits of the ring-down and of the stepped sine against the
linear system, and the slips of a bending mode. (Energy balance of the ring-down and QSMA
against the ring-down: tests/test_qsma.py.)"""

import math

import numpy as np
import pytest
from iwan_element.models import (
    forced_response,
    natural_frequencies,
    preset,
    quasi_static_test,
    ringdown,
)
from iwan_element.models.modal import linear_modes
from iwan_element.models.reduced import contact_points, floor_damping
from scipy.linalg import eigh

#: the example specimen (two plain 200 x 40 x 10 mm steel bars), contact points thinned out
EXAMPLE = preset("example").replace(n_points=12)


def euler_bernoulli_assembly(s, *, tangential: bool, n_per_beam: int = 160):
    """Independent reference: two Euler-Bernoulli frames (Hermite bending + linear axial
    elements, consistent mass) with nodes at the contact points, clamped at x = 0 and tied
    at the interface by the specimen's contact springs (surface point of a frame at distance
    y from its axis: u_s = u - y theta, v_s = v). Plain bars only (lap_thickness ==
    thickness). Returns the three lowest eigenfrequencies [Hz]."""
    assert s.lap_thickness == s.thickness and s.boundary == "clamped-free"
    E, rho, b, h = s.youngs_modulus, s.density, s.width, s.thickness
    A, I = b * h, b * h**3 / 12
    pts = contact_points(s)

    def nodes(x0):
        x = np.linspace(x0, x0 + s.beam_length, n_per_beam + 1)
        c = pts.x[(pts.x > x0) & (pts.x < x0 + s.beam_length)]
        far = np.min(np.abs(x[:, None] - c[None, :]), axis=1) > 1e-6  # no tiny elements
        far[[0, -1]] = True
        return np.sort(np.concatenate([x[far], c]))

    xa, xb = nodes(0.0), nodes(s.lap_start)
    na = len(xa)
    ndof = 3 * (na + len(xb))  # (u, v, theta) per node
    K = np.zeros((ndof, ndof))
    M = np.zeros((ndof, ndof))

    def add_beam(x, off):
        for e in range(len(x) - 1):
            L = x[e + 1] - x[e]
            ka = E * A / L * np.array([[1, -1], [-1, 1]])
            ma = rho * A * L / 6 * np.array([[2, 1], [1, 2]])
            kb = (
                E
                * I
                / L**3
                * np.array(
                    [
                        [12, 6 * L, -12, 6 * L],
                        [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                        [-12, -6 * L, 12, -6 * L],
                        [6 * L, 2 * L * L, -6 * L, 4 * L * L],
                    ]
                )
            )
            mb = (
                rho
                * A
                * L
                / 420
                * np.array(
                    [
                        [156, 22 * L, 54, -13 * L],
                        [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                        [54, 13 * L, 156, -22 * L],
                        [-13 * L, -3 * L * L, -22 * L, 4 * L * L],
                    ]
                )
            )
            i, j = off + 3 * e, off + 3 * (e + 1)
            ia, ib = [i, j], [i + 1, i + 2, j + 1, j + 2]
            K[np.ix_(ia, ia)] += ka
            M[np.ix_(ia, ia)] += ma
            K[np.ix_(ib, ib)] += kb
            M[np.ix_(ib, ib)] += mb

    add_beam(xa, 0)
    add_beam(xb, 3 * na)
    for xc, kt, kn in zip(pts.x, pts.KT, pts.normal_stiffness):
        ia = 3 * int(np.argmin(abs(xa - xc)))
        ib = 3 * na + 3 * int(np.argmin(abs(xb - xc)))
        # tangential: (u_b + h/2 th_b) - (u_a - h/2 th_a); normal: v_b - v_a
        gt = np.zeros(ndof)
        gt[[ib, ib + 2, ia, ia + 2]] = [1, h / 2, -1, h / 2]
        gn = np.zeros(ndof)
        gn[[ib + 1, ia + 1]] = [1, -1]
        K += (kt if tangential else 0.0) * np.outer(gt, gt) + kn * np.outer(gn, gn)
    free = np.setdiff1d(np.arange(ndof), [0, 1, 2])  # clamp u, v, theta of A's first node
    w2 = eigh(
        K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True, subset_by_index=[0, 2]
    )
    return np.sqrt(np.abs(w2)) / (2 * math.pi)


@pytest.mark.parametrize("interface", ["stuck", "none"])
def test_natural_frequencies_match_an_euler_bernoulli_frame_model(interface):
    """With the joint stuck (contact points at KT_i) and without it (normal springs only:
    beam B's axial sliding is a 0 Hz mode), the 1-D model's frequencies with its
    Euler-Bernoulli option are those of a fine Euler-Bernoulli frame model with the same
    contact springs (its Timoshenko elements: tests/test_beam_fe.py)."""
    s = EXAMPLE.replace(n_elements=32, beam_theory="euler-bernoulli")
    f = natural_frequencies(s, n_modes=3, interface=interface)
    ref = euler_bernoulli_assembly(s, tangential=interface == "stuck")
    if interface == "none":  # the sliding mode is 0 Hz up to round-off in both
        assert max(f[0], ref[0]) < 0.05 * ref[1]
        f, ref = f[1:], ref[1:]
    np.testing.assert_allclose(f, ref, rtol=2e-3)  # measured: 3e-4 and 4e-4 at most
    if interface == "stuck":
        assert f[0] == pytest.approx(linear_modes(s)[0] / (2 * math.pi), rel=1e-9)
        # the reference itself is converged: halving its mesh changes f3 by < 0.1 %
        assert (
            abs(euler_bernoulli_assembly(s, tangential=True, n_per_beam=80)[2] / ref[2] - 1) < 1e-3
        )
    else:  # without the joint the bending mode is lower
        assert f[0] < natural_frequencies(s, n_modes=1)[0]


def test_quasi_static_loops_equal_the_closed_form_dissipation():
    """Machine test at 0.1 mm (the lap's edge points in macroslip): each contact point's last
    loop (trapezoid of its recorded force over its slip) is its closed-form dissipation at
    its slip amplitude, the interface's own dissipation record over the cycle is their sum,
    and the machine force is the force through the lap (axial equilibrium of the grip side)."""
    r = quasi_static_test(EXAMPLE, amplitude=1e-4, cycles=2, steps_per_cycle=160)
    area, closed = r.loop_check()
    np.testing.assert_allclose(area, closed, rtol=0, atol=1e-3 * closed.sum())
    assert r.success and not r.warnings
    summary = r.summary()
    assert summary["dissipation_per_cycle_J"] == pytest.approx(closed.sum(), rel=1e-3)
    Fs = contact_points(EXAMPLE).Fs.sum()
    np.testing.assert_allclose(
        r.machine_force, r.joint_force, rtol=0, atol=1e-5 * Fs
    )  # 10 x Newton's
    assert 0 < summary["mean_slip_amplitude_m"] < 1e-4
    assert summary["machine_force_amplitude_N"] <= Fs * (1 + 1e-5)  # at most full slip
    assert "loop areas" in r.report() and r.to_dict()["success"] is True


def test_stuck_ring_down_is_the_linear_mode():
    """A friction so high that nothing slips, no damping floor: the ring-down's frequency is
    the stuck natural frequency and its damping vanishes (the time integration adds none)."""
    s = EXAMPLE.replace(friction=1e4, damping_floor=0.0)
    r = ringdown(s, amplitude=1e-4, cycles=16, steps_per_period=32)
    f0 = natural_frequencies(s, n_modes=1)[0]
    assert len(r.curve) >= 2
    np.testing.assert_allclose(r.curve.frequency, f0, rtol=1e-5)
    assert np.max(r.curve.damping_ratio) < 1e-5


def test_ring_down_with_linear_springs_is_the_stuck_mode_at_its_floor():
    """tangential="linear": springs KT_i instead of the Iwan elements (the release state is
    still the Iwan one): the stuck frequency, the floor, and the energy balance closed with
    no joint terms."""
    s = preset("brake-reuss").replace(n_points=8)
    r = ringdown(
        s, amplitude=30e-6, cycles=16, steps_per_period=32, record_energy=True, tangential="linear"
    )
    f0 = natural_frequencies(s, n_modes=4)[-1]
    assert r.metadata["tangential"] == "linear" and not np.any(r.energy["joint_dissipated"])
    np.testing.assert_allclose(r.curve.frequency, f0, rtol=1e-5)  # measured 1e-6
    np.testing.assert_allclose(r.curve.damping_ratio, s.floor(1), rtol=0.02)  # 0.7 %
    assert r.max_energy_error < 1e-4  # measured 5e-6


def test_stuck_stepped_sine_is_the_linear_frequency_response():
    """Stepped sine with nothing slipping and a 5 % floor (the modal damping matrix ``C``):
    the steady amplitudes are the linear system's frequency response
    ``|S (K - w^2 M + i w C)^-1 S|`` (force and sensor at the tip) at the frequencies asked
    for (the force pre-warped, ``models.simulation.prewarp``). ``C`` itself is checked against
    its definition in tests/test_every_mode.py."""
    s = EXAMPLE.replace(friction=1e4, damping_floor=0.05)
    w0, _, _, L, pts = linear_modes(s)
    freqs = np.linspace(0.9, 1.1, 5) * w0 / (2 * math.pi)
    spp = 32
    r = forced_response(
        s,
        force_levels=(1.0,),
        frequencies=freqs,
        settle_cycles=25,
        measure_cycles=3,
        steps_per_period=spp,
    )
    C = floor_damping(s).C
    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    ref = []
    for f in freqs:
        w = 2 * math.pi * f
        ref.append(abs(L.S @ np.linalg.solve(K - w * w * L.M + 1j * w * C, L.S)))
    np.testing.assert_allclose(r.amplitude[0], ref, rtol=0.01)
    assert r.success and r.peaks()[0][0] == pytest.approx(freqs[2])


def test_bending_mode_slips_the_lap_in_both_directions():
    """In the first bending mode of the clamped-free bars, axial equilibrium of beam B
    leaves the contact points' net tangential force near zero: the two sides of the bolt
    slip in opposite directions."""
    w0, phi, _, L, pts = linear_modes(EXAMPLE)
    g = L.G @ phi
    assert g.min() < 0 < g.max()
    assert abs(np.sum(pts.KT * g)) < 0.05 * np.sum(np.abs(pts.KT * g))


def test_options_are_validated():
    with pytest.raises(ValueError, match="cycles"):
        quasi_static_test(EXAMPLE, cycles=2.5)
    with pytest.raises(ValueError, match="amplitude"):
        quasi_static_test(EXAMPLE, amplitude=-1e-4)
    with pytest.raises(ValueError, match="frequencies"):
        forced_response(EXAMPLE, frequencies=[0.0])
    with pytest.raises(ValueError, match="frequencies must be at least 3 values stepped"):
        forced_response(EXAMPLE, frequencies=[50.0, 52.0, 51.0])
    with pytest.raises(ValueError, match="force_levels"):
        forced_response(EXAMPLE, force_levels=[])
    with pytest.raises(ValueError, match="interface"):
        natural_frequencies(EXAMPLE, interface="bonded")


def test_a_sweep_that_misses_the_resonance_says_so():
    """Every frequency below the resonance: the largest amplitude is at the last one, so the
    result is not a success and warns (returned, not raised, on the frozen result)."""
    f1 = natural_frequencies(EXAMPLE, n_modes=1)[0]
    r = forced_response(
        EXAMPLE,
        force_levels=(1.0,),
        frequencies=np.array([0.90, 0.93, 0.96]) * f1,
        settle_cycles=4,
        measure_cycles=2,
        steps_per_period=16,
    )
    assert not r.success
    assert any("not inside the sweep" in w for w in r.warnings)
    assert np.argmax(r.amplitude[0]) == 2
