"""Physics of the Exudyn connector, each claim checked against an independent route.

* energy: kinetic + spring energy (from Exudyn's node velocities) + the joint's work
  (from the connector records) is constant for an energy-conserving integrator;
* steady displacement-driven loops: the area of the recorded (slip, force) loop equals the
  closed-form dissipation of :func:`iwan_element.dissipation`;
* time history: Exudyn's generalized-alpha at spectral radius 1 equals an independent
  numpy Newmark integration (``_connector_models.newmark_reference``);
* history bookkeeping: the recorded forces equal a replay of the recorded (accepted) slips
  through a fresh joint, for every solver, so the history holds accepted states only.
"""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
import pytest
from _connector_models import SOLVERS, Chain, CommitOnTrial, newmark_reference, settings
from exudyn.itemInterface import CoordinateSpringDamper

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters, backbone, dissipation

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)  # phi_max = 2.25 mm


def _reversal_indices(u):
    du = np.diff(u)
    s = np.sign(du[du != 0.0])
    idx = np.flatnonzero(du != 0.0)
    return idx[np.flatnonzero(s[1:] != s[:-1]) + 1]


# ---------------------------------------------------------------------------- energy
def test_energy_balance_free_vibration_from_macroslip_to_deep_microslip():
    p = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.05)
    m, k, v0 = 1.0, 1e5, 3.0
    h, n = 1.5e-5, 22000  # ~190 steps per period, 0.33 s
    chain = Chain([m], v0=[v0])
    chain.spring(-1, 0, k)
    times, kinetic = [], []

    def user_post_step(mbs, t):  # set before the connector: must be chained
        times.append(t)
        kinetic.append(0.5 * m * chain.velocity(0) ** 2)
        return True

    chain.mbs.SetPostStepUserFunction(user_post_step)
    conn = chain.joint(-1, 0, IwanJoint(p))
    chain.solve(settings(h, n, rho=1.0))

    rec = conn.records()
    assert np.array_equal(np.array(times), rec["time"])
    u = rec["slip"]
    energy = np.array(kinetic) + 0.5 * k * u**2 + rec["stored_energy"] + rec["dissipated_energy"]
    e0 = 0.5 * m * v0**2
    rev = _reversal_indices(u)
    half_amplitudes = np.abs(np.diff(u[rev])) / 2.0
    assert len(rev) >= 100  # at least 50 cycles
    assert np.max(np.abs(u[: rev[0] + 1])) > 1.5 * p.phi_max  # first excursion in macroslip
    assert half_amplitudes[-1] < 0.01 * p.phi_max  # ends deep in microslip
    assert rec["dissipated_energy"][-1] > 0.9 * e0
    assert np.max(np.abs(energy - e0)) / e0 < 1e-4
    # the work column is stored + dissipated, and the force column is the joint force
    assert np.allclose(
        rec["work"], rec["stored_energy"] + rec["dissipated_energy"], rtol=0, atol=1e-12
    )


@pytest.mark.parametrize("law", ["symbolic", "python"])
def test_dashpot_in_parallel_equals_exudyns_damper_and_is_booked(law):
    """``damping=c`` on the connector moves the mass as Exudyn's own damper in parallel
    (an independent force), its force is ``c v`` on top of the joint's, its dissipation is
    ``int c v du`` from Exudyn's node velocities, and the energy balance closes with it."""
    m, k, c, v0 = 1.0, 1e5, 30.0, 3.0
    h, n = 2e-5, 6000
    runs = {}
    for own in (True, False):
        chain = Chain([m], v0=[v0])
        chain.spring(-1, 0, k)
        if not own:
            chain.mbs.AddObject(
                CoordinateSpringDamper(
                    markerNumbers=[chain.marker(-1), chain.marker(0)], stiffness=0.0, damping=c
                )
            )
        vel = []
        chain.mbs.SetPostStepUserFunction(
            lambda mbs, t, vel=vel, chain=chain: vel.append(chain.velocity(0)) or True
        )
        conn = chain.joint(-1, 0, IwanJoint(P), law=law, damping=c if own else 0.0)
        assert conn.route == law and conn.damping == (c if own else 0.0)
        chain.solve(settings(h, n))
        runs[own] = (conn.records(), np.array(vel).ravel())
    (mine, v), (theirs, v_ref) = runs[True], runs[False]
    u = mine["slip"]
    assert np.max(np.abs(u)) > P.phi_max
    assert np.max(np.abs(u - theirs["slip"])) < 1e-10 * np.max(np.abs(u))
    assert np.allclose(mine["force"] - theirs["force"], c * v_ref, rtol=0, atol=1e-9 * P.Fs)
    dash = np.concatenate([[0.0], np.cumsum(c * 0.5 * (v_ref[1:] + v_ref[:-1]) * np.diff(u))])
    assert np.allclose(
        mine["dissipated_energy"] - theirs["dissipated_energy"], dash, rtol=1e-9, atol=1e-12
    )
    assert np.allclose(
        mine["work"] - mine["dissipated_energy"], theirs["stored_energy"], rtol=0, atol=1e-12
    )
    e0 = 0.5 * m * v0**2
    total = 0.5 * m * v**2 + 0.5 * k * u**2 + mine["work"]
    assert dash[-1] > 0.1 * e0 and np.max(np.abs(total - e0)) / e0 < 1e-4


