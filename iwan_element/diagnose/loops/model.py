"""The loop model every diagnosis step fits: an effect stack on the Iwan joint with the
force offset and ``Fs`` eliminated in closed form, its fit and its uncertainty.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares, minimize_scalar

from ...core.history import unit_params
from ...core.parameters import IwanParameters
from ...effects import EFFECTS
from ...effects.engine.evaluate import Evaluator, scale_effect
from ...fitting import covariance
from ...identify.loops.joint_verdict import joint_table
from ...identify.loops.noise import integrated_time
from ...identify.loops.result import FitResult

__all__ = ["LoopModel", "PARAM_NAMES", "CHI_BOUNDS", "BETA_MAX", "PHI_RANGE", "START_GRID", "jumps"]

PARAM_NAMES = ("Fs", "KT", "chi", "beta")
CHI_BOUNDS = (-0.98, 1.0)
BETA_MAX = 100.0
PHI_RANGE = (1e-3, 1e4)  # phi_max / x_max
#: Relative stopping tolerance of every fit (``ftol`` and ``xtol`` of ``least_squares``). The
#: selection rule resolves misfit differences of the order of one information-criterion
#: penalty, at least ``ln(n_eff)`` (about 5) units of chi2, where a record's chi2 is 1e3-1e6:
#: 1e-6 of the cost is below it, and 1e-6 of a variable is far below its standard error.
#: scipy's default 1e-8 asks for more than the data resolve: measured on the ARTS damper
#: record ``ds1_1Hz_22lb``, 5,781 residual and 4,188 Jacobian evaluations (16 fits stopped
#: at their evaluation budget) against 1,604 and 1,064 here, 24.7 s against 9.0 s of CPU,
#: the same effects named and the band misfit 421.7 N against 422.2 N.
FIT_TOL = 1e-6


class LoopModel:
    """Transformed vector ``z = (ln(phi_max/x_max), chi, ln(1+beta), effect variables...)``;
    the force is ``Fs g(z) + F0`` with ``(Fs, F0)`` from linear least squares.
    """

    def __init__(self, ev: Evaluator, y, names, scales, F0=None):
        self.ev, self.y, self.names, self.scales = ev, y, tuple(names), scales
        self.F0 = F0  # a force offset measured at rest, or None: fitted
        lo = [math.log(PHI_RANGE[0]), CHI_BOUNDS[0], 0.0]
        hi = [math.log(PHI_RANGE[1]), CHI_BOUNDS[1], math.log1p(BETA_MAX)]
        for nm in self.names:
            for sp in EFFECTS[nm].specs:
                lo.append(sp.fit_bounds[0])
                hi.append(sp.fit_bounds[1])
        self.lower, self.upper = np.array(lo), np.array(hi)
        self.yy = float(y @ y)
        self.start = 0.0  # the joint's state before the record (Evaluator.set_start)

    def starts(self, z_prev) -> list[NDArray[np.float64]]:
        """Start vectors: the previous model's ``z`` with each of the new effect's starts."""
        new = EFFECTS[self.names[-1]].specs
        k = max(len(s.fit_starts) for s in new)
        return [
            np.concatenate([z_prev, [s.fit_starts[min(j, len(s.fit_starts) - 1)] for s in new]])
            for j in range(k)
        ]

    def decode(self, z) -> tuple[tuple[float, float, float], list[dict[str, float]]]:
        """``((phi_max [m], chi, beta), [effect parameters, ...])`` of the vector ``z``."""
        xm = self.ev.x_max
        shape = (xm * math.exp(z[0]), float(z[1]), math.expm1(z[2]))
        vals, k = [], 3
        for nm in self.names:
            d = {}
            for sp in EFFECTS[nm].specs:
                d[sp.name] = float(z[k]) / self.scales[sp.ref] ** sp.ref_power
                k += 1
            vals.append(d)
        return shape, vals

    def unit(self, z) -> NDArray[np.float64]:
        """Unit-``Fs`` force ``g(z)`` [-] at the fitted samples."""
        shape, vals = self.decode(z)
        self.ev.set_start(self.start)
        return self.ev.unit_force(shape, self.names, vals)

    def linear(self, g) -> tuple[float, float]:
        """``(Fs, F0)`` minimising ``|y - Fs g - F0|`` (``Fs > 0``; ``F0`` fixed if measured)."""
        if self.F0 is not None:
            gg = float(g @ g)
            Fs, F0 = (float(g @ (self.y - self.F0)) / gg if gg > 0 else 0.0), self.F0
        else:
            A = np.column_stack([g, np.ones_like(g)])
            (Fs, F0), *_ = np.linalg.lstsq(A, self.y, rcond=None)
        if not Fs > 0:
            Fs = 1e-12 * math.sqrt(self.yy / self.y.size + 1.0)
            F0 = self.F0 if self.F0 is not None else float(np.mean(self.y))
        return float(Fs), float(F0)

    def residual(self, z) -> NDArray[np.float64]:
        """Force residual ``y - Fs g(z) - F0`` [N] (large and finite where ``z`` fails)."""
        try:
            g = self.unit(z)
        except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError):
            return np.full(self.y.size, 1e6 * math.sqrt(self.yy / self.y.size + 1.0))
        Fs, F0 = self.linear(g)
        return self.y - Fs * g - F0

    def physical(self, z) -> tuple[IwanParameters, list[dict[str, float]], float]:
        """``(IwanParameters, [effect dicts in SI], F0)``."""
        shape, vals = self.decode(z)
        Fs, F0 = self.linear(self.unit(z))
        p1 = unit_params(*shape)
        p = IwanParameters(Fs, Fs * p1.KT, p1.chi, p1.beta)
        return p, [scale_effect(nm, v, Fs, to_unit=False) for nm, v in zip(self.names, vals)], F0


def fit(model: LoopModel, starts, *, max_nfev: int):
    """Bounded trust-region least squares from each start; the best result and total nfev."""
    best, nfev = None, 0
    for z0 in starts:
        z0 = np.clip(np.asarray(z0, float), model.lower, model.upper)
        res = least_squares(
            model.residual,
            z0,
            bounds=(model.lower, model.upper),
            method="trf",
            x_scale="jac",
            max_nfev=max_nfev,
            diff_step=1e-6,
            ftol=FIT_TOL,
            xtol=FIT_TOL,
        )
        nfev += res.nfev
        if best is None or res.cost < best.cost:
            best = res
    return best, nfev


def hop(model: LoopModel, res, *, max_nfev: int, rounds: int = 2):
    """Restarts around a fit whose misfit has jumps (an effect with ``force_jumps``).

    With break-away, the spike sliders (``S`` at ``phi_max``) break all at once: whether
    they break in a given half cycle is a yes/no event of ``phi_max`` and the ratio, and it
    changes the force of the rest of that half cycle, so the misfit has cliffs in these two
    variables and a fit can stop on the wrong side of one (measured: 1.29 x the noise where
    the truth gives 1.03). Each round restarts from the fit with ``ln phi_max`` moved by
    +-0.01, +-0.03 and each jumping effect's first variable by the same steps, and keeps
    the best; it stops when a round finds nothing better. Returns ``(result, nfev)``.
    """
    ks = [0] + [var_index(model.names, nm) for nm in model.names if EFFECTS[nm].force_jumps]
    nfev = 0
    for _ in range(rounds):
        starts = []
        for k in ks:
            for d in (-0.03, -0.01, 0.01, 0.03):
                z = res.x.copy()
                z[k] += d
                starts.append(z)
        best, n = fit(model, starts, max_nfev=max_nfev)
        nfev += n
        if not best.cost < res.cost * (1.0 - 1e-9):
            break
        res = best
    return res, nfev


#: Pre-record path ends scanned for the joint's starting state, as fractions of the largest |u|.
START_GRID = np.linspace(-1.0, 1.0, 21)


def fit_start(model: LoopModel, res, *, max_nfev: int):
    """The joint's state before the record: a nuisance, like the sensor offsets.

    A record starts wherever the previous test or the setting-up left the joint (a residual
    load, a position inside a gap); the model starting from virgin rest then misfits the
    record up to its first large excursion. The state is given the form of a path
    ``0 -> s -> u[0]`` driven before the first sample (:meth:`Evaluator.set_start`): ``s`` is
    scanned on :data:`START_GRID` times the largest |u| with the fit's other variables held,
    refined by a bounded scalar search, and the fit repeated from there. ``s = 0`` (the virgin
    start) is kept unless another value lowers the misfit by more than a part in 1e6, so a
    record that starts at rest is fitted exactly as before. Returns ``(start, result, nfev)``.
    """

    def cost(sv):
        model.start = float(sv)
        r = model.residual(res.x)
        return float(r @ r)

    x = model.ev.x_max
    c0 = cost(0.0)
    grid = [(c0, 0.0) if g == 0.0 else (cost(g * x), g * x) for g in START_GRID]
    nfev = len(grid)
    c_best, s_best = min(grid)
    if not c_best < c0 * (1.0 - 1e-6):
        model.start = 0.0
        return 0.0, res, nfev
    h = x * (START_GRID[1] - START_GRID[0])
    for _ in range(3):  # alternate: the start with the rest held, then the rest
        opt = minimize_scalar(
            cost,
            bounds=(s_best - h, s_best + h),
            method="bounded",
            options={"xatol": 1e-5 * x, "maxiter": 16},
        )
        nfev += int(opt.nfev)
        if opt.fun < c_best:
            c_best, s_best = float(opt.fun), float(opt.x)
        model.start = s_best
        again, n = fit(model, [res.x], max_nfev=max_nfev)
        nfev += n
        if not again.cost < res.cost * (1.0 - 1e-6):
            break
        res = again
        c_best = 2.0 * res.cost
        h *= 0.25
    model.start = s_best
    s_best, res, n = _polish_start(model, s_best, res, max_nfev=max_nfev)
    return s_best, res, nfev + n


def _polish_start(model: LoopModel, s, res, *, max_nfev: int):
    """One least-squares fit of the start together with the other variables, from the
    alternation's result (fitting in turn stops where each variable is optimal with the
    others held, which is not the joint optimum when the start and the joint's shape are
    correlated). Kept only if it lowers the misfit. Returns ``(start, result, nfev)``.
    """
    x = model.ev.x_max
    lo, hi = -1.5 * x, 1.5 * x

    def fun(zs):
        model.start = float(zs[-1])
        return model.residual(zs[:-1])

    zs0 = np.clip(np.append(res.x, s), np.append(model.lower, lo), np.append(model.upper, hi))
    try:
        joint = least_squares(
            fun,
            zs0,
            bounds=(np.append(model.lower, lo), np.append(model.upper, hi)),
            method="trf",
            x_scale="jac",
            max_nfev=max_nfev,
            diff_step=1e-6,
            ftol=FIT_TOL,
            xtol=FIT_TOL,
        )
    finally:
        model.start = s
    if not joint.cost < res.cost * (1.0 - 1e-9):
        return s, res, int(joint.nfev)
    s = float(joint.x[-1])
    joint.x = joint.x[:-1]
    model.start = s
    return s, joint, int(joint.nfev)


def var_index(names, name: str) -> int:
    """Position of the first fitting variable of effect ``name`` in a model's ``z``."""
    k = 3
    for nm in names:
        if nm == name:
            return k
        k += len(EFFECTS[nm].specs)
    raise KeyError(name)


