"""Quasi-static modal analysis against the transient ring-down (two independent routes)."""

import math

import numpy as np
import pytest
from iwan_element.models import modal_amplitude_curve, preset, ringdown
from iwan_element.models.modal import linear_modes, static_modal_load

from iwan_element import AmplitudeCurve, dissipation

NAMES = ("example", "brake-reuss", "two-bolt-aluminium")


def _compare(name, mode, amplitude, cycles, **changes):
    s = preset(name).replace(**changes) if changes else preset(name)
    r = ringdown(s, mode=mode, amplitude=amplitude, cycles=cycles, steps_per_period=48)
    tr = r.curve
    q = modal_amplitude_curve(s, mode=mode, amplitude=tr.amplitude)
    return s, tr, q


CASES = [("example", 2), ("brake-reuss", 1), ("two-bolt-aluminium", 2)]


@pytest.mark.parametrize("name,mode", CASES)
def test_qsma_agrees_with_the_transient_ring_down_at_the_top_of_the_range(name, mode):
    s = preset(name)
    s, tr, q = _compare(name, mode, s.amplitude_range[1], 12)
    assert tr.amplitude.max() / tr.amplitude.min() > 1.02  # it really decayed
    np.testing.assert_array_less(np.abs(tr.frequency / q.frequency - 1), 1e-3)
    np.testing.assert_array_less(np.abs(tr.damping_ratio / q.damping_ratio - 1), 0.10)
    # the joint's share is a visible part of the damping (the test could fail on it)
    assert q.damping_ratio.max() > 1.2 * s.interface.damping_floor


@pytest.mark.parametrize("name,mode", CASES)
def test_qsma_agrees_with_the_transient_ring_down_at_the_bottom_of_the_range(name, mode):
    # At the bottom of every preset's range the damping floor dominates (the joint adds 3-12 %
    # of zeta), so the preset as documented is compared first, then the joint's share alone
    # (no floor), which a wrong interface law could not pass. The forces there are ~1 N: the
    # run needs Newton's tolerance above the model's round-off
    # (models.simulation.solver.roundoff_force).
    s = preset(name)
    low = s.amplitude_range[0]
    for changes in ({}, {"damping_floor": 0.0}):
        s2, tr, q = _compare(name, mode, low, 12, **changes)
        assert len(tr) >= 3 and tr.amplitude.max() <= low * 1.001
        np.testing.assert_array_less(np.abs(tr.frequency / q.frequency - 1), 1e-3)
        np.testing.assert_array_less(np.abs(tr.damping_ratio / q.damping_ratio - 1), 0.10)
    assert q.damping_ratio.min() > 0.02 * s.interface.damping_floor  # the joint damps


@pytest.mark.parametrize("floor", [0.0, None], ids=["no floor", "preset floor"])
def test_energy_closes_with_the_distributed_interface(floor):
    """Kinetic + strain + springs + joint stored + joint, floor and effect dissipation stay
    the release energy to 1e-3, with the joints alone and with the preset's damping floor
    (its beam damping's work booked from the velocities), each dissipating a visible part."""
    s = preset("brake-reuss").replace(n_points=24)
    if floor is not None:
        s = s.replace(damping_floor=floor)
    r = ringdown(s, amplitude=60e-6, cycles=12, steps_per_period=48, record_energy=True)
    err = r.energy_error()
    dissipated = r.energy["joint_dissipated"][-1] - r.energy["joint_dissipated"][0]
    assert dissipated > 0.05 * r.initial_energy  # the joint did work
    if floor is None:
        assert r.energy["floor_dissipated"][-1] > 0.05 * r.initial_energy
    else:
        assert not np.any(r.energy["floor_dissipated"])
    assert np.max(np.abs(err)) < 1e-3
    # what the balance measures is the integrator's quadrature of the joint forces: the
    # joints' exact work minus the trapezoidal work of their recorded slips and forces
    # (with the floor, also the floor's work booked from the linearised beam stiffness:
    # measured 9e-5 of the release energy here)
    tol = 2e-5 if floor is not None else 1.5e-4
    assert err[-1] == pytest.approx(r.metadata["joint_quadrature_error"], abs=tol)
    assert r.success and "trapezoidal work" in r.report()


def test_a_coarse_ring_down_states_its_energy_error_instead_of_hiding_it():
    """16 steps per period: the integrator's quadrature of the joint forces leaves a balance
    error above 1e-3 (measured 2.6e-3, against 1.5e-4 at 48 steps); the result is returned,
    not a success, and its warning names the cure."""
    s = preset("brake-reuss").replace(n_points=24)
    r = ringdown(s, amplitude=60e-6, cycles=12, steps_per_period=16, record_energy=True)
    assert r.max_energy_error > 1e-3 and not r.success
    assert any("energy balance is off" in w and "steps_per_period" in w for w in r.warnings)


