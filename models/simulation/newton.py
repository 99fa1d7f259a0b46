"""A time step of the host solved on the joints' slips: Newton's method condensed onto them.

The host (:mod:`~iwan_element.models.simulation.host`) is linear but for the Iwan elements,
each on its own slip coordinate ``s_i = z_i``. Exudyn's implicit step (generalized-alpha, the
trapezoidal rule at spectral radius 1) updates ``z -= dx``, ``v -= gamma' dx``,
``a -= beta' dx`` and drives the residual ``r(z) = M' a + C' v + K' z + E F(E^T z) - f(t)``
to zero (``E``: the slip columns, ``F``: the joints' forces). Everything but ``F`` is linear,
so with ``A0 = beta' M' + gamma' C' + K' + E diag(KT) E^T`` (the stuck iteration matrix,
factored once per step size) and ``F~(s) = F(s) - KT s``, the step from Exudyn's predictor
``z_p`` (residual ``r_p``, slips ``s_p``) is exactly

    delta = delta_free - W F~(s),   delta_free = -A0^-1 (r_p - E F~(s_p)),   W = A0^-1 E,

with the slips ``s`` the root of ``s - s_free + S F~(s) = 0``, ``s_free = s_p + E^T delta_free``,
``S = E^T W``: an ``m``-dimensional equation solved by Newton's method with the joints'
consistent tangents (:func:`~iwan_element.exudyn.laws.condensed.condensed_slips`). A
step then costs Exudyn's residual twice (at the predictor, and once to check the result
against Exudyn's own residual and tolerances), one back-substitution of ``A0`` and a few
``m x m`` solves: what a step of the same host with linear springs costs, plus the ``m x m``
work. Exudyn's modified Newton instead iterates on the whole model with a Jacobian that the
joints' tangents leave stale: 6.25 iterations a step on the Brake-Reuss two-mode release
(docs/transient_cost.md).

A step whose check fails (an object the condensation does not see, a symbolic law that
read an older reversal point than it holds) goes on with full Newton iterations on Exudyn's
residual, each solved with ``A0`` and a Woodbury update for the joints' tangents (an
``m x m`` solve), until Exudyn's tolerances are met. Every residual after the first counts
as one Newton iteration in Exudyn's counters (``it.newtonStepsCount``); the condensed
iterations are :attr:`HostNewton.condensed_iterations`.
"""

from __future__ import annotations

import logging

import exudyn as exu
import numpy as np
import scipy.linalg as sla
from scipy.linalg.lapack import dgetrs

from iwan_element.exudyn.laws.condensed import condensed_slips

__all__ = ["HostNewton", "NEWTON_ROUTES", "check_newton", "choose_newton", "solve_dynamic"]

#: The ``newton`` options of the transient runs (:func:`choose_newton`).
NEWTON_ROUTES = ("auto", "condensed", "exudyn")

_log = logging.getLogger(__name__)
_CUR = exu.ConfigurationType.Current


