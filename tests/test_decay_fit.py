"""fit_decay: the modal Iwan model fitted directly to the analytic signal of a free decay.

Truths come from routes that share no code with the fit (``tests/_decays.py``): the
slowly-varying-amplitude equations integrated by ``solve_ivp`` with the closed-form curves, and
the exact Iwan oscillator in time. The covariance is checked against the scatter of repeated
seeded fits, the noise correlation against simulated noise, the quadrature against
``solve_ivp``.
"""

from __future__ import annotations

import json
import math

import matplotlib

matplotlib.use("Agg")
import numpy as np
import pytest
from _decays import joint_decay, svam_decay
from scipy import signal
from scipy.integrate import solve_ivp

from iwan_element import IwanParameters, ModalIwanFit, fit_decay, modal_iwan_curve
from iwan_element.identify.decays import _fit_model as D

F0 = 80.0
PHI_MAX = 1e-3


def _joint(kappa=0.05, chi=-0.5, beta=0.5):
    w02 = (2 * math.pi * F0) ** 2
    KT = kappa * w02
    c = beta + (chi + 1) / (chi + 2)
    return IwanParameters(KT * c * PHI_MAX / (1 + beta), KT, chi, beta), w02 - KT


P, K_INF = _joint()


def _reference_decay(fr, dm, a0, T):
    """``(t, [ln a, theta])`` of the averaging equations by an independent ODE solver (DOP853
    to 1e-12) from ``a0`` over ``T`` [s], 301 samples."""

    def rhs(_, s):
        a = math.exp(s[0])
        zz, w = float(dm(a)), 2 * math.pi * float(fr(a))
        return [-zz * w, w * math.sqrt(1 - zz * zz)]

    t = np.linspace(0.0, T, 301)
    return t, solve_ivp(
        rhs, (0, T), [math.log(a0), 0.0], t_eval=t, rtol=1e-12, atol=1e-12, method="DOP853"
    ).y


def _curves(zeta0, p=P, k_inf=K_INF):
    def both(a):
        a = np.asarray(a, dtype=float)
        f, z = modal_iwan_curve(
            np.atleast_1d(a),
            p,
            K_inf=k_inf,
            zeta0=zeta0,
            stiffness="harmonic",
            floor="dashpot",
            damping_form="decay",
        )
        return np.asarray(f).reshape(a.shape), np.asarray(z).reshape(a.shape)

    return (lambda a: both(a)[0]), (lambda a: both(a)[1])


def _truth(fit, zeta0, p=P, k_inf=K_INF):
    x_ref = fit.conventions["x_ref"]
    w02 = k_inf + p.KT
    return {
        "f0": math.sqrt(w02) / (2 * math.pi),
        "zeta0": zeta0,
        "chi": p.chi,
        "delta": p.KT * (x_ref / p.phi_max) ** (p.chi + 1) / (w02 * (p.chi + 2) * (1 + p.beta)),
        "beta": p.beta,
        "kappa": p.KT / w02,
        "phi_max": p.phi_max,
        "KT": p.KT,
        "K_inf": k_inf,
        "Fs": p.Fs,
    }


def _svam(
    zeta0=2e-3,
    a0=1e-4,
    duration=2.0,
    fs=2000.0,
    quantity="acceleration",
    noise=0.01,
    second=0.3,
    seed=0,
    ratio=1.3,
):
    f, z = _curves(zeta0)
    return svam_decay(
        f,
        z,
        a0=a0,
        duration=duration,
        fs=fs,
        quantity=quantity,
        ratio=ratio,
        second=second,
        noise=noise,
        rng=np.random.default_rng(seed),
    )