def test_small_amplitudes_tend_to_the_stuck_linear_mode_and_the_floor():
    s = preset("brake-reuss")
    w0, *_ = linear_modes(s)
    # the joint's share falls as X**(chi+1) (docs/equations.md section 7): slowly, so go far down
    c = modal_amplitude_curve(s, amplitude=[1e-15, 1e-13])
    f0 = w0 / (2 * math.pi)
    assert c.frequency[0] == pytest.approx(f0, rel=1e-7)
    assert c.damping_ratio[0] == pytest.approx(s.interface.damping_floor, rel=1e-4)
    ratio = (1 - c.frequency[1] / f0) / (1 - c.frequency[0] / f0)
    assert ratio == pytest.approx(100 ** (s.interface.chi + 1), rel=0.05)


def test_qsma_curve_softens_and_damps_more_with_amplitude_and_hits_the_asked_amplitudes():
    s = preset("brake-reuss")
    c = modal_amplitude_curve(s)
    assert isinstance(c, AmplitudeCurve) and c.method == "qsma" and len(c) == 20
    np.testing.assert_allclose(c.amplitude[[0, -1]], s.amplitude_range)
    assert np.all(np.diff(c.frequency) < 0) and np.all(np.diff(c.damping_ratio) > 0)
    st = static_modal_load(s, c.amplitude)
    np.testing.assert_allclose(st["x"] @ st["system"].S, c.amplitude, rtol=1e-9)
    # the damping is the sum of the points' closed-form dissipations (sec. 2) over 2 pi alpha q
    D = sum(dissipation(np.abs(st["slip"][:, i]), p) for i, p in enumerate(st["points"].params))
    z = s.interface.damping_floor + D / (2 * math.pi * st["alpha"] * st["q"])
    np.testing.assert_allclose(c.damping_ratio, z, rtol=1e-12)


def test_looser_bolts_and_lower_friction_damp_more():
    s = preset("brake-reuss")
    X = [1e-5, 5e-5]
    base = modal_amplitude_curve(s, amplitude=X).damping_ratio
    assert np.all(
        modal_amplitude_curve(s.replace(preload=s.preload / 2), amplitude=X).damping_ratio > base
    )
    assert np.all(
        modal_amplitude_curve(s.replace(friction=s.friction / 2), amplitude=X).damping_ratio > base
    )


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"amplitude": [-1e-6]}, "amplitude"),
        ({"amplitude": [np.nan]}, "amplitude"),
        ({"mode": 0}, "mode"),
        ({"mode": 1.5}, "mode"),
    ],
)
def test_bad_qsma_input_is_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        modal_amplitude_curve(preset("example"), **kw)


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"amplitude": -1.0}, "amplitude"),
        ({"amplitude": 1e-5, "cycles": 1}, "cycles"),
        ({"amplitude": 1e-5, "steps_per_period": 4}, "steps_per_period"),
        ({"amplitude": 1e-5, "n_periods": 2}, "n_periods"),
    ],
)
def test_bad_ringdown_input_is_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        ringdown(preset("example"), **kw)


def test_the_two_bolt_beam_at_the_top_of_its_range_runs_without_step_cuts():
    """The two-bolt aluminium beam released from 500 um (the top of its range), where the
    Cable2D beams made Exudyn cut about 1,700 steps: on the host (models/simulation/host.py) none is
    cut, and the decay rings at the QSMA frequency and damping."""
    s = preset("two-bolt-aluminium")
    r = ringdown(s, amplitude=5e-4, cycles=12)
    assert r.metadata["extra_steps"] == 0
    assert not any("steps more than" in w for w in r.warnings)
    q = modal_amplitude_curve(s, amplitude=r.curve.amplitude)
    np.testing.assert_allclose(r.curve.frequency, q.frequency, rtol=1e-3)
    np.testing.assert_allclose(r.curve.damping_ratio, q.damping_ratio, rtol=0.1)


def test_records_of_cut_steps_are_put_back_on_the_nominal_grid():
    """Where the solver cuts steps, the records sit at the accepted steps' times: read one
    nominal step apart they would stretch the time scale. on_step_grid interpolates them
    onto the nominal grid (a decaying sine at 20 Hz keeps its frequency) and cut_warning
    says so."""
    from iwan_element.models.simulation.ringdown_records import cut_warning, on_step_grid

    h, n = 1e-3, 1000
    rng = np.random.default_rng(3)
    times = np.sort(np.concatenate([np.arange(n + 1) * h, rng.uniform(0, n * h, 700)]))
    y = np.exp(-2.0 * times) * np.sin(2 * np.pi * 20.0 * times)
    t, (yi,), cut = on_step_grid(times, [y], h, n)
    assert cut == 700 and t.size == n + 1
    np.testing.assert_allclose(yi, np.exp(-2.0 * t) * np.sin(2 * np.pi * 20.0 * t), atol=2e-3)
    assert "700 steps more" in cut_warning(cut, n, 2 * np.pi * 20 * h)[0]