class HostNewton:
    """Exudyn's Newton step replaced by the condensed one (module docstring).

    Parameters
    ----------
    model : HostModel
        An assembled host whose interface is on the symbolic route
        (:func:`~iwan_element.models.simulation.host.build_host`, ``tangential="iwan"``, no
        interface effects) and whose only other objects are linear (loads are fine).
    sim : exudyn.SimulationSettings
        The run's settings (its Newton tolerances and iteration limit are used).
    """

    def __init__(self, model, sim):
        bank = model.interface.bank if model.interface is not None else None
        if bank is None:
            raise ValueError(
                "HostNewton needs the host's Iwan interface on the symbolic route "
                "(tangential='iwan' without interface effects)"
            )
        self.bank = bank
        n, m = model.T.shape[1], bank.n_points
        self.slips = np.arange(model.n_eta, model.n_eta + m)
        self.KT = bank.KT
        self.M = model.Mz
        self.C = model.floor_C if model.floor_C is not None else np.zeros((n, n))
        self.K = model.Kb + model.Ks  # the joints are not in Ks on the Iwan route
        self.sd = model.mbs.systemData
        newton = sim.timeIntegration.newton
        self.abs_tol = float(newton.absoluteTolerance)
        self.rel_tol = float(newton.relativeTolerance)
        self.max_iter = int(newton.maxIterations)
        self._h = None
        self.condensed_iterations = 0
        self.full_iterations = 0  #: iterations of the fallback on Exudyn's residual
        self.steps = 0

    def _factor(self, solver, h: float) -> None:
        """``A0`` factored, ``W`` and ``S`` for the step ``h`` (module docstring)."""
        bp = (1.0 - solver.alphaM) / (h * h * solver.newmarkBeta * (1.0 - solver.alphaF))
        gp = solver.newmarkGamma / (h * solver.newmarkBeta)
        A0 = bp * self.M + gp * self.C + self.K
        A0[self.slips, self.slips] += self.KT
        self.lu = sla.lu_factor(A0)
        E = np.zeros((A0.shape[0], self.slips.size))
        E[self.slips, np.arange(self.slips.size)] = 1.0
        self.W = sla.lu_solve(self.lu, E)
        self.S = np.ascontiguousarray(self.W[self.slips])
        self.bp, self.gp, self.scale, self._h = bp, gp, solver.newmarkBeta * h * h, h

    def _solve(self, r) -> np.ndarray:
        """``A0^-1 r`` from the factors (LAPACK's ``getrs`` directly: scipy's ``lu_solve``
        wrapper cost as much as the back-substitution of this size).
        """
        x, info = dgetrs(self.lu[0], self.lu[1], r)
        if info:
            raise ValueError(f"getrs failed with info={info}")
        return x

    def _move(self, z, v, a, delta) -> None:
        """The state moved by ``delta`` (``z += delta``; ``v``, ``a`` with it), written."""
        z += delta
        v += self.gp * delta
        a += self.bp * delta
        sd = self.sd
        sd.SetODE2Coordinates(z, configuration=_CUR)
        sd.SetODE2Coordinates_t(v, configuration=_CUR)
        sd.SetODE2Coordinates_tt(a, configuration=_CUR)

    def __call__(self, solver, mbs, sim) -> bool:
        """One step's Newton method (Exudyn's ``SetUserFunctionNewton``); True if converged."""
        h = solver.it.currentStepSize
        if h != self._h:
            self._factor(solver, h)
        solver.ComputeNewtonUpdate(mbs, sim, True)  # Exudyn's predictor, accelerations 0
        sd, sl, KT = self.sd, self.slips, self.KT
        z = np.array(sd.GetODE2Coordinates(configuration=_CUR))
        v = np.array(sd.GetODE2Coordinates_t(configuration=_CUR))
        a = np.zeros_like(z)
        r0 = solver.ComputeNewtonResidual(mbs, sim)
        r = np.asarray(solver.GetSystemResidual()) / self.scale
        sp = z[sl]
        Fp, _ = self.bank.trial(sp)
        r[sl] -= Fp - KT * sp
        d_free = -self._solve(r)
        s, F, k, _ = condensed_slips(
            self.bank, sp + d_free[sl], self.S, ftol=1e-3 * self.abs_tol, max_iter=self.max_iter
        )
        self.condensed_iterations += k
        self.steps += 1
        self._move(z, v, a, d_free - self.W @ (F - KT * s))
        init = max(r0, 2.0 * self.abs_tol)
        res = solver.ComputeNewtonResidual(mbs, sim)
        solver.it.newtonStepsCount += 1
        for _ in range(self.max_iter):
            if res <= self.abs_tol or res / init <= self.rel_tol:
                return True
            res = self._full_iteration(solver, mbs, sim, z, v, a)
        _log.warning(
            "the condensed Newton step at t=%g did not meet the tolerance (residual %.3g, "
            "absolute tolerance %.3g)",
            solver.it.currentTime,
            res,
            self.abs_tol,
        )
        return False

    def _full_iteration(self, solver, mbs, sim, z, v, a) -> float:
        """One Newton iteration on Exudyn's residual: ``A0`` with a Woodbury update for the
        joints' consistent tangents; returns the new residual norm.
        """
        sl = self.slips
        y = self._solve(np.asarray(solver.GetSystemResidual()) / self.scale)
        _, K = self.bank.trial(z[sl])
        d = K - self.KT
        act = np.flatnonzero(d)
        if act.size:
            Sa = self.S[np.ix_(act, act)] * d[act][:, None]
            Sa[np.diag_indices(act.size)] += 1.0
            y -= self.W[:, act] @ np.linalg.solve(Sa, d[act] * y[sl[act]])
        self._move(z, v, a, -y)
        self.full_iterations += 1
        solver.it.newtonStepsCount += 1
        return solver.ComputeNewtonResidual(mbs, sim)