# ------------------------------------------------------------------ building blocks
def test_quadrature_trajectory_matches_solve_ivp():
    """Amplitude and phase by quadrature in ln a equal solve_ivp of the averaging equations."""
    zeta0 = 5e-3
    fr, dm = _curves(zeta0)
    a0, T = 3e-4, 1.5

    t, ref = _reference_decay(fr, dm, a0, T)
    prob = D._Problem(
        np.zeros(4096),
        2000.0,
        (70.0, 90.0),
        4,
        2,
        dict(stiffness="harmonic", floor="dashpot", x_ref=3e-5),
    )
    prob.span = 12.0
    w02 = K_INF + P.KT
    theta = [
        math.sqrt(w02) / (2 * math.pi),
        zeta0,
        P.chi,
        P.KT * (3e-5 / P.phi_max) ** (P.chi + 1) / (w02 * (P.chi + 2) * (1 + P.beta)),
    ]
    out = prob.trajectory(np.array(theta), "microslip", math.log(a0), t)
    assert np.max(np.abs(out[:, 0] - ref[0])) < 1e-6  # ln a
    assert np.max(np.abs(out[:, 1] - ref[1])) < 1e-5  # phase [rad], ~750 rad total


def test_quadrature_through_phi_max_matches_solve_ivp():
    """Released at 3 phi_max: the decay-form damping jumps where the amplitude passes phi_max
    (the sliders at phi_max leave the tangent at once); the split quadrature equals solve_ivp
    of the averaging equations with the closed-form curves across the jump."""
    zeta0 = 2e-3
    fr, dm = _curves(zeta0)
    a0, T = 3 * PHI_MAX, 1.5
    assert float(dm(PHI_MAX * (1 + 1e-9))) > float(dm(PHI_MAX * (1 - 1e-9))) * 1.001

    t, ref = _reference_decay(fr, dm, a0, T)
    assert ref[0, -1] < math.log(0.3 * PHI_MAX)  # the decay passes phi_max
    prob = D._Problem(
        np.zeros(4096),
        2000.0,
        (70.0, 90.0),
        4,
        2,
        dict(stiffness="harmonic", floor="dashpot", x_ref=3e-4),
    )
    prob.span = 12.0
    w02 = K_INF + P.KT
    theta = np.array(
        [math.sqrt(w02) / (2 * math.pi), zeta0, P.chi, P.KT / w02, math.log(P.phi_max), P.beta]
    )
    out = prob.trajectory(theta, "macroslip", math.log(a0), t)
    assert np.max(np.abs(out[:, 0] - ref[0])) < 1e-6  # ln a
    assert np.max(np.abs(out[:, 1] - ref[1])) < 1e-5  # phase [rad]


def test_model_record_is_smooth_in_phi_max():
    """The model record, as ln phi_max moves in 40 steps over 2.5 quadrature cells, changes
    smoothly: second differences stay far below first differences. (With a fixed grid it
    stepped whenever phi_max crossed a node, since the decay-form damping jumps at phi_max;
    finite differences then overstated the sensitivity ~50-fold and the stated stderr of
    phi_max was far too small: z = -68 in the benchmark.)"""
    prob = D._Problem(
        np.zeros(4000),
        2000.0,
        (70.0, 90.0),
        4,
        0,
        dict(stiffness="harmonic", floor="dashpot", x_ref=3e-4),
    )
    prob.span, prob.i_s = 8.0, 0
    w02 = K_INF + P.KT
    x = np.array(
        [
            math.sqrt(w02) / (2 * math.pi),
            2e-3,
            P.chi,
            P.KT / w02,
            math.log(P.phi_max),
            P.beta,
            math.log(3 * PHI_MAX),
            0.3,
        ]
    )
    cell = prob.span / (D._GRID - 1)
    recs = []
    for k in range(41):
        xk = x.copy()
        xk[4] += k * 2.5 * cell / 40
        recs.append(prob.record(xk, "macroslip"))
    d1 = np.linalg.norm(np.diff(recs, axis=0), axis=1)
    d2 = np.linalg.norm(np.diff(recs, n=2, axis=0), axis=1)
    assert d1.min() > 0.5 * d1.max()
    assert d2.max() < 0.05 * d1.min()


