"""Modal Iwan identification from f(X), zeta(X).

Truth comes from the closed forms of core.modal (checked against docs/equations.md section 5
and a time simulation in test_vibration.py) and, end to end, from a ring-down of the exact
IwanJoint.
"""

import json
import math

import numpy as np
import pytest

from iwan_element import (
    AmplitudeCurve,
    IwanParameters,
    ModalIwanFit,
    amplitude_curve,
    fit_modal_iwan,
    modal_iwan_curve,
    modal_ringdown,
)
from iwan_element.identify.modal.model import model_curve


def _joint(f0=20.0, kappa=0.3, chi=-0.5, beta=0.5, phimax=1e-3):
    w02 = (2 * math.pi * f0) ** 2
    KT = kappa * w02
    c = beta + (chi + 1) / (chi + 2)
    return IwanParameters(KT * c * phimax / (1 + beta), KT, chi, beta), w02 - KT


def _data(X, p, k_inf, zeta0, rng, f_noise=2e-6, z_noise=0.005):
    f, z = modal_iwan_curve(X, p, K_inf=k_inf, zeta0=zeta0, stiffness="harmonic", floor="dashpot")
    sf, sz = f_noise * f, z_noise * z
    return (f + sf * rng.standard_normal(X.size), z + sz * rng.standard_normal(X.size), sf, sz)


def test_microslip_formula_is_the_small_amplitude_limit():
    """The fit's microslip form against the full closed form at X << phi_max."""
    p, k_inf = _joint()
    X = np.geomspace(1e-9, 1e-7, 5)
    f, z = modal_iwan_curve(X, p, K_inf=k_inf, zeta0=1e-3, stiffness="harmonic", floor="dashpot")
    x_ref = 1e-8
    delta = (
        p.KT * (x_ref / p.phi_max) ** (p.chi + 1) / ((k_inf + p.KT) * (p.chi + 2) * (1 + p.beta))
    )
    fm, zm = model_curve(
        [math.sqrt(k_inf + p.KT) / (2 * math.pi), 1e-3, p.chi, delta],
        X,
        "microslip",
        x_ref,
        "harmonic",
        "dashpot",
    )
    np.testing.assert_allclose(fm, f, rtol=1e-12)
    np.testing.assert_allclose(zm, z, rtol=1e-6)


def test_microslip_data_report_only_what_they_fix():
    rng = np.random.default_rng(3)
    p, k_inf = _joint()
    X = np.geomspace(2e-6, 1e-4, 25)  # at most 0.1 phi_max
    f, z, sf, sz = _data(X, p, k_inf, 1.5e-3, rng)
    r = fit_modal_iwan(AmplitudeCurve(X, f, z, frequency_std=sf, damping_ratio_std=sz))
    assert r.regime == "microslip" and r.success
    assert set(r.parameters) == {"f0", "zeta0", "chi", "delta"}
    assert r.joint is None
    assert any("never leave microslip" in w for w in r.warnings)
    x_ref = r.conventions["x_ref"]
    truth = {
        "f0": math.sqrt(k_inf + p.KT) / (2 * math.pi),
        "zeta0": 1.5e-3,
        "chi": p.chi,
        "delta": p.KT
        * (x_ref / p.phi_max) ** (p.chi + 1)
        / ((k_inf + p.KT) * (p.chi + 2) * (1 + p.beta)),
    }
    for k, v in truth.items():
        assert abs(r.parameters[k] - v) < 4 * r.stderr[k], k
    assert r.stderr["chi"] < 0.05


def test_macroslip_data_identify_the_joint():
    rng = np.random.default_rng(4)
    p, k_inf = _joint(beta=0.3)
    X = np.geomspace(0.01, 4.0, 40) * p.phi_max
    f, z, sf, sz = _data(X, p, k_inf, 1e-3, rng)
    r = fit_modal_iwan(X, f, z)  # no stated uncertainties: from residuals
    assert r.regime == "macroslip", r.report()
    q = r.joint
    assert isinstance(q, IwanParameters)
    assert q.phi_max == pytest.approx(p.phi_max, rel=0.05)
    assert q.KT == pytest.approx(p.KT, rel=0.05)
    assert q.chi == pytest.approx(p.chi, abs=0.05)
    assert q.Fs == pytest.approx(p.Fs, rel=0.05)
    assert r.parameters["K_inf"] == pytest.approx(k_inf, rel=0.02)
    for k in ("phi_max", "KT", "Fs", "chi"):
        truth = {"phi_max": p.phi_max, "KT": p.KT, "Fs": p.Fs, "chi": p.chi}[k]
        assert abs(r.parameters[k] - truth) < 4 * r.stderr[k], k
    f_fit, z_fit, fb, zb = r.predict(X, band=0.95)
    f_true, z_true = modal_iwan_curve(
        X, p, K_inf=k_inf, zeta0=1e-3, stiffness="harmonic", floor="dashpot"
    )
    assert np.mean((fb[0] <= f_true) & (f_true <= fb[1])) > 0.8
    assert np.mean((zb[0] <= z_true) & (z_true <= zb[1])) > 0.8
    assert np.all(fb[1] > fb[0])