def scan_starts(model: LoopModel, z_base, k: int, grid, *, keep: int = 2):
    """Start vectors from a 1-D scan of the newest effect's first fitting variable.

    Some effects make the least-squares objective flat in one variable where a fit starts:
    a break-away ratio changes the force only to second order in ``ratio - 1`` near 1 (no
    gradient to follow from "no effect"), and a backlash gap must first land near the
    data's zero-force plateau before the shape can follow.
    ``z_base`` is a full start vector; its entry ``k`` (see :func:`var_index`) takes each value of
    ``grid`` (fitting units, clipped to the bounds) and the ``keep`` values with the lowest
    residual norm are returned as starts, best first. Costs ``len(grid)`` evaluations.
    """
    costs = []
    for g in grid:
        z = np.array(z_base, float)
        z[k] = min(max(float(g), model.lower[k]), model.upper[k])
        r = model.residual(z)
        costs.append((float(r @ r), z))
    costs.sort(key=lambda c: c[0])
    return [z for _, z in costs[:keep]]


def flat(p: IwanParameters, effs, names, F0):
    out = [p.Fs, p.KT, p.chi, p.beta]
    labels = list(PARAM_NAMES)
    for nm, d in zip(names, effs):
        for k in EFFECTS[nm].parameter_names:
            out.append(d[k])
            labels.append(f"{nm}.{k}")
    return np.array(out + [F0]), labels + ["force_offset"]


