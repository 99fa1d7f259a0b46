"""Closed forms against the test vectors of docs/equations.md section 5 and against independent
routes (quadrature)."""

import numpy as np
import pytest
from scipy import integrate

from iwan_element import (
    IwanParameters,
    backbone,
    backbone_work,
    dissipation,
    dissipation_slope,
    force_amplitude,
    masing_ascending,
    masing_descending,
    masing_loop,
    normalized_backbone,
    secant_stiffness,
    tangent_stiffness,
)

P_REF = IwanParameters(3.0, 2.0, -0.1, 0.1)
PARAMS = [
    P_REF,
    IwanParameters(400.0, 2.5266e5, -0.5, 1.0),
    IwanParameters(1000.0, 1e6, -0.5, 0.2),
    IwanParameters(1.0, 1.0, -0.8, 0.0),
    IwanParameters(2.0, 5.0, 0.3, 2.0),
]


def test_dissipation_reference_vector():
    """docs/equations.md section 5: D for (3, 2, -0.1, 0.1) at seven amplitudes."""
    r = np.array([1e-3, 1e-2, 0.1, 0.5, 1.0, 1.5, 3.0])
    expected = [
        1.96069620e-8,
        1.55743635e-5,
        1.23711567e-2,
        1.31650745,
        9.82675904,
        2.70836398e1,
        7.88542820e1,
    ]
    np.testing.assert_allclose(dissipation(r * P_REF.phi_max, P_REF), expected, rtol=1e-8)


def _force_by_density(u, p):
    """Backbone from the slider density, paper eq. 18, by quadrature (independent route)."""
    a = min(abs(u), p.phi_max)

    def moment(k, lo, hi):  # int_lo^hi R phi**(chi+k), the phi**chi singularity as a quad weight
        def from0(b):
            return integrate.quad(lambda phi: p.R * phi**k, 0, b, weight="alg", wvar=(p.chi, 0))[0]

        return from0(hi) - from0(lo)

    slipped = moment(1, 0.0, a)
    held = moment(0, a, p.phi_max)
    f = slipped + a * held + p.S * min(abs(u), p.phi_max)
    return np.sign(u) * f


@pytest.mark.parametrize("p", PARAMS)
def test_backbone_matches_density_integral(p):
    for r in [1e-4, 0.03, 0.5, 0.999, 1.0, 2.0, -0.7]:
        u = r * p.phi_max
        assert backbone(u, p) == pytest.approx(_force_by_density(u, p), rel=1e-8, abs=1e-12 * p.Fs)


@pytest.mark.parametrize("p", PARAMS)
def test_backbone_limits_and_tangent(p):
    u = np.linspace(-3, 3, 2001) * p.phi_max
    F = backbone(u, p)
    assert np.all(np.abs(F) <= p.Fs * (1 + 1e-12))
    np.testing.assert_allclose(backbone(-u, p), -F, rtol=0, atol=0)
    assert backbone(p.phi_max, p) == pytest.approx(p.Fs, rel=1e-12)
    assert tangent_stiffness(0.0, p) == pytest.approx(p.KT)
    # tangent just below phi_max equals the spike stiffness S (docs/equations.md section 2)
    assert tangent_stiffness(p.phi_max * (1 - 1e-12), p) == pytest.approx(
        p.S, rel=1e-6, abs=1e-6 * p.KT
    )
    assert tangent_stiffness(2 * p.phi_max, p) == 0.0
    # finite difference of the backbone
    x = np.array([0.01, 0.3, 0.8]) * p.phi_max
    h = 1e-7 * p.phi_max
    fd = (backbone(x + h, p) - backbone(x - h, p)) / (2 * h)
    np.testing.assert_allclose(tangent_stiffness(x, p), fd, rtol=1e-6)


@pytest.mark.parametrize("p", PARAMS)
def test_secant_eq24(p):
    r = np.array([1e-6, 0.1, 0.5, 1.0])
    u0 = r * p.phi_max
    np.testing.assert_allclose(secant_stiffness(u0, p), backbone(u0, p) / u0, rtol=1e-12)
    eq24 = p.KT * (1 - r ** (p.chi + 1) / ((p.chi + 2) * (1 + p.beta)))
    np.testing.assert_allclose(secant_stiffness(u0, p), eq24, rtol=1e-12)
    assert secant_stiffness(0.0, p) == p.KT
    assert secant_stiffness(3 * p.phi_max, p) == pytest.approx(p.Fs / (3 * p.phi_max))
    np.testing.assert_allclose(force_amplitude(u0, p), backbone(u0, p))


@pytest.mark.parametrize("p", PARAMS)
def test_dissipation_equals_masing_integral(p):
    """Any Masing model: D = 8 int_0^u0 F dx - 4 u0 F(u0) (docs/equations.md section 2), by
    quadrature."""
    for r in [1e-3, 0.2, 0.9, 1.0, 1.7, 4.0]:
        u0 = r * p.phi_max
        pts = [p.phi_max] if u0 > p.phi_max else None
        I = integrate.quad(
            lambda x: backbone(x, p), 0, u0, points=pts, epsabs=0, epsrel=1e-12, limit=200
        )[0]
        D_masing = 8 * I - 4 * u0 * backbone(u0, p)
        assert dissipation(u0, p) == pytest.approx(D_masing, rel=1e-8)
        assert backbone_work(u0, p) == pytest.approx(I, rel=1e-10)


