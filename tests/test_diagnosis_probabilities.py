"""The diagnoses' posterior probabilities (iwan_element.diagnose.probabilities): they sum to
1, the named effects are the most probable explanation, clean data and pure noise put the
plain joint above 0.9, a dominant effect puts itself above 0.99, the report says when no
explanation is above 0.9, the prior is stated and overridable, and the model-averaged band
agrees with sampling the parameters' posterior (an independent route)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _diagnosis_cases import SIGMA, ZETA0, record, vibration_case

from iwan_element import diagnose, diagnose_vibration
from iwan_element.diagnose.selection.averaging import mixture
from iwan_element.diagnose.selection.probabilities import default_effect_prior, log_model_prior
from iwan_element.diagnose.selection.probable import confidence_text


@pytest.fixture(scope="module")
def clean():
    d = record(None, 0.0, "ladder", 22)
    return diagnose(d.t, d.u, d.F)


@pytest.fixture(scope="module")
def dominant():
    d = record("backlash", 8.0, "ladder", 12)
    return diagnose(d.t, d.u, d.F)


def _check_shape(d):
    p = d.probabilities
    assert sum(p.values()) == pytest.approx(1.0, abs=1e-12)
    assert all(k == tuple(sorted(k)) for k in p)
    assert () in p
    top = max(p, key=p.get)
    assert top == tuple(sorted(d.effects))  # the named effects: the most probable
    for name in {n for k in p for n in k}:
        assert d.effect_probability(name) == pytest.approx(
            sum(v for k, v in p.items() if name in k)
        )
    with pytest.raises(ValueError, match="name must be one of"):
        d.effect_probability("gremlins")


def test_clean_record_puts_the_plain_joint_above_0_9(clean):
    """A clean record (no hidden effect, 5 N noise on a 1000 N joint, 1153 samples): the
    plain joint above 0.9 (on the calibration benchmark's clean loop records the median is
    about 0.93; the rest is mostly a break-away too small to see, which the size prior
    keeps possible)."""
    _check_shape(clean)
    assert clean.effects == ()
    assert clean.probabilities[()] > 0.9
    d = record(None, 0.0, "ladder", 20)
    assert diagnose(d.t, d.u, d.F).probabilities[()] > 0.9
    # every single candidate was fitted for the probabilities, though the rule needed none
    assert {k for k in clean.probabilities if len(k) == 1} == {
        (c,) for c in clean.details["candidates"]
    }


def test_pure_noise_puts_the_plain_joint_above_0_9():
    d = record(None, 0.0, "ladder", 13)
    F = np.random.default_rng(13).normal(0.0, SIGMA, d.F.size)
    g = diagnose(d.t, d.u, F)
    assert g.effects == () and not g.success
    assert g.probabilities[()] > 0.9


def test_dominant_effect_puts_itself_above_0_99(dominant):
    _check_shape(dominant)
    assert dominant.effects == ("backlash",)
    assert dominant.effect_probability("backlash") > 0.99
    assert "most probable: backlash" in dominant.report()


def test_tables_html_and_dict_show_the_probabilities(dominant):
    df = dominant.to_dataframe("probabilities")
    assert df["probability [-]"].sum() == pytest.approx(1.0)
    assert df.iloc[0]["explanation"] == "backlash"
    eff = dominant.to_dataframe("effect probabilities")
    assert set(eff["effect"]) >= {"backlash"}
    assert "probabilities" in dominant._repr_html_()
    d = dominant.to_dict()
    assert sum(e["probability"] for e in d["probabilities"]) == pytest.approx(1.0)


def test_vibration_probabilities_clean_dominant_and_not_sure():
    X, fm, zm, fp, zp = vibration_case(1)
    c = diagnose_vibration(
        X, fm, zm, predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=ZETA0
    )
    _check_shape(c)
    assert c.probabilities[()] > 0.9
    X, fm, zm, fp, zp = vibration_case(1, k_p=1e4, delta=1e-4)
    g = diagnose_vibration(
        X, fm, zm, predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=ZETA0
    )
    _check_shape(g)
    assert g.effect_probability("pinning_stiffness") > 0.99
    # a small dashpot on 12 amplitudes: neither explanation is sure, and the report says so
    X, fm, zm, fp, zp = vibration_case(2, n=12, zeta_v=6e-5)
    u = diagnose_vibration(
        X, fm, zm, predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=ZETA0
    )
    _check_shape(u)
    assert max(u.probabilities.values()) < 0.9
    assert "NOT SURE: no explanation is above 0.9" in u.report()
    assert "probabilities" in u._repr_html_()


def test_confidence_sentence():
    assert confidence_text({(): 0.95, ("a",): 0.05}).startswith("most probable: the plain")
    text = confidence_text({("a",): 0.6, (): 0.3, ("b",): 0.1})
    assert text.startswith("NOT SURE") and "then plain joint 0.3, b 0.1" in text


def test_prior_is_stated_and_overridable():
    """The default gives the plain joint even prior odds; ``effect_prior`` overrides it and
    moves the posterior the way Bayes' rule says (odds times the prior odds' ratio)."""
    K = 6
    p0 = default_effect_prior(K)
    assert (1 - p0) ** K == pytest.approx(0.5)
    lp = log_model_prior([(), ("a",)], dict.fromkeys("abcdef", p0))
    assert lp[()] - lp[("a",)] == pytest.approx(math.log((1 - p0) / p0))
    X, fm, zm, fp, zp = vibration_case(2, n=12, zeta_v=6e-5)
    kw = dict(predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=ZETA0)
    a = diagnose_vibration(X, fm, zm, **kw)
    b = diagnose_vibration(X, fm, zm, effect_prior={"viscous_damping": 0.5}, **kw)
    odds_a = a.probabilities[("viscous_damping",)] / a.probabilities[()]
    odds_b = b.probabilities[("viscous_damping",)] / b.probabilities[()]
    pv = default_effect_prior(len(a.details["candidates"]) if "candidates" in a.details else 4)
    assert odds_b / odds_a == pytest.approx((0.5 / 0.5) / (pv / (1 - pv)), rel=1e-6)
    for bad in (0.0, 1.0, {"gremlins": 0.2}, "half"):
        with pytest.raises(ValueError):
            diagnose_vibration(X, fm, zm, effect_prior=bad, **kw)
    with pytest.raises(ValueError, match="evidence"):
        diagnose_vibration(X, fm, zm, evidence="exact", **kw)


def test_averaged_band_matches_sampling_the_posterior(dominant):
    """One member (probability ~1): the band's mean is the fitted force, and its standard
    deviation (linearised) matches 120 draws of the parameters from their posterior run
    through the elements (median ratio within 20 %)."""
    from iwan_element.diagnose.loops.evidence import member_force

    b = dominant.averaged_band()
    assert b.members[0][0] == ("backlash",)
    f = b.channels["force"]
    assert np.allclose(f["mean"], dominant.force_after, atol=1e-6 * np.ptp(dominant.F))
    e = dominant.explanations[0]
    rng = np.random.default_rng(0)
    uj = np.asarray(dominant.u) - dominant.offsets["displacement"]
    v = np.gradient(uj, dominant.t)
    draws = rng.multivariate_normal(e.theta, e.covariance, size=120)
    from iwan_element.effects import EFFECTS

    lows = [sp.prior_range[0] for nm in e.stack for sp in EFFECTS[nm].specs]
    for j, lo in enumerate(lows):  # a size at its bound: its half-Gaussian
        draws[:, 3 + j] = lo + np.abs(draws[:, 3 + j] - lo)
    sims = np.array(
        [
            member_force(e.stack, th, dominant.details["x_max"], dominant.details["scales"], uj, v)
            for th in draws
        ]
    )
    sd_mc = sims.std(axis=0)
    big = sd_mc > np.median(sd_mc)
    assert np.median(f["std"][big] / sd_mc[big]) == pytest.approx(1.0, rel=0.2)
    assert np.all(f["lower"] <= f["mean"]) and np.all(f["mean"] <= f["upper"])


def test_mixture_quantiles_match_sampling():
    """The band of a two-member mixture against 200,000 draws from it."""
    rng = np.random.default_rng(1)
    w = np.array([0.7, 0.3])
    mu = np.array([[0.0, 1.0], [2.0, 1.0]])
    sd = np.array([[1.0, 0.5], [0.5, 0.1]])
    mean, std, lo, hi = mixture(w, mu, sd, 0.9)
    k = rng.choice(2, size=200_000, p=w)
    for j in range(2):
        x = rng.normal(mu[k, j], sd[k, j])
        assert mean[j] == pytest.approx(x.mean(), abs=0.01)
        assert std[j] == pytest.approx(x.std(), rel=0.01)
        assert lo[j] == pytest.approx(np.quantile(x, 0.05), abs=0.02)
        assert hi[j] == pytest.approx(np.quantile(x, 0.95), abs=0.02)


def test_without_probabilities_the_rule_alone_names():
    d = record("backlash", 8.0, "ladder", 12)
    g = diagnose(d.t, d.u, d.F, probabilities=False)
    assert g.effects == ("backlash",) and g.explanations == () and g.probabilities == {}
    with pytest.raises(ValueError, match="no probabilities"):
        g.averaged_band()


def test_vibration_averaged_band_mixes_the_explanations():
    """Two explanations near even odds (a small dashpot on 12 amplitudes): the band's mean
    is the probability-weighted mean of the members' curves, its ends bracket it, and the
    plain member's curve is the prediction itself."""
    X, fm, zm, fp, zp = vibration_case(2, n=12, zeta_v=6e-5)
    u = diagnose_vibration(
        X, fm, zm, predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=ZETA0
    )
    b = u.averaged_band(X)
    w = np.array([m[1] for m in b.members])
    assert w.sum() == pytest.approx(1.0) and len(b.members) >= 2
    z = b.channels["damping_ratio"]
    assert np.allclose(z["mean"], w @ b.member_means["damping_ratio"], rtol=1e-12)
    assert np.all(z["lower"] <= z["mean"]) and np.all(z["mean"] <= z["upper"])
    plain = [m[0] for m in b.members].index(())
    assert np.allclose(b.member_means["damping_ratio"][plain], zp, rtol=1e-12)
    assert b.to_dataframe("members")["weight [-]"].sum() == pytest.approx(1.0)