def check_newton(newton) -> str:
    """``newton`` if it is one of :data:`NEWTON_ROUTES`, else a ValueError naming it (the
    runs check it before any work, :func:`choose_newton` when it builds the step).
    """
    if newton not in NEWTON_ROUTES:
        raise ValueError(f"newton must be one of {NEWTON_ROUTES}, got {newton!r}")
    return newton


def choose_newton(model, sim, newton: str, *, other_forces: bool = False) -> HostNewton | None:
    """The Newton step of a run on ``model``: a :class:`HostNewton`, or None for Exudyn's.

    ``newton``: ``"exudyn"`` (Exudyn's modified Newton on the whole model), ``"condensed"``
    (the joints' slips; ValueError where it cannot serve: no compiled interface, or
    ``other_forces``, state-dependent forces the condensation does not see, such as modal
    effects), or ``"auto"``: condensed where it can serve and where a condensed iteration's
    ``m x m`` factorisation (about ``m^3 / 3`` operations on ``m`` slips) costs less than one
    residual of the ``n``-coordinate model (about ``n^2``). Measured
    (docs/transient_cost.md): on the 1-D beams (``m = 30``, ``n = 253-276``) a step costs
    1.3-2.0 times linear springs condensed against 1.1-3.5 times on Exudyn's route; the
    coarse solid (``m = 60``, ``n = 104``) took 0.33 ms a step condensed against 0.26 ms.
    """
    if check_newton(newton) == "exudyn":
        return None
    bank = model.interface.bank if model.interface is not None else None
    why = (
        "the interface is not the compiled law (linear springs, or interface effects)"
        if bank is None
        else "the run has other state-dependent forces (modal effects)"
        if other_forces
        else None
    )
    if why is not None:
        if newton == "condensed":
            raise ValueError(f"newton='condensed' cannot serve this run: {why}")
        return None
    assert bank is not None  # a missing bank returned above
    n, m = model.T.shape[1], bank.n_points
    if newton == "auto" and m**3 / 3.0 >= n**2:
        return None
    return HostNewton(model, sim)


def solve_dynamic(mbs, sim, *, newton=None, update_initial_values: bool = False) -> None:
    """``mbs.SolveDynamic(sim)``, with the Newton step ``newton`` (a :class:`HostNewton`, or
    None for Exudyn's own) in Exudyn's implicit solver.

    The solver and the settings are stored in ``mbs.sys`` as ``SolveDynamic`` stores them
    (the Iwan interfaces read them before the first step); ``update_initial_values`` writes
    the final state to the initial one, as ``SolveDynamic(updateInitialValues=True)``.
    Raises ``exudyn.SolverError`` if the solve fails.
    """
    if newton is None:
        mbs.SolveDynamic(sim, updateInitialValues=update_initial_values)
        return
    solver = exu.MainSolverImplicitSecondOrder()
    mbs.sys["dynamicSolver"] = solver
    mbs.sys["simulationSettings"] = sim
    solver.SetUserFunctionNewton(mbs, newton)
    if not solver.SolveSystem(mbs, sim):
        raise exu.SolverError(
            f"the condensed Newton step did not converge at t={solver.it.currentTime:g}: "
            + solver.GetErrorString()
        )
    if update_initial_values:
        sd = mbs.systemData
        sd.SetSystemState(
            systemStateList=sd.GetSystemState(), configuration=exu.ConfigurationType.Initial
        )
        sd.SetODE2Coordinates_tt(
            coordinates=sd.GetODE2Coordinates_tt(), configuration=exu.ConfigurationType.Initial
        )