@pytest.mark.parametrize("p", PARAMS)
def test_masing_loop_area_equals_dissipation(p):
    for r in [0.05, 0.6, 1.0, 2.5]:
        u0 = r * p.phi_max
        u, F = masing_loop(u0, p, n=20001)
        area = np.trapezoid(F, u)  # clockwise in (u, F): descending branch below
        assert area == pytest.approx(dissipation(u0, p), rel=1e-6)
        assert u[0] == u[-1] and F[0] == pytest.approx(F[-1], rel=1e-12)


def test_dissipation_slope_eq21_and_reference_values():
    """Local slope d ln D / d ln F0 (docs/equations.md section 2 values at chi = -0.5, beta = 0)."""
    p = IwanParameters(1.0, 1.0, -0.5, 0.0)
    F0_over_Fs = np.array([0.001, 0.1, 0.3, 0.5])
    # invert the backbone for u0
    from scipy.optimize import brentq

    u0 = np.array(
        [brentq(lambda x, f=f: backbone(x, p) - f * p.Fs, 0, p.phi_max) for f in F0_over_Fs]
    )
    np.testing.assert_allclose(dissipation_slope(u0, p), [2.516, 2.703, 2.975, 3.333], atol=6e-4)
    # against a numerical derivative of the closed forms
    h = 1e-6
    for x in u0:
        dlnD = np.log(dissipation(x * (1 + h), p) / dissipation(x * (1 - h), p))
        dlnF = np.log(backbone(x * (1 + h), p) / backbone(x * (1 - h), p))
        assert dissipation_slope(x, p) == pytest.approx(dlnD / dlnF, rel=1e-6)


def test_dimensionless_forms_match_dimensional():
    p = IwanParameters(7.0, 3.0, -0.3, 0.4)
    s = np.linspace(-1, 1, 101)
    np.testing.assert_allclose(
        normalized_backbone(s, p.chi, p.beta),
        backbone(s * p.phi_max, p) / p.Fs,
        rtol=1e-12,
        atol=1e-15,
    )
    u, F = masing_loop(p.phi_max, p, n=101)
    np.testing.assert_allclose(
        masing_descending(u[:101] / p.phi_max, 1.0, p.chi, p.beta),
        F[:101] / p.Fs,
        rtol=1e-12,
        atol=1e-14,
    )
    np.testing.assert_allclose(
        masing_ascending(u[100:] / p.phi_max, 1.0, p.chi, p.beta),
        F[100:] / p.Fs,
        rtol=1e-12,
        atol=1e-14,
    )


def test_eq14_symmetry_and_corrected_eq15():
    """f_d(s) = -f_u(-s) (paper eq. 14); both branches meet the virgin curve at +-s0."""
    s = np.linspace(-0.8, 0.8, 33)
    for chi, beta in [(0.5, 0.0), (0.5, 1.0), (-0.5, 0.5)]:
        fu = masing_descending(s, 0.8, chi, beta)
        fd = masing_ascending(s, 0.8, chi, beta)
        np.testing.assert_allclose(fd, -masing_descending(-s, 0.8, chi, beta), atol=1e-15)
        f0 = normalized_backbone(0.8, chi, beta)
        assert fu[0] == pytest.approx(-f0) and fu[-1] == pytest.approx(f0)
        assert fd[0] == pytest.approx(-f0) and fd[-1] == pytest.approx(f0)
        assert np.all(fd >= fu - 1e-15)  # reloading branch above the unloading branch


def test_figure3_nonphysical_beta_warns_but_draws():
    with pytest.warns(UserWarning, match="non-physical"):
        f = normalized_backbone(np.linspace(0, 1, 5), 1.0, -0.5)
    assert np.isfinite(f).all() and f[-1] == pytest.approx(1.0)


@pytest.mark.parametrize(
    "call",
    [
        lambda p: backbone(np.nan, p),
        lambda p: dissipation(-1.0, p),
        lambda p: dissipation([1.0, np.inf], p),
        lambda p: secant_stiffness(-0.1, p),
        lambda p: masing_loop(0.0, p),
        lambda p: masing_loop(1.0, p, n=2),
        lambda p: backbone(1.0, {"Fs": 1}),
        lambda p: normalized_backbone(0.5, -1.0, 0.0),
    ],
)
def test_bad_input_raises(call):
    with pytest.raises(ValueError):
        call(P_REF)


def test_inputs_not_mutated():
    u = np.linspace(0, 1, 10)
    keep = u.copy()
    backbone(u, P_REF)
    dissipation(u, P_REF)
    np.testing.assert_array_equal(u, keep)