# ---------------------------------------------------------------------------- loops
@pytest.mark.parametrize("ratio", [0.3, 2.0], ids=["microslip", "macroslip"])
def test_displacement_driven_loop_area_equals_dissipation(ratio):
    u0 = ratio * P.phi_max
    n_cycle = 2000  # divisible by 4: the samples hit +-u0 exactly
    omega = 2.0 * math.pi * 5.0
    h = 2.0 * math.pi / omega / n_cycle
    chain = Chain([1.0])
    chain.prescribe(0, lambda t: u0 * math.sin(omega * t))
    conn = chain.joint(-1, 0, IwanJoint(P))
    chain.solve(settings(h, n_cycle + n_cycle // 4))

    u, F, W = conn.slip_history, conn.force_history, conn.work_history
    assert u[n_cycle // 4] == pytest.approx(u0, rel=1e-12)
    i0, i1 = n_cycle // 4, n_cycle // 4 + n_cycle  # one full cycle, peak to peak
    du = np.diff(u[i0 : i1 + 1])
    area = float(np.sum(0.5 * (F[i0:i1] + F[i0 + 1 : i1 + 1]) * du))  # trapezoid on the samples
    expected = dissipation(u0, P)
    assert area == pytest.approx(expected, rel=1e-4)
    assert W[i1] - W[i0] == pytest.approx(expected, rel=1e-9)  # the element's exact integral
    assert F[i0] == pytest.approx(backbone(u0, P), rel=1e-12)  # virgin loading to the peak


# ---------------------------------------------------------------------------- reference
def _forced_one_mass(element, *, h, n, solver=SOLVERS.GeneralizedAlpha, rho=1.0):
    m, k, f0, om = 1.0, 2e5, 1500.0, 700.0
    chain = Chain([m])
    chain.spring(-1, 0, k)
    chain.harmonic_force(0, f0, om)
    conn = chain.joint(-1, 0, element)
    chain.solve(settings(h, n, rho=rho), solver)
    ref_el = element.element if isinstance(element, CommitOnTrial) else element
    ref_el = IwanJoint(P) if isinstance(ref_el, IwanJoint) else DiscreteIwan(P, ref_el.n_sliders)
    t, x, v = newmark_reference(
        [m],
        [(-1, 0, ref_el)],
        springs=[(-1, 0, k)],
        h=h,
        n_steps=n,
        force=lambda tt: np.array([f0 * math.sin(om * tt)]),
    )
    return conn, chain, t, x[:, 0], v[:, 0]


def _max_rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize(
    "make, solver",
    [
        (lambda: IwanJoint(P), SOLVERS.GeneralizedAlpha),
        (lambda: IwanJoint(P), SOLVERS.TrapezoidalIndex2),
        (lambda: DiscreteIwan(P, 30), SOLVERS.GeneralizedAlpha),
    ],
    ids=["IwanJoint-GA", "IwanJoint-trapezoidal", "DiscreteIwan-GA"],
)
def test_matches_independent_newmark_integration(make, solver):
    conn, chain, t, x, v = _forced_one_mass(make(), h=5e-5, n=2000, solver=solver)
    assert np.max(np.abs(x)) > 1.5 * P.phi_max  # the run reaches macroslip
    assert np.allclose(conn.time_history, t, rtol=0, atol=1e-12)
    assert _max_rel(conn.slip_history, x) < 1e-8
    assert abs(chain.velocity(0) - v[-1]) / np.max(np.abs(v)) < 1e-8


# ---------------------------------------------------------------------------- the classic bug
def _check_large_steps(element):
    """Generalized-alpha with ~11 steps per period: must equal the reference."""
    conn, _, _, x, _ = _forced_one_mass(element, h=5e-4, n=100)
    assert _max_rel(conn.slip_history, x) < 1e-8


def _check_adaptive_rejections(element):
    """DOPRI5 with step-size control: attempts are rejected, and the committed history must
    still be the sequence of accepted states (replay of the recorded slips)."""
    chain = Chain([1.0])
    chain.spring(-1, 0, 2e5)
    chain.harmonic_force(0, 1500.0, 700.0)
    attempts = [0]

    def user_pre_step(mbs, t):
        attempts[0] += 1
        return True

    chain.mbs.SetPreStepUserFunction(user_pre_step)
    conn = chain.joint(-1, 0, element, allow_adaptive_explicit=True)
    chain.solve(settings(1e-4, 500, adaptive=True, tol=1e-6), SOLVERS.DOPRI5)
    accepted = conn.n_records - 1
    assert attempts[0] > accepted  # some attempts were rejected
    replay = IwanJoint(P)
    forces = replay.force_history(conn.slip_history)
    assert np.max(np.abs(forces - conn.force_history)) / P.Fs < 1e-12
    j = IwanJoint(P)
    for ui in conn.slip_history:
        j.trial(ui)
        j.commit()
    assert j.dissipated_energy == pytest.approx(conn.dissipated_energy_history[-1], rel=1e-12)


def test_large_steps_correct():
    _check_large_steps(IwanJoint(P))


def test_adaptive_rejections_correct():
    _check_adaptive_rejections(IwanJoint(P))


@pytest.mark.parametrize(
    "check",
    [_check_large_steps, _check_adaptive_rejections],
    ids=["large-steps", "adaptive-rejections"],
)
def test_commit_inside_force_call_is_detected(check):
    with pytest.raises(AssertionError):
        check(CommitOnTrial(IwanJoint(P)))


# ---------------------------------------------------------------------------- all solvers
@pytest.mark.parametrize(
    "solver, kw, end_of_step_acc",
    [
        (SOLVERS.GeneralizedAlpha, dict(rho=0.6), True),
        (SOLVERS.TrapezoidalIndex2, {}, True),
        (SOLVERS.RK44, {}, True),
        (SOLVERS.RK44, {}, False),
        (SOLVERS.ExplicitEuler, {}, True),
        (SOLVERS.ExplicitEuler, {}, False),
        (SOLVERS.ODE23, dict(adaptive=True, tol=1e-5), True),
        (SOLVERS.DOPRI5, dict(adaptive=True, tol=1e-7), True),
    ],
    ids=[
        "GA-0.6",
        "trapezoidal",
        "RK44",
        "RK44-no-end-acc",
        "explicit-Euler",
        "explicit-Euler-no-end-acc",
        "ODE23",
        "DOPRI5",
    ],
)
def test_history_holds_accepted_states_for_every_solver(solver, kw, end_of_step_acc):
    # Without end-of-step accelerations the explicit solvers' last force evaluation of a step
    # is a stage, not the accepted state: the connector must not commit that last trial.
    h = 2e-5 if solver == SOLVERS.ExplicitEuler else 1e-4
    n = int(round(0.04 / h))
    chain = Chain([1.0], v0=[3.0])
    chain.spring(-1, 0, 2e5)
    accepted = []  # Exudyn's accepted states, read independently
    attempts = [0]

    def user_post_step(mbs, t):
        accepted.append(mbs.GetNodeOutput(chain.nodes[0], exu.OutputVariableType.Coordinates))
        return True

    def guard_pre_step(mbs, t):  # adaptive explicit solvers can stall at a kink
        attempts[0] += 1
        if attempts[0] > 50 * n:
            raise RuntimeError("step-size control stalled")
        return True

    chain.mbs.SetPostStepUserFunction(user_post_step)
    chain.mbs.SetPreStepUserFunction(guard_pre_step)
    conn = chain.joint(-1, 0, IwanJoint(P), allow_adaptive_explicit=True)
    sim = settings(h, n, **kw)
    sim.timeIntegration.explicit.computeEndOfStepAccelerations = end_of_step_acc
    chain.solve(sim, solver)
    u = conn.slip_history
    assert np.array_equal(u, np.array(accepted))  # committed exactly at accepted states
    assert np.max(np.abs(u)) > P.phi_max and len(_reversal_indices(u)) >= 8
    assert np.max(np.abs(IwanJoint(P).force_history(u) - conn.force_history)) / P.Fs < 1e-12
    assert conn.time_history[0] == 0.0 and conn.time_history[-1] == pytest.approx(0.04, rel=1e-9)
    assert np.all(np.diff(conn.time_history) > 0)


class _RateRecorder:
    """A linear spring-dashpot element that remembers the (u, v) of every commit."""

    def __init__(self, k, c):
        self.k, self.c = k, c
        self.committed = []
        self.work = self.stored_energy = self.dissipated_energy = 0.0
        self.displacement = self.force = 0.0
        self._t = (0.0, 0.0)

    def trial(self, u, v=0.0):
        self._t = (u, v)
        return self.k * u + self.c * v, self.k

    def commit(self):
        self.committed.append(self._t)
        self.displacement = self._t[0]

    def revert(self):
        pass

    def reset(self):
        self.committed.clear()


@pytest.mark.parametrize(
    "solver, end_of_step_acc",
    [
        (SOLVERS.GeneralizedAlpha, True),
        (SOLVERS.RK44, True),
        (SOLVERS.RK44, False),
        (SOLVERS.ExplicitEuler, False),
        (SOLVERS.DOPRI5, True),
    ],
    ids=["GA", "RK44", "RK44-no-end-acc", "explicit-Euler-no-end-acc", "DOPRI5"],
)
def test_rate_dependent_element_commits_the_accepted_velocity(solver, end_of_step_acc):
    """Between two masses: the element commits (u, v) of the accepted state, velocity
    included, also when the solver's last force evaluation of a step was a stage."""
    h, n = 1e-4, 300
    chain = Chain([1.0, 2.0], v0=[3.0, -1.0])
    chain.spring(-1, 0, 2e5)
    accepted = []

    def user_post_step(mbs, t):
        x = [mbs.GetNodeOutput(nd, exu.OutputVariableType.Coordinates) for nd in chain.nodes]
        v = [mbs.GetNodeOutput(nd, exu.OutputVariableType.Coordinates_t) for nd in chain.nodes]
        accepted.append((x[1] - x[0], v[1] - v[0]))
        return True

    chain.mbs.SetPostStepUserFunction(user_post_step)
    element = _RateRecorder(1e5, 30.0)
    chain.joint(0, 1, element, allow_adaptive_explicit=True)
    sim = settings(h, n)
    sim.timeIntegration.explicit.computeEndOfStepAccelerations = end_of_step_acc
    chain.solve(sim, solver)
    assert len(element.committed) >= n + 1
    assert element.committed == accepted
    assert len({v for _, v in accepted}) > n // 2  # the velocity really varies


# ---------------------------------------------------------------------------- several joints
def test_two_connectors_with_different_parameters_and_user_functions():
    pa = P
    pb = IwanParameters(Fs=300.0, KT=4e5, chi=-0.3, beta=0.5)
    masses, k1, f0, om = [1.0, 0.5], 1e5, 900.0, 600.0
    h, n = 5e-5, 1600
    chain = Chain(masses)
    chain.spring(-1, 0, k1)
    chain.harmonic_force(1, f0, om)
    calls = {"pre": 0, "post": 0}
    conns = []

    def user_pre_step(mbs, t):
        calls["pre"] += 1
        return True

    def user_post_step(mbs, t):
        calls["post"] += 1
        for c in conns:  # the connectors have committed already
            assert c.time_history[-1] == t
        return True

    chain.mbs.SetPreStepUserFunction(user_pre_step)
    chain.mbs.SetPostStepUserFunction(user_post_step)
    conns.append(chain.joint(-1, 0, IwanJoint(pa)))
    conns.append(chain.joint(0, 1, IwanJoint(pb)))
    chain.solve(settings(h, n))

    t, x, _ = newmark_reference(
        masses,
        [(-1, 0, IwanJoint(pa)), (0, 1, IwanJoint(pb))],
        springs=[(-1, 0, k1)],
        h=h,
        n_steps=n,
        force=lambda tt: np.array([0.0, f0 * math.sin(om * tt)]),
    )
    assert calls == {"pre": n, "post": n + 1}
    assert _max_rel(conns[0].slip_history, x[:, 0]) < 1e-8
    assert _max_rel(conns[1].slip_history, x[:, 1] - x[:, 0]) < 1e-8
    assert np.max(np.abs(x[:, 1] - x[:, 0])) > pb.phi_max  # joint B also reaches macroslip
    assert conns[0].dissipated_energy_history[-1] > 0 and conns[1].dissipated_energy_history[-1] > 0


def test_static_solver_commits_load_steps():
    k, F = 2e5, 900.0
    chain = Chain([1.0])
    chain.spring(-1, 0, k)
    from exudyn.itemInterface import LoadCoordinate

    chain.mbs.AddLoad(LoadCoordinate(markerNumber=chain.marker(0), load=F))
    conn = chain.joint(-1, 0, IwanJoint(P))
    chain.mbs.Assemble()
    sim = settings(1e-3, 10)
    sim.staticSolver.numberOfLoadSteps = 5
    sim.staticSolver.newton.relativeTolerance = 1e-12
    sim.staticSolver.verboseMode = 0
    chain.mbs.SolveStatic(sim)
    u = conn.slip_history[-1]
    assert conn.n_records == 6
    assert backbone(u, P) + k * u == pytest.approx(F, rel=1e-9)
    assert conn.force_history[-1] == pytest.approx(backbone(u, P), rel=1e-12)
    assert np.all(np.diff(conn.slip_history) > 0)  # monotone quasi-static loading
