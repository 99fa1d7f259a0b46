"""DiscreteIwan: slider layout, docs/equations.md section 4 figures, protocol and energy."""

import numpy as np
import pytest

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters, dissipation, slider_distribution

P = IwanParameters(1.0, 1.0, -0.5, 0.1)  # the case of docs/equations.md section 4


def steady_cycle_dissipation(el, u0, n=40):
    el.reset()
    cycle = np.concatenate([np.linspace(u0, -u0, n + 1)[1:], np.linspace(-u0, u0, n + 1)[1:]])
    for x in np.concatenate([[u0], cycle]):
        el.trial(x)
        el.commit()
    D0 = el.dissipated_energy
    for x in cycle:
        el.trial(x)
        el.commit()
    return el.dissipated_energy - D0


def test_moment_matched_bins_keep_KT_and_Fs():
    for p in [P, IwanParameters(3.0, 2.0, -0.1, 0.1), IwanParameters(1.0, 1.0, -0.9, 0.0)]:
        k, phi = slider_distribution(p, 100, spacing="log")
        assert k.sum() == pytest.approx(p.KT, rel=1e-12)
        assert (k * phi).sum() == pytest.approx(p.Fs, rel=1e-12)


def test_uniform_midpoint_underestimates_KT_as_in_reference():
    k, _ = slider_distribution(P, 100, spacing="uniform")
    assert k.sum() / P.KT - 1 == pytest.approx(-0.0275, abs=5e-4)  # docs/equations.md section 4


@pytest.mark.parametrize(
    "spacing,lowest,expected",
    [
        ("uniform", None, [2.4e-4, 8.6e-3, 3.3e-1, 1.0, 1.0]),
        ("log", 1e-5, [1.7e-3, 6.1e-4, 2.3e-3, 2.4e-3, 2.8e-3]),
    ],
)
def test_dissipation_errors_reproduce_reference_table(spacing, lowest, expected):
    kw = {} if lowest is None else {"lowest_edge": lowest}
    el = DiscreteIwan(P, 100, spacing=spacing, **kw)
    for r, e in zip([1.0, 0.1, 1e-2, 1e-3, 1e-4], expected):
        u0 = r * P.phi_max
        err = abs(steady_cycle_dissipation(el, u0) / dissipation(u0, P) - 1)
        assert err == pytest.approx(e, rel=0.1)


def test_uniform_sliders_dissipate_nothing_below_half_bin():
    el = DiscreteIwan(P, 100, spacing="uniform")
    assert steady_cycle_dissipation(el, 0.004 * P.phi_max) == 0.0


def test_dense_discrete_converges_to_exact():
    rng = np.random.default_rng(5)
    u = np.cumsum(rng.normal(size=300)) * 0.05 * P.phi_max
    F_exact = IwanJoint(P).force_history(u)
    errs = [np.max(np.abs(DiscreteIwan(P, n).force_history(u) - F_exact)) for n in (30, 300, 3000)]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-3 * P.Fs


def test_protocol_and_energy_balance():
    el = DiscreteIwan(P, 50)
    el.trial(0.5 * P.phi_max)
    assert el.displacement == 0.0 and el.work == 0.0  # trial commits nothing
    el.revert()
    u = P.phi_max * np.concatenate([np.linspace(0, 1.5, 3001), np.linspace(1.5, -0.3, 3001)])
    F = []
    for x in u:
        F.append(el.trial(x)[0])
        el.commit()
    work_trapz = np.trapezoid(F, u)
    assert el.work == pytest.approx(work_trapz, rel=1e-5)
    assert el.work == pytest.approx(el.stored_energy + el.dissipated_energy, rel=1e-12)
    assert np.allclose(el.force_history(u), F)
    # tangent: sum of stuck sliders, equals a one-sided difference inside a step
    el.reset()
    el.trial(0.2 * P.phi_max)
    el.commit()
    F1, K1 = el.trial(0.2 * P.phi_max + 1e-9 * P.phi_max)
    assert K1 == pytest.approx((F1 - el.force) / (1e-9 * P.phi_max), rel=1e-5)


@pytest.mark.parametrize(
    "kw,name",
    [
        (dict(n_sliders=0), "n_sliders"),
        (dict(n_sliders=2.5), "n_sliders"),
        (dict(spacing="linear"), "spacing"),
        (dict(lowest_edge=0.0), "lowest_edge"),
        (dict(lowest_edge=1.5), "lowest_edge"),
    ],
)
def test_bad_arguments(kw, name):
    with pytest.raises(ValueError, match=name):
        DiscreteIwan(P, **kw)
    with pytest.raises(ValueError, match="u must be finite"):
        DiscreteIwan(P).trial(np.nan)
