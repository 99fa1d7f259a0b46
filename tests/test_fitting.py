"""The fitting engine (iwan_element.fitting): covariance against independent routes, the
verdict rule, the parameter table's validation and immutability."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from iwan_element.fitting import (
    Parameter,
    ParameterTable,
    covariance,
    fit_success,
    normal_inverse,
    verdict,
)


def _linear(seed, m=200, sigma=0.3):
    rng = np.random.default_rng(seed)
    A = np.column_stack([np.ones(m), np.linspace(-1, 1, m), rng.normal(size=m)])
    x = np.array([1.0, -2.0, 0.5])
    y = A @ x + sigma * rng.normal(size=m)
    xh = np.linalg.solve(A.T @ A, A.T @ y)
    return A, y - A @ xh


def test_linear_model_matches_textbook_formula():
    """y = A x + noise: stderr = sqrt(diag(s^2 (A^T A)^-1)), s^2 = SSR/(m - p), by inv()."""
    A, r = _linear(1)
    m, p = A.shape
    s2 = r @ r / (m - p)
    textbook = np.sqrt(np.diag(s2 * np.linalg.inv(A.T @ A)))
    c = covariance(-A, r)  # the residual's Jacobian is -A
    np.testing.assert_allclose(c.stderr, textbook, rtol=1e-10)
    assert not c.degenerate.any() and c.block == 0
    np.testing.assert_allclose(np.diag(c.correlation), 1.0, rtol=1e-12)
    # tau multiplies every variance
    np.testing.assert_allclose(covariance(-A, r, tau=4.0).stderr, 2.0 * textbook, rtol=1e-10)


def test_columns_of_very_different_scale():
    """Column scaling: a variable in units 1e6 times smaller changes nothing but its units."""
    A, r = _linear(2)
    B = A * np.array([1.0, 1e6, 1e-6])
    textbook = np.sqrt(np.diag(r @ r / (A.shape[0] - 3) * np.linalg.inv(A.T @ A)))
    np.testing.assert_allclose(covariance(B, r).stderr, textbook / [1.0, 1e6, 1e-6], rtol=1e-8)


def test_delta_method_equals_direct_parametrisation():
    """Linear model fitted in theta = ln x: Jp = diag(x) must give the covariance of x."""
    A, r = _linear(3)
    x = np.array([1.0, 2.0, 0.5])
    direct = covariance(A, r)
    via = covariance(A * x, r, Jp=np.diag(x))  # d r / d theta = A diag(x)
    np.testing.assert_allclose(via.covariance, direct.covariance, rtol=1e-9)
    np.testing.assert_allclose(via.stderr, direct.stderr, rtol=1e-9)


def test_degenerate_column_gives_nan():
    A, r = _linear(4)
    J = np.column_stack([A, 2.0 * A[:, 1]])  # column 3 = 2 x column 1
    c = covariance(J, r)
    assert c.degenerate.tolist() == [False, True, False, True]
    assert np.isnan(c.stderr[[1, 3]]).all() and np.isfinite(c.stderr[[0, 2]]).all()
    assert np.isnan(c.correlation[1]).all()
    assert (c.stderr[[0, 2]] > 0).all()
    zero = covariance(np.column_stack([A, np.zeros(A.shape[0])]), r)
    assert zero.degenerate.tolist() == [False, False, False, True]
    _, bad = normal_inverse(J)
    assert bad.tolist() == [False, True, False, True]
    # the model depends on theta1 + 2 theta3 only: that combination is determined, with the
    # standard error of the coefficient of column 1 in the fit without the duplicate
    Jp = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 2.0], [0, 1.0, 0, 0]])
    d = covariance(J, r, Jp=Jp, dof=A.shape[0] - 3)  # the rank is 3
    assert d.degenerate.tolist() == [False, False, True]
    np.testing.assert_allclose(d.stderr[:2], covariance(A, r).stderr[:2], rtol=1e-8)


def _ar1(rng, m, phi):
    e = rng.normal(size=m)
    out = np.empty(m)
    out[0] = e[0] / math.sqrt(1 - phi**2)
    for i in range(1, m):
        out[i] = phi * out[i - 1] + e[i]
    return out


def test_block_sandwich_widens_for_ar1_residuals():
    """Mean of AR(1) noise (phi = 0.8): the plain formula is too narrow by sqrt((1+phi)/(1-phi))
    = 3; the block sandwich (tau = 1 given, so only the blocks see the correlation) is wider
    and close to the true spread."""
    rng = np.random.default_rng(5)
    m, phi = 4000, 0.8
    J = -np.ones((m, 1))
    ratios_plain, ratios_block = [], []
    truth = math.sqrt((1 + phi) / (1 - phi) / (1 - phi**2) / m)  # sd of the mean, unit e
    for _ in range(20):
        y = _ar1(rng, m, phi)
        r = y - y.mean()
        c0 = covariance(J, r)
        c1 = covariance(J, r, block=100)
        assert c1.block == 100 and c1.widened
        assert c1.stderr[0] > 1.5 * c0.stderr[0]
        ratios_plain.append(c0.stderr[0] / truth)
        ratios_block.append(c1.stderr[0] / truth)
    assert np.median(ratios_plain) < 0.4
    assert 0.8 < np.median(ratios_block) < 1.15
    # white residuals: the sandwich does not widen much beyond the plain value
    r = rng.normal(size=m)
    r -= r.mean()
    assert covariance(J, r, block=0).stderr[0] < 1.3 * covariance(J, r).stderr[0]


def test_an_undetermined_column_does_not_switch_the_sandwich_off():
    """Residuals whose size grows along the record (the plain formula is too narrow for the
    slope): a zero Jacobian column (a parameter the data do not touch) gets NaN, and the
    others keep the sandwich's wider errors instead of falling back to the plain ones."""
    rng = np.random.default_rng(0)
    m = 300
    t = np.linspace(0.0, 1.0, m)
    A = np.column_stack([np.ones(m), t])
    r = rng.normal(size=m) * (0.2 + 2.0 * t)
    plain = covariance(A, r).stderr
    full = covariance(A, r, block=0)
    with_zero = covariance(np.column_stack([A, np.zeros(m)]), r, block=0)
    assert full.widened and with_zero.widened and with_zero.block == full.block
    assert math.isnan(with_zero.stderr[2])
    assert with_zero.stderr[1] > 1.2 * plain[1]
    np.testing.assert_allclose(with_zero.stderr[:2], full.stderr, rtol=0.05)  # nb/(nb - p)


