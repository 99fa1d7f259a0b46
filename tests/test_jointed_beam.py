"""The jointed-beam model: mesh convergence against an independent Euler-Bernoulli model, the
quasi-static test, energy balance and amplitude-dependent frequency and damping in free decay."""
import math

import numpy as np
import pytest
from scipy.linalg import eigh

from iwan_element import IwanParameters, dissipation
from iwan_element.models.jointed_beam import (M16_JOINT, JointedBeamConfig,
                                              build_jointed_beam)
from iwan_element.models.scenarios import (decay_analysis, free_decay, modal_analysis,
                                           quasi_static_test)

# a lightly preloaded bolt: small phi_max, so bending slips reach a good part of it
LOOSE = JointedBeamConfig(joint=M16_JOINT.replace(Fs=150.0))


def euler_bernoulli_assembly(cfg: JointedBeamConfig, n_per_beam: int = 160):
    """Independent reference: two Euler-Bernoulli frames (Hermite bending + linear axial
    elements, consistent mass) with nodes at the contact points, clamped at x = 0 and tied
    at the interface by the same springs as the Exudyn model (surface point of a frame at
    distance y from its axis: u_s = u - y theta, v_s = v). Returns the eigenfrequencies [Hz]."""
    E, rho, b, h = cfg.youngs_modulus, cfg.density, cfg.width, cfg.thickness
    A, I = b * h, b * h ** 3 / 12
    xs_c = cfg.contact_x()

    def nodes(x0):
        x = np.linspace(x0, x0 + cfg.beam_length, n_per_beam + 1)
        return np.unique(np.concatenate([x, xs_c[(xs_c > x0) & (xs_c < x0 + cfg.beam_length)]]))

    xa, xb = nodes(0.0), nodes(cfg.beam_length - cfg.overlap)
    na, nb = len(xa), len(xb)
    ndof = 3 * (na + nb)                           # (u, v, theta) per node
    K = np.zeros((ndof, ndof))
    M = np.zeros((ndof, ndof))

    def add_beam(x, off):
        for e in range(len(x) - 1):
            L = x[e + 1] - x[e]
            ka = E * A / L * np.array([[1, -1], [-1, 1]])
            ma = rho * A * L / 6 * np.array([[2, 1], [1, 2]])
            kb = E * I / L ** 3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                             [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
            mb = rho * A * L / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                                [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
            i, j = off + 3 * e, off + 3 * (e + 1)
            ia = [i, j]
            ib = [i + 1, i + 2, j + 1, j + 2]
            K[np.ix_(ia, ia)] += ka
            M[np.ix_(ia, ia)] += ma
            K[np.ix_(ib, ib)] += kb
            M[np.ix_(ib, ib)] += mb

    add_beam(xa, 0)
    add_beam(xb, 3 * na)
    n = cfg.n_contact_points
    kt = cfg.rigid_stiffness
    kn = cfg.normal_stiffness / n
    for xc in xs_c:
        ia = 3 * int(np.argmin(abs(xa - xc)))
        ib = 3 * na + 3 * int(np.argmin(abs(xb - xc)))
        # tangential: (u_b + h/2 th_b) - (u_a - h/2 th_a); normal: v_b - v_a
        gt = np.zeros(ndof)
        gt[[ib, ib + 2, ia, ia + 2]] = [1, h / 2, -1, h / 2]
        gn = np.zeros(ndof)
        gn[[ib + 1, ia + 1]] = [1, -1]
        K += kt * np.outer(gt, gt) + kn * np.outer(gn, gn)
    free = np.setdiff1d(np.arange(ndof), [0, 1, 2])      # clamp u, v, theta of A's first node
    w2 = eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True,
              subset_by_index=[0, 5])
    return np.sqrt(w2) / (2 * math.pi)


def test_rigid_joint_bending_frequencies_match_euler_bernoulli():
    cfg = JointedBeamConfig(joint_model="rigid")
    m = build_jointed_beam(cfg)
    w2, _ = m.mbs.ComputeODE2Eigenvalues(constrainedCoordinates=m.clamped_coordinates,
                                         ignoreAlgebraicEquations=True, numberOfEigenvalues=3)
    f_exudyn = np.sqrt(w2) / (2 * math.pi)
    f_eb = euler_bernoulli_assembly(cfg)[:3]
    np.testing.assert_allclose(f_exudyn, f_eb, rtol=0.01)
    # the reference itself is converged: halving its mesh changes f3 by < 0.1 %
    assert abs(euler_bernoulli_assembly(cfg, 80)[2] / f_eb[2] - 1) < 1e-3


def test_uniform_cantilever_limit_matches_theory():
    """Sanity of the reference and of the Cable2D mesh: a single beam clamped-free."""
    cfg = JointedBeamConfig()
    L = cfg.beam_length
    f1 = 1.875104068711961 ** 2 / (2 * math.pi) * math.sqrt(cfg.EI / (cfg.mass_per_length * L ** 4))
    m = build_jointed_beam(cfg)
    # beam A alone: clamp it, do not attach B (use its eigenvalue via a separate model)
    import exudyn as exu
    from exudyn.itemInterface import (CoordinateConstraint, MarkerNodeCoordinate,
                                      NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = cfg.n_elements
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * L / n, 0, 1, 0])) for i in range(n + 1)]
    for i in range(n):
        mbs.AddObject(ObjectANCFCable2D(massPerLength=cfg.mass_per_length,
                                        bendingStiffness=cfg.EI, axialStiffness=cfg.EA,
                                        length=L / n, nodeNumbers=[nodes[i], nodes[i + 1]]))
    g = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    for c in (0, 1, 3):
        mbs.AddObject(CoordinateConstraint(markerNumbers=[g, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))]))
    mbs.Assemble()
    w2, _ = mbs.ComputeODE2Eigenvalues(constrainedCoordinates=[0, 1, 3], ignoreAlgebraicEquations=True,
                                       numberOfEigenvalues=1)
    assert math.sqrt(w2[0]) / (2 * math.pi) == pytest.approx(f1, rel=1e-4)
    assert m.config.total_length == pytest.approx(2 * L - cfg.overlap)


