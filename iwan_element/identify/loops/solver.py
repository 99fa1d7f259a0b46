"""Least-squares machinery shared by the loop and dissipation fits.

:class:`_Problem` holds data modelled as ``Fs g(phi_max, chi, beta)`` (plus a force offset
for loop fits) with ``Fs`` and the offset eliminated in closed form (variable projection);
:func:`_multistart` runs the box-bounded Levenberg-Marquardt of
:func:`iwan_element.fitting.minimize` (``method="box-lm"``) from several starts;
:func:`_uncertainty` takes the Jacobian at the optimum to :func:`iwan_element.fitting.covariance`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from ...core.history import unit_params
from ...core.parameters import IwanParameters
from ...fitting import covariance, minimize

log = logging.getLogger(__name__)


class _Problem:
    """Data ``y`` modelled as ``Fs * g(phi_max, chi, beta)`` (+ ``dF0`` with ``offset=True``).

    ``log=False``: residuals ``w (y - Fs g - dF0)``; ``log=True``: ``w (ln y - ln Fs - ln g)``.
    ``Fs`` (and the force offset ``dF0``) enter linearly and are eliminated in closed form.
    ``entry_x`` is the largest backbone argument [m] behind each residual: the residual is in
    macroslip when it exceeds ``phi_max``.
    """

    def __init__(
        self,
        y,
        unit: Callable,
        *,
        w,
        log_space: bool,
        entry_x,
        min_macro: int,
        offset: bool = False,
        timeseries: bool = False,
    ):
        self.y = y
        self.ly = np.log(y) if log_space else None
        self.unit = unit
        self.w = w
        self.w2 = w * w
        self.log = log_space
        self.offset = bool(offset) and not log_space
        self.timeseries = bool(timeseries)  # residuals in time order: their correlation counts
        self.block = 0  # residuals per half cycle (block sandwich)
        self.entry_x = entry_x
        self.x_max = float(entry_x.max())
        self.min_macro = min_macro
        self.nfev = 0
        self.dF0 = 0.0  # force offset of the last projection [N]
        self.sw = float(self.w2.sum())
        self.sy = float(np.einsum("i,i->", self.w2, y))

    def g(self, phi_max, chi, beta):
        self.nfev += 1
        return self.unit(unit_params(phi_max, chi, beta))

    def projected(self, phi_max, chi, beta):
        """Best ``Fs`` (and ``dF0``) for the shape ``(phi_max, chi, beta)`` and the residuals."""
        return self.project_g(self.g(phi_max, chi, beta))

    def project_g(self, g):
        """Best ``Fs`` (and ``dF0``) for the unit-``Fs`` model values ``g``, and the residuals."""
        if self.log:
            lg = np.log(g)
            lnFs = np.sum(self.w2 * (self.ly - lg)) / np.sum(self.w2)
            return math.exp(lnFs), self.w * (self.ly - lnFs - lg)
        if self.offset:  # weighted 2x2 normal equations for (Fs, dF0)
            # einsum, not @: BLAS dot products are slow on a busy multi-threaded OpenBLAS
            wg = self.w2 * g
            sw, sg, sgg = self.sw, float(wg.sum()), float(np.einsum("i,i->", wg, g))
            sy, sgy = self.sy, float(np.einsum("i,i->", wg, self.y))
            det = sgg * sw - sg * sg
            Fs = (sgy * sw - sg * sy) / det if det > 0 else 1.0
            Fs = Fs if Fs > 0 else 1e-300
            self.dF0 = float((sy - Fs * sg) / sw)
            return Fs, self.w * (self.y - Fs * g - self.dF0)
        den = np.sum(self.w2 * g * g)
        Fs = np.sum(self.w2 * g * self.y) / den if den > 0 else 1.0
        Fs = Fs if Fs > 0 else 1e-300
        return Fs, self.w * (self.y - Fs * g)

    def residual(self, params: IwanParameters, dF0: float = 0.0):
        """Residuals of a full parameter set (no projection)."""
        self.nfev += 1
        model = self.unit(params)
        if self.log:
            return self.w * (self.ly - np.log(model))
        return self.w * (self.y - model - dF0)

    def n_macro(self, phi_max):
        return int(np.count_nonzero(self.entry_x > phi_max))


def _q_to_shape(q, x_max, beta_fixed):
    phi = x_max * math.exp(q[0])
    beta = beta_fixed if beta_fixed is not None else math.expm1(q[2])
    return phi, float(q[1]), beta


def _multistart(prob: _Problem, starts, lower, upper, *, beta_fixed, max_nfev):
    """Least squares on ``q = (ln(phi_max/x_max), chi[, ln(1+beta)])`` from each start.

    The best wins.
    """
    best = None

    def fun(q):
        return prob.projected(*_q_to_shape(q, prob.x_max, beta_fixed))[1]

    for q0 in starts:
        res = minimize(fun, np.asarray(q0, float), lower, upper, method="box-lm", max_nfev=max_nfev)
        log.debug("start %s -> cost %.6g (%s)", np.round(q0, 3), res.cost, res.message)
        if best is None or res.cost < best.cost:
            best = res
    return best


def _fd_jacobian(fun, theta, steps):
    """Central-difference Jacobian of ``fun`` at ``theta``."""
    cols = []
    for j, h in enumerate(steps):
        tp = theta.copy()
        tm = theta.copy()
        tp[j] += h
        tm[j] -= h
        cols.append((fun(tp) - fun(tm)) / (2.0 * h))
    return np.column_stack(cols)


def _uncertainty(
    fun,
    theta,
    r,
    scale,
    *,
    at_lower_bound=None,
    tau: float = 1.0,
    timeseries: bool = False,
    block: int = 0,
):
    """Standard errors and correlations from the Jacobian (see :mod:`.identifiability`).

    The central-difference Jacobian of ``fun`` (transformed parameters ``theta`` ->
    residuals) at the optimum goes to the package's one covariance routine,
    :func:`iwan_element.fitting.covariance` (docs/fitting.md): ``tau s^2 (J^T J)^-1``, for a
    time series (``timeseries=True``) also the block sandwich over blocks of at least
    ``block`` residuals (a half cycle), and the delta method with the diagonal factor
    ``scale = |d p / d theta|``. A parameter whose index is ``at_lower_bound`` is evaluated
    one step inside its bound 0. Returns ``(stderr of p, correlation)``; NaN for a parameter
    the data do not determine.
    """
    h = 1e-5
    th = np.array(theta, float)
    if at_lower_bound is not None:
        th[at_lower_bound] = max(th[at_lower_bound], h)
    J = _fd_jacobian(fun, th, np.full(th.size, h))
    if not np.all(np.isfinite(J)):  # the model failed next to the optimum
        return np.full(th.size, math.nan), np.full((th.size, th.size), math.nan)
    c = covariance(
        J, r, tau=tau, block=block if timeseries else None, Jp=np.diag(np.asarray(scale, float))
    )
    return c.stderr, c.correlation