def test_monte_carlo_coverage_of_a_nonlinear_model():
    """y = a exp(-b t) + noise: 95 % intervals from the Jacobian of least_squares hold the
    truth in 90-98 % of 300 draws, and the stated stderr matches the spread of the estimates."""
    rng = np.random.default_rng(6)
    t = np.linspace(0, 3, 60)
    a, b, sig = 2.0, 1.3, 0.05
    hits, est, ses = np.zeros(2), [], []
    for _ in range(300):
        y = a * np.exp(-b * t) + sig * rng.normal(size=t.size)
        res = least_squares(lambda x, y=y: x[0] * np.exp(-x[1] * t) - y, [1.0, 1.0])
        c = covariance(res.jac, res.fun)
        hits += np.abs(res.x - [a, b]) <= 1.96 * c.stderr
        est.append(res.x)
        ses.append(c.stderr)
    cover = hits / 300
    assert np.all((cover >= 0.90) & (cover <= 0.98)), cover
    np.testing.assert_allclose(np.mean(ses, axis=0), np.std(est, axis=0), rtol=0.12)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"J": np.array([[1.0, np.nan]] * 5)}, "J"),
        ({"J": np.ones(5)}, "J"),
        ({"r": np.ones(4)}, "r must have one entry"),
        ({"tau": 0.0}, "tau"),
        ({"r": None}, "r \\(the residuals\\) is required"),
        ({"Jp": np.ones((2, 3))}, "Jp"),
    ],
)
def test_covariance_rejects_bad_input(kw, match):
    args = {"J": np.eye(5)[:, :2], "r": np.ones(5)}
    args.update(kw)
    J, r = args.pop("J"), args.pop("r")
    with pytest.raises(ValueError, match=match):
        covariance(J, r, **args)