@pytest.mark.parametrize("regime", ["microslip", "macroslip"])
def test_jacobian_columns_equal_central_differences_of_the_record(regime):
    """The record's derivatives the fit's Jacobian is made of (one quadrature of all the
    curve parameters' steps, the time shift of ln a0, phi_s exactly) equal central
    differences of the model record itself, in microslip and released at 3 phi_max (two
    grid pieces); a record longer than the grid checks the continuation past it."""
    prob = D._Problem(
        np.zeros(4000),
        2000.0,
        (70.0, 90.0),
        4,
        2 if regime == "microslip" else 1,
        dict(stiffness="harmonic", floor="dashpot", x_ref=3e-4),
    )
    prob.span, prob.i_s = 8.0, 0
    w02 = K_INF + P.KT
    f0 = math.sqrt(w02) / (2 * math.pi)
    if regime == "microslip":
        delta = P.KT * (3e-4 / P.phi_max) ** (P.chi + 1) / (w02 * (P.chi + 2) * (1 + P.beta))
        x = np.array([f0, 2e-3, P.chi, delta, math.log(3e-4), 0.3])
    else:
        theta = [f0, 2e-3, P.chi, P.KT / w02, math.log(P.phi_max), P.beta]
        x = np.array([*theta, math.log(3 * PHI_MAX), 0.3])
    curve = [j for j in range(x.size - 2) if regime == "microslip" or j != 4]
    for span, ends in ((8.0, True), (1.0, False)):  # 1.0: the record runs past the grid
        prob.span = span
        steps = [(j, 1e-7 * max(abs(x[j]), 1e-2)) for j in curve]
        _, dy = prob.record(x, regime, steps)
        for c, j in enumerate(curve + [x.size - 2, x.size - 1]):
            if j == x.size - 2 and not ends:
                continue  # ln a0 also moves the grid's end, where the continuation starts
            h = 1e-5 * max(abs(x[j]), 1e-2)
            xp, xm = x.copy(), x.copy()
            xp[j] += h
            xm[j] -= h
            ref = (prob.record(xp, regime) - prob.record(xm, regime)) / (2 * h)
            err = np.linalg.norm(dy[:, c] - ref) / np.linalg.norm(ref)
            assert err < 3e-5, (regime, span, j, err)


def test_noise_correlation_matches_simulated_noise():
    """rho(tau) from |H|^4 equals the correlation of band-passed white noise's analytic signal."""
    prob = D._Problem(
        np.zeros(4096),
        1000.0,
        (70.0, 90.0),
        4,
        0,
        dict(stiffness="harmonic", floor="dashpot", x_ref=1.0),
    )
    rho = D._noise_correlation(prob, 60)
    x = np.random.default_rng(3).standard_normal(2**21)  # ~4e4 correlation times
    z = signal.hilbert(signal.sosfiltfilt(prob.sos, x))
    emp = np.array([np.mean(z[: z.size - k] * np.conj(z[k:])) for k in range(0, 61, 6)])
    emp /= emp[0]
    assert np.max(np.abs(emp - np.conj(rho[::6]))) < 0.025  # sampling error ~0.005


