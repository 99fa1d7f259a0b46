"""The specimen in the frequency domain: the reduced model, harmonic balance, nonlinear modes.

Independent routes: the full model's static condensation and all its modes (reduction), the
closed-form linear receptance of the stuck limit, QSMA (microslip backbone), the modal form of
an effect, and the phase-resonance condition linking the forced response to the nonlinear
mode.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
from iwan_element.models.reduced import (
    contact_points,
    linear_system,
    reduced_model,
    reduction_error,
)

from iwan_element import models

BRB = models.preset("brake-reuss")


def test_reduced_model_statics_are_exact_and_its_error_is_reported():
    red = reduced_model(BRB)
    L, pts = linear_system(BRB), contact_points(BRB)
    A = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    V = sla.eigh(A, L.M, subset_by_index=[0, 2])[1]  # the rigid-body modes
    MV = L.M @ V
    Ap = A + 1e6 * MV @ MV.T
    C = L.G @ np.linalg.solve(Ap, L.G.T)
    H0 = red.system.receptance(0.0).real[: len(pts), : len(pts)]
    np.testing.assert_allclose(H0, C, rtol=0, atol=1e-9 * np.abs(C).max())
    e = reduction_error(BRB, n_modes=8, frequencies=np.linspace(0, 400, 81))
    assert e["max_relative_error"] < 1e-3 and e["n_full"] == L.M.shape[0]
    assert red.frequency(1) == pytest.approx(
        models.natural_frequencies(BRB, n_modes=4)[3], rel=1e-8
    )


def test_stuck_specimen_is_its_linear_frf():
    """Friction so high nothing slips, chi = 1 (microslip ~ (u/phi_max)^2): the harmonic
    balance is the reduced model's linear receptance to round-off, and the full model's
    (all modes) to the reduction's error."""
    s = BRB.replace(friction=1e6, chi=1.0)
    red = reduced_model(s)
    f = np.linspace(75, 85, 11)
    r = models.harmonic_balance(s, frequency=f, force=0.7)
    nz = red.system.n_z
    H = np.array([red.system.receptance(2 * np.pi * fk)[nz, nz + 1] for fk in f])
    np.testing.assert_allclose(r.amplitude, 0.7 * np.abs(H), rtol=1e-9)
    np.testing.assert_allclose(r.phase, np.angle(H), atol=1e-9)
    L = linear_system(s)
    w2, V = sla.eigh(L.K0 + L.G.T @ (contact_points(s).KT[:, None] * L.G), L.M)
    V = V / np.sqrt(np.einsum("ij,ij->j", V, L.M @ V))
    z = np.array([0.0] * 3 + [s.floor(k) for k in range(1, w2.size - 2)])
    w = np.sqrt(np.clip(w2, 0, None))
    Hf = [np.sum((L.S @ V) * (L.E @ V) / (w * w - W * W + 2j * z * w * W)) for W in 2 * np.pi * f]
    np.testing.assert_allclose(r.amplitude, 0.7 * np.abs(Hf), rtol=1e-3)


def test_nonlinear_mode_agrees_with_qsma_in_microslip():
    X = np.geomspace(2e-6, 60e-6, 8)
    c = models.nonlinear_mode(BRB, amplitude=X)
    q = models.modal_amplitude_curve(BRB, amplitude=X)
    assert c.method == "epmc" and len(c) == X.size
    np.testing.assert_allclose(c.frequency, q.frequency, rtol=2e-4)
    np.testing.assert_allclose(c.damping_ratio, q.damping_ratio, rtol=0.05)


def test_second_mode_has_its_own_floor():
    s = BRB.replace(modal_damping=(BRB.floor(1), 9.7e-4))
    c = models.nonlinear_mode(s, amplitude=[1e-8], mode=2)
    assert c.frequency[0] == pytest.approx(reduced_model(s).frequency(2), rel=1e-5)
    assert c.damping_ratio[0] == pytest.approx(9.7e-4, rel=0.02)