def test_covariance_does_not_modify_input():
    A, r = _linear(7)
    A0, r0 = A.copy(), r.copy()
    covariance(A, r, block=0, Jp=np.eye(3))
    assert np.array_equal(A, A0) and np.array_equal(r, r0)


# ------------------------------------------------------------------------------ verdict


@pytest.mark.parametrize(
    "args, kw, ok, text",
    [
        (("KT", 1e6, 1e5), {}, True, None),
        (("KT", 1e6, 6e5), {}, False, "exceeds half of its value"),
        (("KT", 1e6, 1e5), {"at_bound": True}, False, "at a bound"),
        (("KT", 1e6, math.nan), {}, False, "not determined"),
        (("dF0", 1.0, 30.0), {"nuisance": True}, True, None),
        (("du0", 0.0, math.nan), {"nuisance": True}, False, "not determined"),
        (("chi", -0.05, 0.3), {"reference": 0.95, "reference_text": "chi + 1"}, True, None),
        (("chi", -0.8, 0.3), {"reference": 0.2, "reference_text": "chi + 1"}, False, "chi + 1"),
    ],
)
def test_verdict_rule(args, kw, ok, text):
    got, warn = verdict(*args, **kw)
    assert got is ok
    assert (warn is None) if ok else (text in warn and args[0] in warn)


def test_verdict_boundary_is_half():
    assert verdict("a", 2.0, 1.0)[0] and not verdict("a", 2.0, 1.0 + 1e-12)[0]


def test_fit_success():
    ident = {"a": True, "b": False}
    assert not fit_success(True, ident)
    assert fit_success(True, ident, ["a"])
    assert not fit_success(False, ident, ["a"])
    assert not fit_success(True, ident, ["c"])
    with pytest.raises(ValueError, match="iterable of parameter names"):
        fit_success(True, ident, "a")


def test_verdict_refuses_a_negative_error_and_rejects_a_non_finite_value():
    with pytest.raises(ValueError, match="stderr of a must be >= 0"):
        verdict("a", 1.0, -5.0)
    ok, why = verdict("a", math.nan, 0.1)
    assert not ok and "no finite value" in why


# ---------------------------------------------------------------------------- the table


def _table():
    return ParameterTable(
        [
            Parameter("Fs", 1000.0, 10.0, 0.0, math.inf, "N", True),
            Parameter("dF0", 3.0, 1.0, unit="N", identified=True, nuisance=True),
            Parameter("beta", 0.0, math.nan, 0.0, 100.0, "1", fixed=True),
        ],
        correlation=np.eye(3),
    )


def test_table_views_and_report():
    t = _table()
    assert t.names == ("Fs", "dF0", "beta") and list(t) == list(t.names) and len(t) == 3
    assert t.values == {"Fs": 1000.0, "dF0": 3.0, "beta": 0.0}
    assert t.identified == {"Fs": True, "dF0": True, "beta": False}
    assert math.isnan(t.stderr["beta"]) and "Fs" in t and "KT" not in t
    rows = t.report().splitlines()
    assert len(rows) == 4
    assert "identified" in rows[1] and "nuisance (fitted)" in rows[2] and "given" in rows[3]
    d = t.to_dict()
    assert d["parameters"][2]["stderr"] is None and d["parameters"][0]["upper"] is None
    page = t._repr_html_()  # a real table: header + one row per parameter
    assert "<pre>" not in page and page.count("<tr>") == len(t) + 1


def test_table_is_immutable():
    t = _table()
    with pytest.raises(dataclasses.FrozenInstanceError):
        t["Fs"].value = 2.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        t.parameters = ()
    with pytest.raises(TypeError):
        t["Fs"] = Parameter("Fs", 1.0)
    with pytest.raises(ValueError):
        t.correlation[0, 1] = 0.5
    v = t.values
    v["Fs"] = -1.0
    assert t["Fs"].value == 1000.0


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"value": math.nan}, "value must be finite"),
        ({"value": math.inf}, "value must be finite"),
        ({"stderr": -1.0}, "stderr"),
        ({"stderr": math.inf}, "stderr"),
        ({"lower": 2.0, "upper": 1.0, "value": 1.5}, "bounds must be ordered"),
        ({"lower": 2.0}, "must lie in its bounds"),
        ({"name": ""}, "name"),
        ({"value": "1"}, "real number"),
        ({"value": 1j}, "real number"),
        ({"identified": "no"}, "identified must be True or False"),
    ],
)
def test_parameter_validation(kw, match):
    args = {"name": "a", "value": 1.0}
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        Parameter(**args)