def test_noise_level_over_its_degrees_of_freedom_matches_simulated_noise():
    """The noise level and covariance of ``_covariance`` against simulated band-passed noise.

    A linear least-squares problem on the turned analytic signal of white noise (through the
    fit's own processing ``L``) with 12 slowly varying columns, about as many as the record
    has independent noise samples (a short record): the plain mean square of the residual
    understates the noise by a third; the sum of squares over ``m - tr(B Omega / s2)`` does
    not, its scatter matches the stated chi-square degrees of freedom, and the sandwich
    covariance matches the scatter of the estimates."""
    prob = D._Problem(
        np.zeros(1024),
        1000.0,
        (70.0, 90.0),
        4,
        0,
        dict(stiffness="harmonic", floor="dashpot", x_ref=1.0),
    )
    idx = np.arange(100, 900, 2)
    t = idx / 1000.0
    obj = type("Obj", (), dict(prob=prob, idx=idx, phd=2 * math.pi * 80.0 * t))()
    cols = np.column_stack([((t - 0.5) / 0.4) ** j for j in range(6)])
    zero = np.zeros_like(cols)
    J = np.vstack([np.hstack([cols, zero]), np.hstack([zero, cols])])
    rng = np.random.default_rng(5)
    s2_true, s2_plain, s2_dof, est, var = [], [], [], [], []
    for _ in range(300):
        rr = prob.apply(rng.standard_normal(1024))[idx] * np.exp(-1j * obj.phd)
        r = np.concatenate([rr.real, rr.imag])
        b, *_ = np.linalg.lstsq(J, r, rcond=None)
        res = r - J @ b
        cov, _, (dof, nu) = D._covariance(obj, res, J)
        s2_true.append(np.mean(np.abs(rr) ** 2))
        s2_plain.append(np.mean(res**2) * 2.0)
        s2_dof.append(np.sum(res**2) / dof)
        est.append(b)
        var.append(np.diag(cov))
    s2 = np.mean(s2_true)
    assert np.mean(s2_plain) < 0.8 * s2  # what the fit absorbed
    assert np.mean(s2_dof) == pytest.approx(s2, rel=0.05)  # sampling error ~2 %
    assert np.var(s2_dof) / s2**2 == pytest.approx(2.0 / nu, rel=0.3)
    ratio = np.var(est, axis=0) / np.mean(var, axis=0)
    assert np.all(np.abs(ratio - 1.0) < 0.3), ratio  # sampling error ~8 %


# ------------------------------------------------------------------ recovery
@pytest.mark.parametrize("quantity", ["displacement", "velocity", "acceleration"])
def test_noise_free_decay_recovers_the_curves(quantity):
    """Without noise or a second mode the fit returns the closed-form truth (the processing of
    data and model is the same, release included)."""
    d = _svam(zeta0=2e-3, a0=2e-4, duration=1.0, quantity=quantity, noise=0.0, second=0.0)
    fit = fit_decay(d.t, d.y, quantity=quantity, band=d.band)
    tr = _truth(fit, 2e-3)
    assert fit.regime == "microslip"
    assert fit.parameters["f0"] == pytest.approx(tr["f0"], rel=1e-6)
    assert fit.parameters["zeta0"] == pytest.approx(tr["zeta0"], rel=1e-3)
    assert fit.parameters["chi"] == pytest.approx(tr["chi"], abs=2e-3)
    assert fit.parameters["delta"] == pytest.approx(tr["delta"], rel=3e-3)
    f, z = fit.predict(np.array([1e-5, 1e-4]))
    ft, zt = _curves(2e-3)
    assert np.allclose(f, ft(np.array([1e-5, 1e-4])), rtol=1e-6)
    assert np.allclose(z, zt(np.array([1e-5, 1e-4])), rtol=2e-3)