def test_one_amplitude_and_bad_input():
    r = fit_modal_iwan([1e-5, 1e-5], [50.0, 50.01], [0.002, 0.0021])
    assert r.regime == "linear" and not r.success
    assert any("distinct amplitude" in w for w in r.warnings)
    assert r.parameters["f0"] == pytest.approx(50.005)
    X = np.geomspace(1e-6, 1e-4, 10)
    with pytest.raises(ValueError, match="percent"):
        fit_modal_iwan(X, np.full(10, 50.0), np.full(10, 0.2) * 10)
    with pytest.raises(ValueError, match="frequency and damping_ratio"):
        fit_modal_iwan(X)
    with pytest.raises(ValueError, match="stiffness"):
        fit_modal_iwan(X, np.full(10, 50.0), np.full(10, 0.002), stiffness="tangent")
    with pytest.raises(ValueError, match="amplitude"):
        fit_modal_iwan(-X, np.full(10, 50.0), np.full(10, 0.002))


def test_result_api_and_no_mutation():
    rng = np.random.default_rng(5)
    p, k_inf = _joint()
    X = np.geomspace(2e-6, 1e-4, 12)
    f, z, sf, sz = _data(X, p, k_inf, 1e-3, rng)
    Xc, fc, zc = X.copy(), f.copy(), z.copy()
    r = fit_modal_iwan(X, f, z)
    np.testing.assert_array_equal(X, Xc)
    np.testing.assert_array_equal(f, fc)
    np.testing.assert_array_equal(z, zc)
    assert isinstance(r, ModalIwanFit)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["regime"] == "microslip"
    assert {p["name"]: p["stderr"] for p in d["params"]["parameters"]}["f0"] > 0
    assert "f0" in r.report() and "delta" in r.report()
    f1, z1 = r.predict(X)
    assert f1.shape == X.shape
    draws = r.sample_parameters(20, rng=np.random.default_rng(0))
    assert len(draws) == 20 and all(0 <= s["zeta0"] < 1 and s["chi"] > -1 for s in draws)
    with pytest.raises(ValueError, match="rng"):
        r.sample_parameters(3, rng=0)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 1)
    artists = r.plot(ax=ax)
    assert len(artists) >= 6
    plt.close(fig)


def test_ringdown_end_to_end():
    """Exact-joint ring-down -> Hilbert curve -> fit: the microslip combination is found.

    The curve reaches 0.16 phi_max, where a free decay's damping is the decay form
    (``D / (2 pi (K_inf + K_t) X**2)``, 2-3 % above the energy form here): a curve from
    amplitude_curve is fitted in that form by default, and the truth is the closed form."""
    p, k_inf = _joint(beta=0.5)
    t = np.arange(0.0, 20.0, 1 / 400.0)
    a = modal_ringdown(t, p, K_inf=k_inf, q0=0.2e-3, zeta0=2e-3).acceleration
    noise = 0.01 * np.std(a) * np.random.default_rng(7).standard_normal(t.size)
    cur = amplitude_curve(t, a + noise, band=(12.0, 30.0))
    assert cur.amplitude.max() > 0.1 * p.phi_max
    r = fit_modal_iwan(cur)
    assert r.regime == "microslip" and r.conventions["damping_form"] == "decay"
    x_ref = r.conventions["x_ref"]
    truth = {
        "f0": math.sqrt(k_inf + p.KT) / (2 * math.pi),
        "zeta0": 2e-3,
        "chi": p.chi,
        "delta": p.KT
        * (x_ref / p.phi_max) ** (p.chi + 1)
        / ((k_inf + p.KT) * (p.chi + 2) * (1 + p.beta)),
    }
    for k, v in truth.items():
        assert abs(r.parameters[k] - v) < 4 * r.stderr[k], (k, r.report())
    assert r.chi2_red < 4.0  # the fit follows the curve within its stated scatter


def test_a_free_decay_shows_the_decay_form_of_the_damping():
    """Independent route: the exact Iwan oscillator integrated in time (no noise, no floor).
    Its amplitude decays at the rate the dissipation drains the energy at a turning point,
    whose growth with amplitude is (K_inf + K_t) X: the decay form follows the measured
    damping to 1 % at 0.05-0.2 phi_max, where the energy form (w**2 in place of K_inf + K_t)
    is 3-8 % low."""
    p = IwanParameters(Fs=2.631894506957162, KT=4737.410112522892, chi=-0.5, beta=0.5)
    k_inf = 0.6 * p.KT
    t = np.arange(0.0, 20.0, 1 / 400.0)
    q = modal_ringdown(t, p, K_inf=k_inf, q0=0.3e-3).displacement
    c = amplitude_curve(t, q, quantity="displacement", band=(8.0, 30.0), compare=False)
    m = (c.amplitude > 0.05 * p.phi_max) & (c.amplitude < 0.2 * p.phi_max)
    assert m.sum() >= 5
    _, z_decay = modal_iwan_curve(
        c.amplitude[m], p, K_inf=k_inf, stiffness="harmonic", damping_form="decay"
    )
    _, z_energy = modal_iwan_curve(c.amplitude[m], p, K_inf=k_inf, stiffness="harmonic")
    assert np.max(np.abs(c.damping_ratio[m] / z_decay - 1)) < 0.01
    assert np.min(c.damping_ratio[m] / z_energy - 1) > 0.03
    with pytest.raises(ValueError, match="damping"):
        modal_iwan_curve(1e-4, p, K_inf=k_inf, damping_form="viscous")