def test_table_validation():
    with pytest.raises(ValueError, match="unique"):
        ParameterTable([Parameter("a", 1.0), Parameter("a", 2.0)])
    with pytest.raises(ValueError, match="Parameter"):
        ParameterTable([("a", 1.0)])
    with pytest.raises(ValueError, match="correlation"):
        ParameterTable([Parameter("a", 1.0)], correlation=np.eye(2))


# ------------------------------------------------------------- the fits carry the table


def test_fit_result_params_table_and_joint():
    """fit_loops: params is a ParameterTable, .joint the IwanParameters built from it, and
    stderr/identified/correlation/fixed are views of the same table."""
    from iwan_element import IwanParameters, fit_loops
    from iwan_element.identify.loops.testdata import simulate_test

    p = IwanParameters(1000.0, 2e6, -0.5, 0.3)
    d = simulate_test(p, np.array([0.3, 1.0, 2.0]) * p.phi_max, cycles=2, force_noise=2.0, seed=1)
    r = fit_loops(d.t, d.u, d.F, seed=0)
    assert isinstance(r.params, ParameterTable) and r.params.names == ("Fs", "KT", "chi", "beta")
    assert r.joint == IwanParameters(*(r.params[k].value for k in r.params.names))
    assert r.stderr == r.params.stderr and r.identified == r.params.identified
    assert r.correlation is r.params.correlation and r.fixed == ()
    assert [r.params[k].unit for k in r.params] == ["N", "N/m", "1", "1"]
    assert abs(r.joint.KT / p.KT - 1) < 0.05
    d2 = r.to_dict()
    assert IwanParameters.from_dict(d2["joint"]) == r.joint
    assert [q["name"] for q in d2["params"]["parameters"]] == list(r.params.names)


# ------------------------------------------------------------------- the minimiser entry


def test_minimize_box_lm_and_trf_reach_the_same_bounded_minimum():
    """y = a exp(-b t) with b bounded below its unconstrained optimum: both solvers stop on
    the bound at the same a (the 1-D least squares in a with b held, closed form)."""
    from iwan_element.fitting import minimize

    rng = np.random.default_rng(8)
    t = np.linspace(0, 3, 80)
    y = 2.0 * np.exp(-1.3 * t) + 0.01 * rng.normal(size=t.size)

    def fun(x):
        return x[0] * np.exp(-x[1] * t) - y

    for method in ("box-lm", "trf"):
        r = minimize(fun, [1.0, 2.0], [0.0, 1.5], [10.0, 5.0], method=method, max_nfev=500)
        g = np.exp(-1.5 * t)
        assert r.success and r.x[1] == pytest.approx(1.5, abs=1e-9)
        assert r.x[0] == pytest.approx(g @ y / (g @ g), rel=1e-6), method
        assert r.cost == pytest.approx(0.5 * float(fun(r.x) @ fun(r.x)), rel=1e-12)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"method": "nelder"}, "method"),
        ({"lower": [1.0, 0.0], "upper": [0.0, 1.0]}, "lower < upper"),
        ({"x0": [np.nan, 1.0]}, "x0"),
        ({"max_nfev": 0}, "max_nfev"),
        ({"method": "box-lm", "x_scale": "jac"}, "no options"),
    ],
)
def test_minimize_rejects_bad_input(kw, match):
    from iwan_element.fitting import minimize

    args = {"x0": [0.5, 0.5], "lower": [0.0, 0.0], "upper": [1.0, 1.0], "max_nfev": 10}
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        minimize(lambda x: x - 0.3, args.pop("x0"), args.pop("lower"), args.pop("upper"), **args)