def test_stderr_is_not_smaller_than_the_scatter_of_repeated_fits():
    """Over seeded noise (and a second mode of random phase) the spread of the estimates is
    not larger than the stated stderr, nor their mean further from the truth than the
    stderr of a mean allows.

    Found here: the stated stderr is conservative (scatter / stderr for f0, zeta0, chi: 0.48,
    0.67, 0.55 over seeds 0-9; 0.55, 0.75, 0.68 over the six kept, so the test fails once the
    stderr is understated by 2.1x); reported, not hidden by a two-sided bound.

    Six repetitions (were ten; each fit takes about 5.6 s): the ratio of the sample standard
    deviation to the stated stderr then follows sqrt(chi2_5 / 5) for calibrated errors, so
    the bound 1.6 passes a true stderr with probability 0.975 (per parameter) and catches one
    understated 2x, 2.5x, 3x with probability 0.67, 0.84, 0.92 (0.76, 0.93, 0.98 with ten;
    scipy.stats.chi2.sf(5 * (1.6 / k)**2, 5)).
    """
    est, sds = [], []
    for seed in range(6):
        d = _svam(zeta0=3e-3, a0=1e-4, duration=0.6, quantity="velocity", seed=seed)
        fit = fit_decay(d.t, d.y, quantity="velocity", band=d.band)
        est.append([fit.parameters[k] for k in ("f0", "zeta0", "chi")])
        sds.append([fit.stderr[k] for k in ("f0", "zeta0", "chi")])
        tr = _truth(fit, 3e-3)
    est, rms_sd = np.array(est), np.sqrt(np.mean(np.square(sds), axis=0))
    ratio = np.std(est, axis=0, ddof=1) / rms_sd
    assert np.all(ratio < 1.6), ratio
    truth = np.array([tr["f0"], tr["zeta0"], tr["chi"]])
    assert np.all(np.abs(est.mean(axis=0) - truth) < 3 * rms_sd / math.sqrt(len(est)) + 1e-12)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_exact_iwan_oscillator_within_three_stderr(seed):
    """The exact Iwan oscillator (virgin start, harmonics) against the first-order truth."""
    rng = np.random.default_rng(seed)
    zeta0 = float(rng.uniform(1e-3, 5e-3))
    q0 = float(rng.uniform(0.05, 0.3)) * PHI_MAX
    d = joint_decay(
        P,
        K_inf=K_INF,
        zeta0=zeta0,
        q0=q0,
        duration=1.5,
        fs=2000.0,
        quantity=("displacement", "velocity", "acceleration")[seed % 3],
        ratio=1.25,
        rng=rng,
    )
    fit = fit_decay(d.t, d.y, quantity=d.quantity, band=d.band)
    tr = _truth(fit, zeta0)
    assert fit.identified
    for k in fit.identified:
        assert abs(fit.parameters[k] - tr[k]) < 3 * fit.stderr[k], (k, fit.report())


def test_short_heavily_damped_decay_uses_the_release():
    """2.3 % damping, 30 periods to the noise, 1 % noise, no second mode: the fit starts at
    the release (nothing is trimmed), fixes f0 and zeta0 and follows the truth's curves over
    the decay. (With a strong nearby mode the transient its abrupt start leaks through the
    band-pass dominates so short a record; see docs/decay_fit.md, limits.)"""
    d = _svam(
        zeta0=0.02, a0=0.8 * PHI_MAX, duration=0.4, quantity="acceleration", seed=5, second=0.0
    )
    fit = fit_decay(d.t, d.y, quantity="acceleration", band=d.band)
    assert fit.conventions["t_fit"][0] == 0.0
    tr = _truth(fit, 0.02)
    for k in ("f0", "zeta0"):
        assert k in fit.identified
        assert abs(fit.parameters[k] - tr[k]) < 3 * fit.stderr[k]
    assert fit.stderr["zeta0"] < 0.05 * 0.02
    a_hi, a_lo = fit.conventions["amplitude_range"]
    X = np.geomspace(a_lo, a_hi, 5)
    f, z, fb, zb = fit.predict(X, band=0.997)
    ft, zt = _curves(0.02)
    assert np.all((fb[0] <= ft(X)) & (ft(X) <= fb[1]))
    assert np.all((zb[0] <= zt(X)) & (zt(X) <= zb[1]))
    assert np.all(zb[1] - zb[0] < 0.1 * zt(X))  # and the band is informative
    if set(fit.parameters) - set(fit.identified):
        assert not fit.success
        assert any("not identified" in w for w in fit.warnings)


def test_macroslip_release_identifies_the_joint():
    d = _svam(zeta0=2e-3, a0=3 * PHI_MAX, duration=1.5, quantity="displacement", seed=7)
    fit = fit_decay(d.t, d.y, quantity="displacement", band=d.band)
    assert fit.regime == "macroslip"
    tr = _truth(fit, 2e-3)
    for k in fit.identified:
        assert abs(fit.parameters[k] - tr[k]) < 3 * fit.stderr[k], (k, fit.report())
    assert {"phi_max", "KT", "Fs"} <= set(fit.identified)


