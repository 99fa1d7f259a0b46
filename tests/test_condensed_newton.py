"""The time step condensed onto the joints' slips (models/simulation/newton.py).

Independent routes: the bank's trial forces against separate ``IwanJoint`` elements driven
to the same slips, its tangents against finite differences of those forces; the condensed
equations against scipy's root finder on the same equations; the condensed host against
Exudyn's own modified Newton on the same model (records, energy balance, stepped sine), and
its fallback against a deliberately wrong condensation.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize as so
from iwan_element.models.simulation import newton as host_newton

from iwan_element import IwanJoint, IwanJointBank, IwanParameters, models
from iwan_element.exudyn.laws.condensed import condensed_slips

P = [
    IwanParameters(Fs=10.0, KT=1e6, chi=-0.5, beta=0.5),
    IwanParameters(Fs=4.0, KT=3e5, chi=-0.3, beta=1.2),
    IwanParameters(Fs=7.0, KT=8e5, chi=-0.7, beta=0.2),
]


def _history(rng, n=60):
    """Slips of three points: decaying oscillations with nested small loops (loop closures,
    reversals, macroslip of the weakest point)."""
    t = np.linspace(0.0, 6.0, n)
    big = 2.5e-5 * np.exp(-0.2 * t) * np.sin(2.0 * t)
    small = 4e-6 * np.sin(13.0 * t)
    return np.column_stack([big + small, 0.7 * big - small, 1.3 * big + 0.5 * small])


def test_bank_trials_are_the_joints_trials_and_change_nothing():
    rng = np.random.default_rng(0)
    U = _history(rng)
    bank = IwanJointBank(P)
    joints = [IwanJoint(p) for p in P]
    for u in U:
        for du in (3e-7, -2e-6, 1.1e-5):  # continue, reverse, close loops
            trial = u + du * rng.uniform(-1.0, 1.0, 3)
            F, K = bank.trial(trial)
            ref = np.array([j.trial(x) for j, x in zip(joints, trial)])
            assert np.allclose(F, ref[:, 0], rtol=1e-12, atol=1e-12 * 10.0)
            assert np.allclose(K, ref[:, 1], rtol=1e-12, atol=1e-6)
            # the tangent is the derivative of the trial force (central differences)
            e = 1e-11
            Fp, _ = bank.trial(trial + e)
            Fm, _ = bank.trial(trial - e)
            fd = (Fp - Fm) / (2 * e)
            assert np.allclose(K, fd, rtol=1e-4, atol=1e-4 * 1e6)
        bank.commit(u)
        for j, x in zip(joints, u):
            j.trial(x)
            j.commit()
        assert np.allclose(bank.force, [j.force for j in joints], rtol=1e-12, atol=1e-11)


def test_the_bank_trial_rejects_a_wrong_shape():
    with pytest.raises(ValueError, match="u must have shape"):
        IwanJointBank(P).trial(np.zeros(2))


def test_condensed_slips_solve_the_condensed_equations():
    # against scipy's root finder on g(s) = s - s_free + S (F(s) - KT s), from a bank with
    # a history; a flexibility from a random symmetric positive definite stiffness
    rng = np.random.default_rng(3)
    bank = IwanJointBank(P)
    for u in _history(rng, 25):
        bank.commit(u)
    A = rng.standard_normal((3, 3))
    Kstr = A @ A.T * 1e5 + np.diag(bank.KT) + 2e5 * np.eye(3)
    S = np.linalg.inv(Kstr)
    for scale in (1e-6, 1e-5, 4e-5):  # stuck, partial slip, macroslip of a point
        s_free = bank.u + scale * rng.standard_normal(3)
        s, F, it, ok = condensed_slips(bank, s_free, S, ftol=1e-10)
        assert ok and it <= 12

        def g(x, s_free=s_free):
            return x - s_free + S @ (bank.trial(x)[0] - bank.KT * x)

        ref = so.fsolve(g, s_free, xtol=1e-12)
        assert np.max(np.abs(g(s))) < 1e-15 + 1e-10 * np.max(np.abs(s_free))
        assert np.allclose(s, ref, rtol=1e-8, atol=1e-14)
        assert np.allclose(F, bank.trial(s)[0], rtol=0, atol=0)


def _ringdown(newton, **kw):
    p = models.preset("brake-reuss")
    return models.ringdown(
        p,
        amplitude={1: 60e-6, 2: 15e-6},
        cycles=8,
        steps_per_period=32,
        record_energy=True,
        newton=newton,
        **kw,
    )


@pytest.fixture(scope="module")
def exudyn_route():
    return _ringdown("exudyn")


def test_the_condensed_step_is_exudyns_step(exudyn_route):
    # the two-mode release (loop closures at every step): the same records within the Newton
    # tolerance, each step accepted on its first check (one counted iteration a step, no
    # Jacobian), a few condensed iterations a step; measured 3.4 a step
    a, b = _ringdown("condensed"), exudyn_route
    gap = np.max(np.abs(a.sensor_displacement - b.sensor_displacement))
    assert gap < 1e-7 * np.max(np.abs(b.sensor_displacement))
    m = a.metadata
    assert m["newton_iterations"] == m["steps"] and m["jacobians"] == 0
    assert m["extra_steps"] == 0
    assert 1.0 <= m["condensed_iterations"] / m["steps"] < 6.0
    assert b.metadata["condensed_iterations"] == 0
    for c, d in zip(a.curves, b.curves):
        assert np.allclose(c.frequency, d.frequency, rtol=1e-7)
        assert np.allclose(c.damping_ratio, d.damping_ratio, rtol=1e-4)
    ea, eb = np.max(np.abs(a.energy_error())), np.max(np.abs(b.energy_error()))
    assert abs(ea - eb) < 1e-6 and ea < 1e-3


def test_a_step_the_condensation_misses_is_finished_on_exudyns_residual(exudyn_route, monkeypatch):
    # the condensation built on a stiffness 0.1 % off (as an object it cannot see would
    # leave it): every step's check fails and the full iterations on Exudyn's residual
    # (the condensed matrix with the joints' tangents) finish it; same records
    made = []
    original = host_newton.HostNewton.__init__

    def off(self, model, sim):
        original(self, model, sim)
        self.K = self.K * 1.001
        made.append(self)

    monkeypatch.setattr(host_newton.HostNewton, "__init__", off)
    a = _ringdown("condensed")
    b = exudyn_route
    assert made and made[0].full_iterations >= made[0].steps
    gap = np.max(np.abs(a.sensor_displacement - b.sensor_displacement))
    assert gap < 1e-7 * np.max(np.abs(b.sensor_displacement))


def test_the_route_is_chosen_where_it_serves_and_pays():
    from iwan_element.models.simulation import build_host, solver_settings

    sim = solver_settings(force_scale=1.0)
    lin = build_host(models.preset("two-bolt-aluminium"), tangential="linear")
    with pytest.raises(ValueError, match="symbolic route"):
        host_newton.HostNewton(lin, sim)
    with pytest.raises(ValueError, match="cannot serve this run: the interface"):
        host_newton.choose_newton(lin, sim, "condensed")
    assert host_newton.choose_newton(lin, sim, "auto") is None
    beam = build_host(models.preset("two-bolt-aluminium"))
    assert isinstance(host_newton.choose_newton(beam, sim, "auto"), host_newton.HostNewton)
    assert host_newton.choose_newton(beam, sim, "exudyn") is None
    with pytest.raises(ValueError, match="modal effects"):
        host_newton.choose_newton(beam, sim, "condensed", other_forces=True)
    with pytest.raises(ValueError, match="newton must be one of"):
        models.ringdown(models.preset("two-bolt-aluminium"), amplitude=2e-5, newton="full")


def test_the_stepped_sine_condensed_is_exudyns():
    from iwan_element.models.reduced import reduced_model

    s = models.preset("brake-reuss").replace(damping_floor=0.02, modal_damping=())
    f = np.array([0.99, 1.0, 1.01]) * reduced_model(s).frequency(1)
    kw = dict(
        force_levels=(0.5,),
        frequencies=f,
        settle_cycles=6,
        measure_cycles=4,
        steps_per_period=32,
    )
    a = models.forced_response(s, newton="condensed", **kw)
    b = models.forced_response(s, newton="exudyn", **kw)
    assert np.allclose(a.amplitude, b.amplitude, rtol=1e-7)
    assert np.allclose(a.phase, b.phase, atol=1e-7)
    assert np.all(a.metadata["jacobians"] == 0)