def jacobian(model: LoopModel, z):
    """Jacobian of the residual [N per variable] and of the physical parameters in the fit's
    variables ``theta = (z, [start], Fs, F0)`` (``start`` only when the fit freed it,
    ``model.start != 0``; ``F0`` only when it is fitted): central differences at two steps,
    samples whose force jumps between them left out (:func:`jumps`); the columns of ``Fs``
    and ``F0``, in which the residual ``y - Fs g(z) - F0`` is linear, exactly (``-g``,
    ``-1``), and the physical parameters' by their closed form (no force evaluated: a
    Jacobian costs four force evaluations per variable of ``z`` and the start). Returns
    ``(J, Jp, theta, lower, upper)``, the bounds of ``theta`` (infinite for the linear ones
    and the start).
    """
    g = model.unit(z)
    Fs, F0 = model.linear(g)
    s0 = model.start
    free_start = s0 != 0.0
    nz = z.size
    theta = np.concatenate([z, [s0] if free_start else [], [Fs, F0]])
    fixed = model.F0 is not None
    lo = np.concatenate([model.lower, [-np.inf] if free_start else [], [0.0, -np.inf]])
    hi = np.concatenate([model.upper, [np.inf] if free_start else [], [np.inf, np.inf]])

    def resid(th):
        if free_start:
            model.start = float(th[nz])
        try:
            return model.y - th[-2] * model.unit(th[:nz]) - th[-1]
        finally:
            model.start = s0

    def phys(th):
        shape, vals = model.decode(th[:nz])
        p1 = unit_params(*shape)
        p = IwanParameters(th[-2], th[-2] * p1.KT, p1.chi, p1.beta)
        effs = [scale_effect(nm, d, th[-2], to_unit=False) for nm, d in zip(model.names, vals)]
        return np.append(flat(p, effs, model.names, th[-1])[0], th[nz] if free_start else 0.0)

    cols, pcols = [], []
    m = theta.size - (1 if fixed else 0)
    for j in range(m):
        if j == theta.size - 2:  # Fs: a relative step that stays positive
            h = 1e-5 * theta[j]
        elif j == theta.size - 1:
            h = 1e-5 * max(abs(theta[j]), 1.0)
        elif j == nz:  # the start (only when free): metres
            h = 1e-5 * model.ev.x_max
        else:
            h = 1e-5
        pcols.append(_difference(phys, theta, j, h, lo, hi))
        if j >= theta.size - 2:
            cols.append(-g if j == theta.size - 2 else -np.ones_like(g))
            continue
        dr, dr4 = (_difference(resid, theta, j, f * h, lo, hi) for f in (1, 4))
        cols.append(np.where(jumps(dr, dr4), 0.0, dr))
    return (np.column_stack(cols), np.column_stack(pcols), theta[:m], lo[:m], hi[:m])


