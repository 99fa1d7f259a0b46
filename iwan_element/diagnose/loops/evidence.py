"""The probability stage of a loop diagnosis: the evidence of every stack the selection fitted
(:mod:`..selection.probabilities`), and the force of a fitted stack from its variables (for the
model-averaged band, :mod:`..selection.averaging`).

The variables of a loop fit are ``theta = (z, [start], Fs, F0)`` (:func:`.model.jacobian`):
the joint's shape ``z[:3] = (ln(phi_max / x_max), chi, ln(1 + beta))``, the effects' fitting
variables, the starting state when the fit freed it, the force scale and the force offset.
Their prior box: the loop model's bounds for the shape, each effect variable's declared
``prior_range``, ``+-1.5 x_max`` for the start, ``[0, 1e3 F_span]`` and ``+-1e3 F_span``
for ``Fs`` and ``F0`` (the same for every explanation of the record, so they cancel but for
what the other variables' correlation with them changes).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...core.history import unit_params
from ...core.parameters import IwanParameters
from ...effects import EFFECTS
from ...effects.engine.evaluate import build_element, scale_effect
from ...fitting.evidence import Ridge
from ..selection.probabilities import key
from . import model as M

if TYPE_CHECKING:
    from ..selection.averaging import AveragedBand

__all__ = ["loop_evaluator", "collect_fits", "member_force", "n_variables"]


def n_variables(stack) -> int:
    """Fitting variables ``z`` of a stack: the joint's shape and the effects' variables."""
    return 3 + sum(len(EFFECTS[nm].specs) for nm in stack)


def collect_fits(base: dict, steps) -> dict:
    """``{key: (stack, chi2, n_params, fitter row)}``: the best fit of each explanation the
    selection fitted (``base``: the plain joint's row; ``steps``: the rule's step table).
    """
    out = {(): ((), float(base["chi2"]), 5, base)}
    for st in steps:
        for r in st["rows"]:
            row = r["state"]
            k = key(row["names"])
            q = n_variables(row["names"]) + 2
            if k not in out or row["chi2"] < out[k][1]:
                out[k] = (tuple(row["names"]), float(row["chi2"]), q, row)
    return out


def _box(model, theta, free_start, span):
    """The prior box of ``theta`` (module docstring)."""
    lo, hi = list(model.lower[:3]), list(model.upper[:3])
    for nm in model.names:
        for sp in EFFECTS[nm].specs:
            a, b = sp.prior_range
            lo.append(a)
            hi.append(b)
    if free_start:
        x = model.ev.x_max
        lo.append(-1.5 * x)
        hi.append(1.5 * x)
    lo += [0.0, -1e3 * span][: theta.size - len(lo)]
    hi += [1e3 * span, 1e3 * span][: theta.size - len(hi)]
    return np.array(lo), np.array(hi)


def loop_evaluator(sigma: float, span: float) -> Callable[..., Any]:
    """``evaluate(stack, row)`` for :func:`.probabilities.rank` on a loop record: the
    noise-normalised Jacobian (kept in the row's cache, where the final fit's uncertainty
    finds it) and residual, the variables and their prior box; ``sigma`` [N]: the noise the
    selection scored against, ``span`` [N]: the force range.
    """

    def evaluate(stack, row):
        cache = row.setdefault("cache", {})
        if "jac" not in cache:
            cache["jac"] = M.jacobian(row["model"], row["z"])
        J, _, theta, _, _ = cache["jac"]
        model = row["model"]
        r = model.residual(row["z"])
        nz = n_variables(stack)
        free = theta.size - nz == 3
        lo, hi = _box(model, theta, free, span)

        def chi2_at(th):
            s0 = model.start
            if free:
                model.start = float(th[nz])
            try:
                res = model.y - th[-2] * model.unit(th[:nz]) - th[-1]
            except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError):
                return math.inf
            finally:
                model.start = s0
            return float(res @ res) / sigma**2

        specs = [None] * 3 + [sp for nm in stack for sp in EFFECTS[nm].specs]
        specs += [None] * (theta.size - len(specs))
        rdg = microslip_ridge(stack, np.clip(theta, lo, hi), hi, chi2_at, J=J / sigma)
        return J / sigma, r / sigma, theta, lo, hi, chi2_at, specs, rdg

    return evaluate


#: Step along the microslip ridge (in ``ln phi_max``) at which a record is tested for it.
RIDGE_STEP = 0.02


def microslip_ridge(stack, theta, hi, chi2_at, *, J=None) -> Ridge | None:
    """The curve along which a loop fit's force does not change when no sample reaches the
    joint's macroslip (:class:`~iwan_element.fitting.evidence.Ridge`), or None.

    Below ``phi_max`` the Iwan force depends on ``KT``, ``chi`` and the density ``R`` of the
    sliders' strengths alone (Segalman 2005, J. Appl. Mech. 72:752-760: ``F = KT u - R
    u^(chi+2) / ((chi+1)(chi+2))`` on the virgin curve, Masing's rule after it): ``phi_max``
    and the spike ``S`` trade along a curve that keeps ``KT = r (1 + beta)`` and ``R``,
    ``r = R phi_max^(chi+1) / (chi+1)``. With ``Delta = ln(phi_max' / phi_max)``:
    ``ln(1 + beta') = ln(1 + beta) - (chi+1) Delta``, ``Fs' = Fs e^((chi+2) Delta) c' / c``,
    ``c = beta + (chi+1)/(chi+2)``, and each effect variable scaled by ``(Fs / Fs')^p``
    (``p`` its ``fs_power``: the effect's physical value kept); it ends where ``beta' = 0``.
    The Jacobian of the box variables ``(ln(1+beta), Fs, effects)`` in the invariants
    ``(KT, R, physical effects)`` at fixed ``phi_max``: ``(phi_max / R) (1 - 1 / ((1 + beta)
    (chi + 2))) prod Fs^-p``.

    The record is on the ridge when ``chi2_at`` is the same (to 1e-9 of it) at two points
    of the curve on one side of the fit, :data:`RIDGE_STEP` and twice that away (the fit
    itself may sit where the ridge ends, macroslip just reached at the largest
    displacement); not tested (None) when the noise-normalised Jacobian ``J`` at the fit
    predicts a change of ``chi2`` above 1e4 at the first point (a record well into
    macroslip: no evaluation of the model).
    """
    nz = n_variables(stack)
    chi, lb0, Fs0 = float(theta[1]), float(theta[2]), float(theta[-2])
    k, a = chi + 1.0, (chi + 1.0) / (chi + 2.0)
    c0 = math.expm1(lb0) + a
    pw = np.array([sp.fs_power for nm in stack for sp in EFFECTS[nm].specs], float)

    def curve(s):
        d = s - theta[0]
        lb = lb0 - k * d
        beta = math.expm1(lb)
        Fs = Fs0 * math.exp((chi + 2.0) * d) * (beta + a) / c0
        th = theta.copy()
        th[0], th[2], th[-2] = s, lb, Fs
        th[3:nz] = theta[3:nz] * (Fs0 / Fs) ** pw
        return th, d + math.log1p(-1.0 / ((1.0 + beta) * (chi + 2.0))) - float(pw.sum()) * math.log(
            Fs / Fs0
        )

    s_hi = theta[0] + lb0 / k  # beta' = 0
    s_lo = theta[0] + (lb0 - hi[2]) / k  # beta' at its bound
    if J is not None:
        h = 1e-6
        t = (curve(theta[0] + h)[0] - curve(theta[0] - h)[0]) / (2 * h)
        if (RIDGE_STEP * float(np.linalg.norm(J @ t))) ** 2 > 1e4:
            return None
    for sign in (1.0, -1.0):  # away from macroslip first
        s1, s2 = theta[0] + sign * RIDGE_STEP, theta[0] + 2.0 * sign * RIDGE_STEP
        if not (s_lo <= min(s1, s2) and max(s1, s2) <= s_hi):
            continue
        c1, c2 = chi2_at(curve(s1)[0]), chi2_at(curve(s2)[0])
        return Ridge(0, curve, s_lo, s_hi) if abs(c1 - c2) <= 1e-9 * max(c1, 1.0) else None
    return None


__all__ += ["microslip_ridge"]


def member_physical(
    stack, theta, x_max: float, scales: dict
) -> tuple[IwanParameters, list[dict[str, float]], float, float]:
    """``(IwanParameters, effect dicts [SI], F0 [N], start [m])`` of a loop fit's variables
    ``theta`` (module docstring) on a record of largest |u| ``x_max`` and fit scales
    ``scales``.
    """
    nz = n_variables(stack)
    z = theta[:nz]
    start = float(theta[nz]) if theta.size - nz == 3 else 0.0
    Fs, F0 = float(theta[-2]), float(theta[-1])
    p1 = unit_params(x_max * math.exp(z[0]), float(z[1]), math.expm1(z[2]))
    p = IwanParameters(Fs, Fs * p1.KT, p1.chi, p1.beta)
    effs, k = [], 3
    for nm in stack:
        d = {}
        for sp in EFFECTS[nm].specs:
            d[sp.name] = float(z[k]) / scales[sp.ref] ** sp.ref_power
            k += 1
        effs.append(scale_effect(nm, d, Fs, to_unit=False))
    return p, effs, F0, start


def member_force(stack, theta, x_max, scales, u, v) -> NDArray[np.float64]:
    """Force [N] of a loop fit's variables ``theta`` on the drive ``u`` [m], ``v`` [m/s]
    from the joint's rest, its fitted starting state and force offset included.
    """
    p, effs, F0, start = member_physical(stack, theta, x_max, scales)
    el = build_element(p, stack, effs)
    ue, ve = np.concatenate([[start], u]), np.concatenate([[0.0], v])
    F = el.force_history(ue, ve) if stack else el.force_history(ue)
    return F[1:] + F0


__all__ += ["member_physical"]


def loop_band(diag, t, u, level: float) -> AveragedBand:
    """The model-averaged force of a loop diagnosis ``diag`` on the drive ``(t, u)`` (None:
    the record as fitted): :class:`.averaging.AveragedBand` with channel ``"force"`` [N].
    """
    from ...base.validation import check_time, finite_array
    from ..selection.averaging import band, linear_spread, members

    if not diag.explanations:
        raise ValueError(
            "this diagnosis has no probabilities (diagnose(..., "
            "probabilities=False)): nothing to average"
        )
    if u is None:
        uj = np.asarray(diag.u, float) - float(diag.offsets["displacement"])
        tt = None if diag.details.get("time_given") is False else np.asarray(diag.t, float)
    else:
        uj = finite_array("u", u, ndim=1, min_size=3)
        tt = None if t is None else check_time(t, uj.size)
    v = np.zeros(uj.size) if tt is None else np.gradient(uj, tt)
    x_max, scales = diag.details["x_max"], diag.details["scales"]
    parts = []
    for e, w in members(diag.explanations):
        if e.theta.size == 0:
            continue

        def predict(th, stack=e.stack):
            return member_force(stack, th, x_max, scales, uj, v)

        mu, sd = linear_spread(predict, e.theta, e.covariance)
        parts.append((e.effects, w, {"force": (mu, sd, "N")}))
    s = sum(p[1] for p in parts)
    parts = [(a, w / s, c) for a, w, c in parts]
    x = np.arange(uj.size, dtype=float) if tt is None else tt
    return band(x, "time [s]" if tt is not None else "sample", parts, level)


__all__ += ["loop_band"]