def test_nearby_mode_is_modelled_not_taken_for_the_joint():
    """A strong linear mode 12 % above the band (released with the mode, so its abrupt start
    leaks through the band-pass): the fit models it as a neighbour, finds its frequency, and
    the joint's microslip parameters agree with the fit of the same decay without it."""
    base = _svam(
        zeta0=3e-3, a0=3e-4, duration=1.0, quantity="acceleration", seed=21, second=0.0, ratio=1.24
    )
    with_nb = _svam(
        zeta0=3e-3, a0=3e-4, duration=1.0, quantity="acceleration", seed=21, second=0.6, ratio=1.24
    )
    f_a = fit_decay(base.t, base.y, quantity="acceleration", band=base.band)
    f_b = fit_decay(with_nb.t, with_nb.y, quantity="acceleration", band=with_nb.band)
    nb = f_b.conventions["neighbour_modes"]
    assert len(nb) == 1 and nb[0]["frequency"] == pytest.approx(1.24 * with_nb.f0, rel=2e-3)
    tr = _truth(f_b, 3e-3)
    for k in ("f0", "zeta0", "chi", "delta"):
        assert k in f_b.identified
        assert abs(f_b.parameters[k] - tr[k]) < 3 * f_b.stderr[k], (k, f_b.report())
        assert f_b.stderr[k] < 3 * f_a.stderr[k]  # the neighbour costs little


def test_macroslip_release_next_to_a_mode_is_not_silently_microslip():
    """The exact Iwan oscillator released at 3 phi_max (1.4 % damping at the release), a
    linear mode 25 % above, 1 % noise (benchmark seed 38's setting, where the leak of the
    neighbour's start hid the macroslip and microslip was reported with success and chi 11
    stderr off): the fit reports the full model within 3 stderr, or says it failed."""
    p, k_inf = _joint(kappa=0.07, chi=-0.55, beta=0.75)
    d = joint_decay(
        p,
        K_inf=k_inf,
        zeta0=7e-3,
        q0=3 * PHI_MAX,
        duration=1.2,
        fs=2400.0,
        quantity="acceleration",
        ratio=1.25,
        rng=np.random.default_rng(38),
    )
    fit = fit_decay(d.t, d.y, quantity="acceleration", band=d.band)
    if fit.regime != "macroslip":
        assert not fit.success and any("phi_max" in w for w in fit.warnings), fit.report()
        return
    tr = _truth(fit, 7e-3, p=p, k_inf=k_inf)
    assert {"phi_max", "KT", "Fs", "beta"} <= set(fit.identified)
    for k in fit.identified:
        assert abs(fit.parameters[k] - tr[k]) < 3 * fit.stderr[k], (k, fit.report())


def test_short_macroslip_release_with_few_noise_samples_is_not_a_success():
    """Benchmark seed 100's setting: the exact Iwan oscillator released at 3 phi_max at
    about 2 % damping, a 0.34 s record (45 periods), a linear mode 12 % below, 1 % noise.
    Reported microslip with success and f0 10 stderr off before: the record holds so few
    independent noise samples beyond what the fit absorbs that the stated stderr cannot be
    trusted. Now every identified parameter is within 3 stderr of the truth, or the fit is no
    success and says why (the noise level's degrees of freedom, stated in the conventions)."""
    w02 = (2 * math.pi * 131.848) ** 2
    KT, chi, beta = 0.02344 * w02, -0.4017, 0.36
    p = IwanParameters(KT * (beta + (chi + 1) / (chi + 2)) * PHI_MAX / (1 + beta), KT, chi, beta)
    d = joint_decay(
        p,
        K_inf=w02 - KT,
        zeta0=0.01772,
        q0=3 * PHI_MAX,
        duration=0.3406,
        fs=3138.0,
        quantity="velocity",
        ratio=0.879,
        rng=np.random.default_rng(100),
    )
    fit = fit_decay(d.t, d.y, quantity="velocity", band=d.band)
    nu = fit.conventions["noise_dof"]
    assert 0.0 < nu < fit.conventions["residual_dof"] < fit.conventions["samples"]
    tr = _truth(fit, 0.01772, p=p, k_inf=w02 - KT)
    z = {k: (fit.parameters[k] - tr[k]) / fit.stderr[k] for k in fit.identified}
    if fit.success:
        assert max(map(abs, z.values())) < 3.0, (z, fit.report())
    else:
        assert any("degrees of freedom" in w or "phi_max" in w for w in fit.warnings)
    if nu < 5.0:
        assert not fit.success and any("degrees of freedom" in w for w in fit.warnings)