def uncertainty(model: LoopModel, z, r, jac=None):
    """Standard errors and correlation of (Fs, KT, chi, beta, effect params, F0): the package's
    one covariance routine (:func:`iwan_element.fitting.covariance`, docs/fitting.md) with the
    delta method from the Jacobian in ``(z, start, Fs, F0)`` (:func:`jacobian`, or ``jac``,
    its result when already computed), the residual variance inflated by its correlation time
    (a correlated, systematic misfit is not treated as independent noise); NaN for a
    parameter along a degenerate direction.

    A fitted starting state (``model.start != 0``, :func:`fit_start`) is a nuisance variable
    of the fit like the force offset: it has a column in the Jacobian, so its correlation
    with the joint's variables widens their errors; ``start = 0`` (kept when no start fits
    better) is held. Returns ``(se, corr, se_start)`` (``se_start`` [m], 0 when held).
    """
    J, Jp, theta, _, _ = jacobian(model, z) if jac is None else jac
    c = covariance(J, r, tau=integrated_time(r), dof=max(r.size - theta.size, 1), Jp=Jp)
    se, corr = c.stderr, c.correlation
    return se[:-1], corr[:-1, :-1], float(se[-1])


def _difference(fn, theta, j, h, lo, hi):
    """Central difference quotient of ``fn`` in ``theta[j]`` (one-sided at a bound)."""
    tp, tm = theta.copy(), theta.copy()
    tp[j] = min(theta[j] + h, hi[j])
    tm[j] = max(theta[j] - h, lo[j])
    return (fn(tp) - fn(tm)) / (tp[j] - tm[j])


def jumps(d1, d4) -> NDArray[np.bool_]:
    """Samples whose force jumps between the two difference steps (quotients that do not
    agree; a jump gives ``jump / step``): a force that is discontinuous in a parameter
    (sliders breaking at once at one sample or the next, e.g. the spike ``S`` of a joint
    with break-away) has no derivative there, and its difference quotient would claim a
    precision the data do not hold, so these samples are left out of the Jacobian.
    """
    scale = float(np.sqrt(np.mean(d1 * d1 + d4 * d4))) + 1e-300
    return np.abs(d1 - d4) > 0.1 * np.maximum(np.abs(d1), np.abs(d4)) + 1e-6 * scale


def make_fit_result(
    *, params: IwanParameters, stderr: dict, identified: dict, correlation, fixed=(), **kw
) -> FitResult:
    """A :class:`FitResult` from the fitted joint, its standard errors, verdicts and
    correlation (gathered into its parameter table,
    :func:`identify.loops.joint_verdict.joint_table`) and the other fields this module knows
    (others left at None/defaults), so a change of the fit module's result fields does not
    break the diagnosis.
    """
    kw["params"] = joint_table(params, stderr, identified, fixed=fixed, correlation=correlation)
    args = {}
    for f in dataclasses.fields(FitResult):
        if f.name in kw:
            args[f.name] = kw[f.name]
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            args[f.name] = None
    return FitResult(**args)