def _drive(amplitudes):
    from _diagnosis_cases import P

    from iwan_element import IwanJoint
    from iwan_element.diagnose import simulate_element_test

    d = simulate_element_test(IwanJoint(P), np.array(amplitudes) * P.phi_max)
    return d.u, np.gradient(d.u, d.t)


def test_microslip_ridge_keeps_the_force_and_states_its_density():
    """Below ``phi_max`` the Iwan force depends on ``KT``, ``chi`` and ``R`` alone: along the
    curve of ``microslip_ridge`` the force of the elements (a joint with a pinning spring,
    run in time by the element: not the fitted model's evaluator) stays the same on a drive
    that never reaches macroslip, and no ridge is found on one that does. The curve's log
    Jacobian against finite differences of ``(KT, R)`` in ``(ln(1 + beta), Fs)`` (and the
    pinning spring's ``Fs``-scaled variable)."""
    from _diagnosis_cases import P

    from iwan_element.core.history import unit_params
    from iwan_element.diagnose.loops.evidence import member_force, microslip_ridge
    from iwan_element.diagnose.loops.prepare import effect_scales

    stack = ("pinning_stiffness",)
    for amps, on_ridge in (((0.5, 1.5), False), ((0.3, 0.6, 0.9), True)):
        u, v = _drive(amps)
        x_max, scales = float(np.max(np.abs(u))), effect_scales(u, v)
        theta = np.array(
            [math.log(P.phi_max / x_max), P.chi, math.log1p(P.beta), 0.3, 0.5, P.Fs, 2.0]
        )
        F = member_force(stack, theta, x_max, scales, u, v)

        def chi2_at(th, F=F, x_max=x_max, scales=scales, u=u, v=v):
            return float(np.sum((F - member_force(stack, th, x_max, scales, u, v)) ** 2))

        hi = np.array([math.log(1e4), 1.0, math.log(101.0), 20.0, 0.95, 1e9, 1e9])
        ridge = microslip_ridge(stack, theta, hi, chi2_at)
        assert (ridge is not None) == on_ridge
    pts = [theta[0] - 0.04, theta[0] + 0.05, ridge.upper - 0.01]
    for s in pts:
        th, _ = ridge.curve(s)
        assert np.max(np.abs(member_force(stack, th, x_max, scales, u, v) - F)) < 1e-9 * np.max(
            np.abs(F)
        )

    def invariants(lb, Fs, z0):
        phi = x_max * math.exp(z0)
        p1 = unit_params(phi, P.chi, math.expm1(lb))
        KT = Fs * p1.KT
        return np.array([KT, KT / (1 + p1.beta) * (P.chi + 1) / phi ** (P.chi + 1)])

    def log_density(s):  # ln |d(lb, Fs, z_kp) / d(KT, R, k_p)| at fixed s
        th, _ = ridge.curve(s)
        h = np.array([1e-6, 1e-6 * th[5]])
        cols = [
            (invariants(th[2] + h[0], th[5], s) - invariants(th[2] - h[0], th[5], s)) / (2 * h[0]),
            (invariants(th[2], th[5] + h[1], s) - invariants(th[2], th[5] - h[1], s)) / (2 * h[1]),
        ]
        return -math.log(abs(np.linalg.det(np.column_stack(cols)))) - math.log(th[5])

    ref = [log_density(s) - log_density(pts[0]) for s in pts]
    got = [ridge.curve(s)[1] - ridge.curve(pts[0])[1] for s in pts]
    assert got == pytest.approx(ref, abs=1e-5)


def test_clean_microslip_record_puts_the_plain_joint_above_0_9():
    """A clean record that never reaches macroslip (0.3, 0.6, 0.9 phi_max): every
    explanation's joint lies on the microslip ridge, whose evidence is integrated along it;
    the plain joint above 0.9 (with the Gaussian at the fits, which stopped where the ridge
    ends, break-away was named at 0.80)."""
    from _diagnosis_cases import P

    from iwan_element import IwanJoint
    from iwan_element.diagnose import simulate_element_test

    d = simulate_element_test(
        IwanJoint(P), np.array([0.3, 0.6, 0.9]) * P.phi_max, force_noise=SIGMA, seed=23
    )
    g = diagnose(d.t, d.u, d.F)
    _check_shape(g)
    assert g.effects == () and g.probabilities[()] > 0.9