def test_effects_run_through_the_nonlinear_mode_as_in_their_modal_form():
    s = BRB.with_effects(
        {"hardening": {"k3_per_mass": 2e12}}, mode=1, calibrated_range=(2e-6, 60e-6)
    )
    X = np.geomspace(5e-6, 50e-6, 5)
    c = models.nonlinear_mode(s, amplitude=X)
    q = models.modal_amplitude_curve(s, amplitude=X)
    plain = models.nonlinear_mode(BRB, amplitude=X)
    assert np.all(c.frequency[-2:] > plain.frequency[-2:] + 0.05)  # it hardens
    np.testing.assert_allclose(c.frequency, q.frequency, rtol=2e-4)
    np.testing.assert_allclose(c.damping_ratio, q.damping_ratio, rtol=0.05)


def test_phase_resonance_lies_on_the_nonlinear_mode():
    """Where the forced response's phase crosses -pi/2 the drive balances the damping: its
    frequency is the nonlinear mode's at that amplitude (light damping)."""
    f = np.linspace(80.0, 80.6, 61)
    r = models.harmonic_balance(BRB, frequency=f, force=0.3)
    assert r.success
    k = int(np.argmax(r.phase < -np.pi / 2))
    t = (-np.pi / 2 - r.phase[k - 1]) / (r.phase[k] - r.phase[k - 1])
    f90 = f[k - 1] + t * (f[k] - f[k - 1])
    X90 = r.amplitude[k - 1] + t * (r.amplitude[k] - r.amplitude[k - 1])
    c = models.nonlinear_mode(BRB, amplitude=[X90])
    assert f90 == pytest.approx(c.frequency[0], rel=2e-4)


def test_specimen_entries_refuse_bad_input():
    with pytest.raises(ValueError, match="specimen"):
        models.harmonic_balance("beam", frequency=[80.0], force=1.0)
    with pytest.raises(ValueError, match="mode"):
        models.nonlinear_mode(BRB, amplitude=[1e-5], mode=12)
    with pytest.raises(ValueError, match="amplitude"):
        models.nonlinear_mode(BRB, amplitude=[-1e-5])
    with pytest.raises(ValueError, match="n_modes"):
        reduced_model(BRB, n_modes=0)


def test_harmonic_balance_matches_the_exudyn_stepped_sine():
    """The Exudyn time integration of the same specimen (the trapezoidal rule driven at the
    pre-warped frequency, 60 settling periods at a 2 % floor: the transient decays to 5e-4),
    read by lock-in, against the harmonic balance at the same frequencies: below, at and
    above the resonance, the interface barely slipping (0.02 N)."""
    s = BRB.replace(damping_floor=0.02, modal_damping=())
    f = np.array([0.985, 1.0, 1.012]) * reduced_model(s).frequency(1)
    ts = models.forced_response(
        s,
        force_levels=(0.02,),
        frequencies=f,
        settle_cycles=60,
        measure_cycles=10,
        steps_per_period=64,
        spectral_radius=1.0,
    )
    hb = models.harmonic_balance(s, frequency=f, force=0.02)
    np.testing.assert_allclose(ts.amplitude[0], hb.amplitude, rtol=5e-3)
    np.testing.assert_allclose(ts.phase[0], hb.phase, atol=1e-2)
    # Newton's tolerance above the residual's round-off: no step cut, at most one Jacobian
    # per frequency (Exudyn's route had stalled at 1.012 x and taken 233-560 of them,
    # docs/transient_cost.md; the condensed route takes none)
    assert ts.metadata["jacobians"].max() <= 2 and ts.metadata["step_cuts"].max() == 0


def test_nonlinear_mode_agrees_with_the_transient_ring_down():
    """EPMC against the Exudyn ring-down's curve (modal filter, free-decay route) of the
    Brake-Reuss beam from the top of its range, with the tolerances QSMA meets there."""
    s = BRB.replace(n_points=20)
    tr = models.ringdown(s, amplitude=s.amplitude_range[1], cycles=12, steps_per_period=48).curve
    c = models.nonlinear_mode(s, amplitude=tr.amplitude)
    assert len(tr) >= 3 and tr.amplitude.max() / tr.amplitude.min() > 1.02
    np.testing.assert_array_less(np.abs(tr.frequency / c.frequency - 1), 1e-3)
    np.testing.assert_array_less(np.abs(tr.damping_ratio / c.damping_ratio - 1), 0.10)
