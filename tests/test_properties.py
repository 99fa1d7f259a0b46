"""Property tests (hypothesis) of the exact Iwan joint and the closed forms.

The number of examples is bounded by the settings profiles of ``tests/conftest.py`` (``ci``
by default); ``benchmarks/bench_properties.py`` runs them with many more examples.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import log_uniform, params_strategy, step_element
from hypothesis import assume, given
from hypothesis import strategies as st

from iwan_element import (
    IwanJoint,
    IwanParameters,
    backbone,
    backbone_work,
    dissipation,
    dissipation_slope,
    secant_stiffness,
    tangent_stiffness,
)

# reversal targets as fractions of phi_max: large, small and tiny excursions mixed
_targets = st.lists(
    st.one_of(st.floats(-3.0, 3.0), st.floats(-1e-3, 1e-3)), min_size=1, max_size=12
)


@st.composite
def histories(draw):
    """(params, u): a displacement history [m] through random reversal points, each leg
    sampled at a few points; some legs are tiny excursions around the previous point."""
    p = draw(params_strategy)
    pts = [0.0]
    for a in draw(_targets):
        if draw(st.booleans()):
            a = pts[-1] + draw(st.floats(-1e-3, 1e-3))  # a small loop inside a big one
        pts.append(a)
    legs = [np.linspace(a, b, draw(st.integers(2, 6)))[1:] for a, b in zip(pts[:-1], pts[1:])]
    return p, p.phi_max * np.concatenate(legs)


def _state(j):
    us, Fr = j.reversal_points()
    return (
        j.displacement,
        j.force,
        j.stiffness,
        j.work,
        j.dissipated_energy,
        tuple(us.tolist()),
        tuple(Fr.tolist()),
    )


# ---------------------------------------------------------------- the element
def _slider_bank(p, n=20000):
    """An independent dense bank: ``n`` equal bins in ``s = phi/phi_max`` with weight = the
    integral of rho over the bin and slip at the bin's centroid (moment matching, docs/equations.md
    section 4), plus the spike. Returns (k, phi, bound): ``bound = sum k_i (hi_i - lo_i)
    = K_slider phi_max / n`` is the largest force error of the bank, since a slider's force is
    1-Lipschitz in its slip threshold (moving each threshold inside its bin changes the force
    by at most k_i (hi_i - lo_i))."""
    e = np.linspace(0.0, 1.0, n + 1)
    c = p.chi
    m0 = e[1:] ** (c + 1) - e[:-1] ** (c + 1)  # int_lo^hi (c+1) s^c ds
    m1 = e[1:] ** (c + 2) - e[:-1] ** (c + 2)
    k = p.KT / (1.0 + p.beta) * m0  # R phi_max^(c+1)/(c+1) = KT/(1+beta)
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(m0 > 0, (c + 1) / (c + 2) * m1 / m0, e[1:])
    bound = float(np.sum(k * np.diff(e)) * p.phi_max)
    k = np.append(k, p.KT * p.beta / (1.0 + p.beta))  # spike S at phi_max
    phi = np.append(s, 1.0) * p.phi_max
    return k, phi, bound


@given(histories())
def test_exact_joint_agrees_with_a_dense_slider_bank(case):
    p, u = case
    F = step_element(IwanJoint(p, reversal_tol=0.0), u)
    k, phi, bound = _slider_bank(p)
    x = np.zeros_like(k)
    Fb = np.empty(len(u))
    for i, ui in enumerate(u):
        x = np.clip(x, ui - phi, ui + phi)  # each Jenkins slider: |u - x| <= phi
        Fb[i] = np.dot(k, ui - x)
    assert np.max(np.abs(F - Fb)) <= bound + 1e-9 * p.Fs


@given(histories(), st.floats(0.02, 0.98))
def test_closed_cycles_dissipate_non_negative_energy(case, frac):
    """D never decreases; a closed cycle u_s -> a -> u_s inside the current branch restores
    the state, and its work equals its dissipation, 4 I_H(|a - u_s|/2) = D(|a - u_s|/2) >= 0."""
    p, u = case
    j = IwanJoint(p, reversal_tol=0.0)
    D_prev = 0.0
    for x in u.tolist():
        j.trial(x)
        j.commit()
        assert j.dissipated_energy >= D_prev
        D_prev = j.dissipated_energy
    before = _state(j)
    us = j.reversal_points()[0]
    bound = us[-1] if len(us) else -j.displacement  # the current branch closes there
    us_ = j.displacement
    a = us_ + frac * (bound - us_)
    assume(abs(a - us_) > 1e-6 * p.phi_max)
    for x in np.concatenate([np.linspace(us_, a, 7)[1:], np.linspace(a, us_, 7)[1:]]):
        j.trial(x)
        j.commit()
        assert j.dissipated_energy >= D_prev
        D_prev = j.dissipated_energy
    after = _state(j)
    assert after[5:] == before[5:]  # memory restored (Madelung)
    assert after[1] == pytest.approx(before[1], abs=1e-9 * p.Fs)
    dW, dD = after[3] - before[3], after[4] - before[4]
    expected = dissipation(abs(a - us_) / 2.0, p)
    scale = p.Fs * abs(a - us_)
    assert dD >= 0.0
    assert dW == pytest.approx(expected, rel=1e-6, abs=1e-9 * scale)
    assert dD == pytest.approx(expected, rel=1e-6, abs=1e-9 * scale)


@given(histories())
def test_masing_rule_on_every_branch(case):
    """After each commit: F = F_r + s 2 F_bb(|u - u_r|/2) from the top reversal (u_r, F_r), or
    the backbone on the virgin curve; each remembered reversal is a committed (u, F) of the
    history; the stack is nested (excursions shrink)."""
    p, u = case
    j = IwanJoint(p, reversal_tol=0.0)
    seen = {0.0: [0.0]}
    for x in u.tolist():
        j.trial(x)
        j.commit()
        seen.setdefault(j.displacement, []).append(j.force)
        us, Fr = j.reversal_points()
        if len(us):
            ur, Fr_top = us[-1], Fr[-1]
            s = 1.0 if x >= ur else -1.0
            expected = Fr_top + s * 2.0 * backbone(abs(x - ur) / 2.0, p)
        else:
            expected = backbone(x, p)
        assert j.force == pytest.approx(expected, rel=1e-12, abs=1e-12 * p.Fs)
        for a, b in zip(us.tolist(), Fr.tolist()):
            assert b in seen[a]
        # nested: each reversal lies strictly inside the excursion of the two before it
        # (the first inside (-u_0, u_0)); sign tests, since differences of ~1e-224 round away
        chain = ([-us[0]] if len(us) else []) + us.tolist()
        for k in range(2, len(chain)):
            assert min(chain[k - 2], chain[k - 1]) < chain[k] < max(chain[k - 2], chain[k - 1])


@given(histories(), st.lists(st.floats(-3.0, 3.0), min_size=1, max_size=5))
def test_trial_without_commit_changes_nothing_and_revert_restores(case, probes):
    p, u = case
    j = IwanJoint(p)
    ref = IwanJoint(p)
    for x in u.tolist():
        for q in probes:
            j.trial(q * p.phi_max)
        before = _state(j)
        j.trial(x + p.phi_max * probes[0])
        j.revert()
        assert _state(j) == before
        assert j.trial(x) == ref.trial(x)
        j.commit()
        ref.commit()
        assert _state(j) == _state(ref)


@given(histories(), st.floats(-12.0, -1.0), st.booleans())
def test_force_is_continuous_and_tangent_bounded(case, log_h, up):
    """|F(u_c + h) - F_c| <= KT |h| (every slider's tangent is in [0, KT]); the trial tangent
    is in [0, KT]."""
    p, u = case
    j = IwanJoint(p)
    h = (1.0 if up else -1.0) * 10.0**log_h * p.phi_max
    for x in u.tolist():
        F, K = j.trial(x)
        assert 0.0 <= K <= p.KT
        j.commit()
        F1, _ = j.trial(x + h)
        assert abs(F1 - F) <= p.KT * abs(h) * (1.0 + 1e-9) + 1e-12 * p.Fs
        j.revert()


# ---------------------------------------------------------------- closed forms
_r = np.concatenate([[0.0], np.geomspace(1e-9, 20.0, 300)])


@given(params_strategy)
def test_closed_forms_are_finite_and_monotone(p):
    u = _r * p.phi_max
    F = backbone(u, p)
    Kt = tangent_stiffness(u, p)
    Ks = secant_stiffness(u, p)
    D = dissipation(u, p)
    G = backbone_work(u, p)
    for v in (F, Kt, Ks, D, G):
        assert np.all(np.isfinite(v))
    assert np.all(np.diff(F) >= 0.0) and F[-1] == p.Fs and np.all(F <= p.Fs * (1 + 1e-12))
    assert np.all(backbone(-u, p) == -F)
    assert np.all((Kt >= 0.0) & (Kt <= p.KT))
    assert np.all(np.diff(Ks) <= 1e-12 * p.KT)
    assert np.all(np.diff(D) >= 0.0) and D[0] == 0.0
    # any Masing model: D = 8 int_0^u0 F - 4 u0 F(u0) (docs/equations.md section 2), an
    # independent route
    assert np.allclose(D, 8.0 * G - 4.0 * u * F, rtol=1e-7, atol=1e-12 * p.Fs * p.phi_max)
    slope = dissipation_slope(u[1:], p)
    assert np.all(slope[_r[1:] < 1.0] >= (p.chi + 3.0) * (1.0 - 1e-9))


_bad = st.one_of(
    st.just(math.nan),
    st.just(math.inf),
    st.just(-math.inf),
    st.floats(-1e6, 0.0),
    st.text(max_size=3),
    st.none(),
    st.just(1 + 1j),
)


@given(st.sampled_from(["Fs", "KT", "chi", "beta"]), _bad)
def test_invalid_parameters_give_a_clear_error(name, bad):
    kw = dict(Fs=1e3, KT=1e6, chi=-0.5, beta=0.2)
    if name == "chi" and isinstance(bad, float) and -1.0 < bad <= 0.0:
        bad = bad - 1.0  # (-1, 0] is valid for chi
    if name == "beta" and bad == 0.0:
        bad = -1.0
    kw[name] = bad
    with pytest.raises(ValueError, match=name):
        IwanParameters(**kw)


_wide_params = st.tuples(
    log_uniform(1e-120, 1e120),
    log_uniform(1e-120, 1e120),
    st.one_of(st.floats(-0.999999, 2.0), log_uniform(1.0, 1e6)),
    st.one_of(st.just(0.0), log_uniform(1e-12, 1e12)),
)


@given(_wide_params)
def test_extreme_valid_parameters_compute_or_are_refused_clearly(vals):
    """Any (Fs, KT, chi, beta) in range either builds, and then every closed form and the
    element are finite without numpy overflow warnings, or is refused with a ValueError
    saying which derived quantity leaves the float range."""
    import warnings

    try:
        p = IwanParameters(*vals)
    except ValueError as exc:
        assert "outside the float range" in str(exc)
        return
    u = _r * p.phi_max
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        out = [
            backbone(u, p),
            tangent_stiffness(u, p),
            secant_stiffness(u, p),
            dissipation(u, p),
            backbone_work(u, p),
            dissipation_slope(u[1:50], p),
        ]
        j = IwanJoint(p)
        for x in (0.5, -0.3, 2.0, -2.0, 0.1):
            out.append(np.array(j.trial(x * p.phi_max)))
            j.commit()
        out.append(np.array([j.work, j.dissipated_energy]))
    for v in out:
        assert np.all(np.isfinite(v))
    assert abs(backbone(2.0 * p.phi_max, p)) == p.Fs