def test_quasi_static_loop_area_equals_dissipation():
    r = quasi_static_test(amplitude=1e-4, cycles=2, steps_per_cycle=160)
    last = r.last_cycle()
    pj = r.config.point_joint
    for k in range(r.config.n_contact_points):
        s, F = r.joint_slip[k, last], r.joint_force[k, last]
        area = np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(s))          # trapezoid of the records
        s0 = 0.5 * (s.max() - s.min())
        assert area == pytest.approx(dissipation(s0, pj), rel=1e-3)
    # machine force equals the force through the joint (axial equilibrium of the grip side)
    np.testing.assert_allclose(r.machine_force, r.total_joint_force, rtol=0, atol=1e-6 * pj.Fs)
    summary = r.summary()
    assert 0 < summary["joint_slip_amplitude_m"][0] < 1e-4


def test_linear_limit_iwan_with_huge_slip_force_equals_linear_joint():
    cfg = JointedBeamConfig(joint=M16_JOINT.replace(Fs=1e15))
    res = free_decay(cfg, levels=(1e-3,), cycles=6, steps_per_period=60)
    a, b = res.runs[0], res.linear_runs[0]
    assert np.max(np.abs(a.tip - b.tip)) <= 1e-6 * np.max(np.abs(b.tip))


@pytest.fixture(scope="module")
def loose_decay():
    return free_decay(LOOSE, levels=(3e-4, 1e-3), cycles=24, steps_per_period=80,
                      record_energy=True, energy_every=4)


def test_free_decay_energy_balance(loose_decay):
    f1 = loose_decay.modal.frequencies[0]
    for run in loose_decay.runs:
        E = run.energy
        after = E["t"] >= 0.1 / f1          # once the release ramp is over
        total = sum(E[k] for k in ("kinetic", "strain", "springs", "joint_stored",
                                   "joint_dissipated"))[after]
        assert np.max(np.abs(total / total[0] - 1)) < 1e-3
        assert E["joint_dissipated"][-1] > E["joint_dissipated"][after][0]


