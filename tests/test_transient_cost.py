"""The cost structure of the transient routes (docs/transient_cost.md): counts, never clocks.

Independent routes: Exudyn's own finite-difference Jacobian of the host against the one the
host hands it; the solver's counters (Jacobians, step cuts, Newton iterations) of ring-downs
at the top of each preset's amplitude range.
"""

from __future__ import annotations

import exudyn as exu
import numpy as np
import pytest
from iwan_element.models.simulation import build_host, solver_settings

from iwan_element import models


def _system_jacobian(specimen, differences: bool) -> np.ndarray:
    """Exudyn's Newton matrix of the host (generalized-alpha, h = 1e-4 s) at a random state,
    with the host's Jacobian function, or with Exudyn's finite differences of the whole
    ObjectGenericODE2 (the function removed)."""
    m = build_host(specimen, assemble=False)
    # without a function Exudyn differences the whole object (about 4 n^3 operations)
    assert m.mbs.GetObject(0)["jacobianUserFunction"] != 0
    if differences:
        m.mbs.SetObjectParameter(0, "jacobianUserFunction", 0)
    m.mbs.Assemble()
    m.set_state(1e-6 * np.random.default_rng(1).standard_normal(m.T.shape[0]))
    sim = solver_settings(force_scale=1.0)
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(m.mbs, sim)
    solver.it.currentStepSize = 1e-4
    solver.ComputeNewtonJacobian(m.mbs, sim)
    J = np.array(solver.GetSystemJacobian())
    solver.FinalizeSolver(m.mbs, sim)
    return J


def test_the_host_hands_exudyn_the_jacobian_its_differences_give():
    # mass, stiffness, the floor's damping and the Iwan elements' tangents: measured 4.7e-9
    # of the largest entry (the differences' round-off)
    s = models.preset("two-bolt-aluminium")
    J, Jd = _system_jacobian(s, False), _system_jacobian(s, True)
    assert np.all(np.isfinite(J)) and J.shape == Jd.shape
    assert np.max(np.abs(J - Jd)) < 1e-7 * np.max(np.abs(Jd))


@pytest.mark.parametrize("name, it_max", [("brake-reuss", 4.5), ("two-bolt-aluminium", 4.0)])
def test_a_ring_down_at_the_top_of_the_range_keeps_its_first_jacobian(name, it_max):
    # Exudyn's route: no step cut, the Jacobian of the release kept for the whole run
    # (modified Newton); measured 3.75 and 3.36 Newton iterations per step. The condensed
    # route: no step cut, no Jacobian, every step accepted on its first check
    p = models.preset(name)
    r = models.ringdown(p, amplitude=p.amplitude_range[1], cycles=8, newton="exudyn")
    m = r.metadata
    assert m["extra_steps"] == 0 and m["jacobians"] <= 2
    assert m["newton_iterations"] / m["steps"] < it_max
    m = models.ringdown(p, amplitude=p.amplitude_range[1], cycles=8).metadata
    assert m["extra_steps"] == 0 and m["jacobians"] == 0
    assert m["newton_iterations"] == m["steps"]


def _trapezoidal_modes(k, c, q, h, n) -> np.ndarray:
    """Modal coordinates of ``q'' + c q' + k q = 0`` (elementwise, from rest at ``q``) over
    ``n`` steps of the trapezoidal rule (Newmark beta = 1/4, gamma = 1/2), one row a step."""
    v, a, out = np.zeros_like(q), -(k * q), [q]
    for _ in range(n):
        qp, vp = q + h * v + 0.25 * h * h * a, v + 0.5 * h * a
        a = -(c * vp + k * qp) / (1 + 0.5 * h * c + 0.25 * h * h * k)
        q, v = qp + 0.25 * h * h * a, vp + 0.5 * h * a
        out.append(q)
    return np.array(out)


def test_the_linear_spring_host_is_the_stuck_modal_recurrence():
    # the independent route any condensation of the host must reproduce: with linear springs
    # KT the host is the stuck system, whose modes (the floor's matrix diagonal in them)
    # each follow the trapezoidal rule on their own; measured 1.7e-8 of the largest
    # displacement over 64 steps (one Newton iteration a step on the exact Jacobian)
    from iwan_element.models.reduced.damping import floor_damping
    from iwan_element.models.reduced.model import stuck_key, stuck_modes
    from iwan_element.models.simulation.transient import release_state

    p = models.preset("two-bolt-aluminium")
    rel = release_state(p, {1: 100e-6})
    L, pts, _, V, _ = stuck_modes(stuck_key(p))
    fl = floor_damping(p)
    h, n = 2 * np.pi / rel["omega0"][0] / 32, 64
    rec: list = []
    m = build_host(
        p,
        tangential="linear",
        post_step=lambda mbs, t: rec.append(mbs.systemData.GetODE2Coordinates().copy()) or True,
    )
    m.set_state(rel["x"])
    sim = solver_settings(force_scale=float(np.max(np.abs(L.K0 @ rel["x"]))))
    sim.linearSolver.solverType = exu.LinearSolverType.EigenDense
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    m.mbs.SolveDynamic(sim)
    X = m.to_free(np.array(rec))
    k = np.einsum("ij,ij->j", V, (L.K0 + L.G.T @ (pts.KT[:, None] * L.G)) @ V)
    q0 = V.T @ (L.M @ rel["x"])
    Xm = _trapezoidal_modes(k, 2 * fl.zeta * fl.omega, q0, h, n) @ V.T
    gap = np.max(np.abs(X - Xm)) / np.max(np.abs(Xm))
    assert X.shape == Xm.shape and gap < 1e-6
    # the comparison sees the floor: without it the records are far off
    X0 = _trapezoidal_modes(k, 0.0 * k, q0, h, n) @ V.T
    assert np.max(np.abs(X - X0)) / np.max(np.abs(Xm)) > 100 * gap