def test_pretrigger_and_impact_start_are_found():
    """A record with 0.2 s of noise before the decay: the start is found and the model is
    zero before it."""
    d = _svam(zeta0=4e-3, a0=1e-4, duration=1.0, quantity="acceleration", seed=11)
    n_pre = 400
    rng = np.random.default_rng(12)
    y = np.concatenate([0.01 * np.abs(d.y).max() * rng.standard_normal(n_pre), d.y])
    t = np.arange(y.size) / 2000.0
    fit = fit_decay(t, y, quantity="acceleration", band=d.band)
    assert fit.conventions["t_fit"][0] == pytest.approx(n_pre / 2000.0, abs=3e-3)
    tr = _truth(fit, 4e-3)
    for k in ("f0", "zeta0"):
        assert abs(fit.parameters[k] - tr[k]) < 3 * fit.stderr[k]


# ------------------------------------------------------------------ API and bad input
def test_result_api_and_no_mutation():
    d = _svam(zeta0=2e-3, duration=1.0, seed=2)
    t0, y0 = d.t.copy(), d.y.copy()
    fit = fit_decay(d.t, d.y, quantity="acceleration", band=d.band)
    assert np.array_equal(d.t, t0) and np.array_equal(d.y, y0)
    assert isinstance(fit, ModalIwanFit)
    assert fit.conventions["method"] == "direct signal fit"
    assert isinstance(fit.warnings, tuple)
    json.dumps(fit.to_dict(), allow_nan=False)
    assert "Modal Iwan fit" in fit.report()
    f, z, fb, zb = fit.predict(np.array([1e-5, 5e-5]), band=0.95)
    assert np.all(fb[0] <= f) and np.all(f <= fb[1])
    from matplotlib.figure import Figure

    fig = Figure()
    axes = (fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2))
    artists = fit.plot(ax=axes)
    assert artists and all(getattr(a, "axes", axes[0]) in axes for a in artists)


def _ok():
    d = _svam(zeta0=2e-3, duration=0.5, seed=4)
    return d.t, d.y, d.band


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda t, y, b: (t, np.where(np.arange(y.size) == 50, np.nan, y), b, {}), "y"),
        (lambda t, y, b: (t[:-1], y, b, {}), "t"),
        (lambda t, y, b: (t * np.r_[1.0, np.ones(t.size - 2) * 1.0, 1.3], y, b, {}), "t"),
        (lambda t, y, b: (t, y, (b[0], 5000.0), {}), "band"),
        (lambda t, y, b: (t, y, (b[1], b[0]), {}), "band"),
        (lambda t, y, b: (t, y, b, {"quantity": "jerk"}), "quantity"),
        (lambda t, y, b: (t, y, b, {"order": 0}), "order"),
        (lambda t, y, b: (t, y, b, {"snr_min": 1.0}), "snr_min"),
        (lambda t, y, b: (t, y, b, {"significance": 0.0}), "significance"),
        (lambda t, y, b: (t, y, b, {"t_start": -1.0}), "t_start"),
        (lambda t, y, b: (t, y, b, {"floor": "none"}), "floor"),
        (lambda t, y, b: (t[:30], y[:30], b, {}), "y"),
    ],
)
def test_bad_input_raises_naming_the_argument(change, match):
    t, y, band = _ok()
    tt, yy, bb, kw = change(t, y, band)
    with pytest.raises(ValueError, match=match):
        fit_decay(tt, yy, band=bb, **kw)


def test_noise_only_record_is_refused_or_unsupported():
    """Pure noise holds no decaying mode: an error or a fit that says it is not supported."""
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 2000.0
    y = rng.standard_normal(t.size)
    try:
        fit = fit_decay(t, y, quantity="acceleration", band=(70.0, 90.0))
    except ValueError as exc:
        assert "band" in str(exc) or "mode" in str(exc)
    else:
        assert not fit.success