def test_free_decay_trends_slope_and_prediction(loose_decay):
    res = loose_decay
    a, f, z = res.curves()
    a_lin, f_lin, z_lin = res.curves("linear")
    # damping rises and frequency falls with amplitude
    lo, hi = res.runs[0], res.runs[1]
    assert np.median(hi.damping) > np.median(lo.damping) > 0
    assert np.median(hi.frequency) < np.median(lo.frequency)
    # the linear joint neither damps nor shifts
    assert np.max(np.abs(z_lin)) < 2e-2 * np.median(lo.damping)
    # small-amplitude log-log slope of damping vs amplitude = chi + 1
    slope = math.log(np.median(hi.damping) / np.median(lo.damping)) / math.log(
        np.median(hi.amplitude) / np.median(lo.amplitude))
    assert slope == pytest.approx(LOOSE.joint.chi + 1, abs=0.05)
    # measured curves against the closed-form single-mode prediction
    fp, zp = res.modal.predict(a)
    np.testing.assert_allclose(z, zp, rtol=0.05)
    # the frequency itself changes by ~1e-6 relative, so an rtol on f cannot fail; compare
    # the amplitude-dependent *shift* from the linear frequency, per point, against the
    # predicted shift (measured shift: minus the linear-joint run's frequency, which removes
    # the integrator's period error), to a quarter of the largest predicted shift
    shift_meas = f - np.median(f_lin)
    shift_pred = fp - res.modal.frequencies[0]
    assert np.max(np.abs(shift_pred)) > 0
    np.testing.assert_allclose(shift_meas, shift_pred, rtol=0,
                               atol=0.25 * np.max(np.abs(shift_pred)))
    # the frequency drop itself, with the integrator's period error removed via the
    # linear-joint run, within 20 %
    f0_meas = np.median(f_lin)
    drop_meas = f0_meas - np.median(hi.frequency)
    fp_hi, _ = res.modal.predict(np.median(hi.amplitude))
    drop_pred = res.modal.frequencies[0] - fp_hi[0]
    assert drop_meas == pytest.approx(drop_pred, rel=0.2)


def test_decay_analysis_recovers_known_damping():
    f, z = 50.0, 2e-4
    w = 2 * math.pi * f
    t = np.arange(4000) / (f * 80)
    x = np.exp(-z * w * t) * np.cos(w * math.sqrt(1 - z * z) * t) + 0.3
    amp, freq, damp = decay_analysis(t, x)
    np.testing.assert_allclose(damp, z, rtol=1e-4)
    np.testing.assert_allclose(freq, f * math.sqrt(1 - z * z), rtol=1e-6)
    with pytest.raises(ValueError, match="too few extremes"):
        decay_analysis(t[:100], x[:100])


@pytest.mark.parametrize("kw,match", [
    (dict(overlap=0.3), "overlap"), (dict(n_contact_points=0), "n_contact_points"),
    (dict(joint_model="bonded"), "joint_model"), (dict(thickness=-1.0), "thickness"),
    (dict(contact_spacing=0.2), "inside the overlap"), (dict(boundary="pinned"), "boundary"),
])
def test_config_validation(kw, match):
    with pytest.raises(ValueError, match=match):
        JointedBeamConfig(**kw)


def test_modal_slip_participation_is_antisymmetric_in_bending():
    m = modal_analysis(JointedBeamConfig())
    g = m.slip_per_q[:, 0]
    assert g[0] * g[1] < 0          # the two sides of the bolt slip in opposite directions
    assert isinstance(m.config.point_joint, IwanParameters)


def test_scenario_and_config_options_are_validated():
    with pytest.raises(ValueError, match="unknown JointedBeamConfig fields"):
        JointedBeamConfig().replace(overlapp=0.01)
    with pytest.raises(ValueError, match="contact_spacing"):
        JointedBeamConfig(contact_spacing="a")
    with pytest.raises(ValueError, match="cycles"):
        quasi_static_test(cycles=2.5)
    from iwan_element.models.scenarios import forced_response
    with pytest.raises(ValueError, match="frequencies"):
        forced_response(frequencies=[0.0])
    with pytest.raises(ValueError, match="force_levels"):
        forced_response(force_levels=[])
