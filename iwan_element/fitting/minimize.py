"""A thin least-squares entry shared by the fits: :func:`minimize` over scipy's bounded
trust-region solver (``least_squares(method="trf")``) and :func:`box_lm`, a small box-bounded
Levenberg-Marquardt kept for the loop fit's speed (its docstring says why).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ..base.validation import check_int, check_scalar, finite_array

__all__ = ["MinimizeResult", "minimize", "box_lm", "METHODS"]

#: The solvers :func:`minimize` offers.
METHODS = ("trf", "box-lm")


@dataclass
class MinimizeResult:
    """Result of :func:`minimize`.

    Attributes
    ----------
    x : ndarray
        The solution.
    cost : float
        ``0.5 |fun(x)|^2``.
    status : int
        ``> 0`` converged, ``0`` evaluation budget used up (``< 0``: scipy's failures).
    message : str
    nfev : int
        Residual evaluations (the box LM counts its difference Jacobians too).
    fun : ndarray
        Residuals at ``x``.
    jac : ndarray or None
        Jacobian at ``x`` (``"trf"``; None for ``"box-lm"``).
    """

    x: np.ndarray
    cost: float
    status: int
    message: str
    nfev: int
    fun: np.ndarray | None = None
    jac: np.ndarray | None = None

    @property
    def success(self) -> bool:
        """The solver converged (``status > 0``)."""
        return self.status > 0


def minimize(
    fun,
    x0,
    lower,
    upper,
    *,
    method: str = "trf",
    max_nfev: int,
    ftol: float | None = None,
    xtol: float | None = None,
    **options,
) -> MinimizeResult:
    """Minimise ``0.5 |fun(x)|^2`` for ``lower <= x <= upper``.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> ndarray (m,)``, the residuals.
    x0 : array_like, shape (p,)
        Start (clipped into the bounds).
    lower, upper : array_like, shape (p,)
        Bounds (``-inf``/``inf``: none), ``lower < upper``.
    method : {"trf", "box-lm"}, keyword-only
        ``"trf"``: ``scipy.optimize.least_squares(method="trf")`` with ``options`` passed on
        (``x_scale``, ``diff_step``, ...); ``"box-lm"``: :func:`box_lm` (no options).
    max_nfev : int, keyword-only
        Evaluation budget, ``>= 1``.
    ftol, xtol : float, optional, keyword-only
        Relative stopping tolerances (default: the solver's own, 1e-8 for ``"trf"``,
        1e-12 and 1e-10 for ``"box-lm"``).

    Returns
    -------
    MinimizeResult
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    x0 = finite_array("x0", x0, ndim=1)
    lo = np.asarray(lower, float)
    hi = np.asarray(upper, float)
    if (
        lo.shape != x0.shape
        or hi.shape != x0.shape
        or np.isnan(lo).any()
        or np.isnan(hi).any()
        or np.any(lo >= hi)
    ):
        raise ValueError(f"lower and upper must have {x0.size} entries each with lower < upper")
    max_nfev = check_int("max_nfev", max_nfev, 1)
    x0 = np.clip(x0, lo, hi)
    tol = {
        k: check_scalar(k, v, low=0.0, high=1.0, low_open=True)
        for k, v in (("ftol", ftol), ("xtol", xtol))
        if v is not None
    }
    if method == "box-lm":
        if options:
            raise ValueError(f"box-lm takes no options, got {sorted(options)}")
        return box_lm(fun, x0, lo, hi, max_nfev=max_nfev, **tol)
    res = least_squares(fun, x0, bounds=(lo, hi), method="trf", max_nfev=max_nfev, **tol, **options)
    return MinimizeResult(
        res.x, float(res.cost), int(res.status), str(res.message), int(res.nfev), res.fun, res.jac
    )


def box_lm(
    fun, x0, lower, upper, *, max_nfev: int, ftol: float = 1e-12, xtol: float = 1e-10
) -> MinimizeResult:
    """Levenberg-Marquardt with box bounds (projected steps) for a few parameters.

    Minimises ``0.5 |fun(x)|^2`` for ``lower <= x <= upper``. The Jacobian is taken by
    forward differences; the normal equations are formed with ``einsum``. Why not
    ``scipy.optimize.least_squares``: for a tall Jacobian (thousands of residuals, three
    parameters) its trust-region steps spend their time in multithreaded OpenBLAS
    matrix-vector products, which ran 7-10 times slower than single-threaded on a busy
    2-core machine; this loop needs no BLAS. ``tests/test_fit.py`` checks that it reaches the
    same minimum as ``least_squares(method="trf")``.
    """
    x = np.clip(np.asarray(x0, float), lower, upper)
    r = fun(x)
    nfev = 1
    cost = 0.5 * float(np.einsum("i,i->", r, r))
    lam = 1e-3
    p = x.size
    while nfev + p < max_nfev:
        J = np.empty((r.size, p))
        for j in range(p):
            h = 1e-7 * max(1.0, abs(x[j]))
            if x[j] + h > upper[j]:
                h = -h  # step inwards at an upper bound
            xh = x.copy()
            xh[j] += h
            J[:, j] = (fun(xh) - r) / h
        nfev += p
        g = np.einsum("ij,i->j", J, r)
        A = np.einsum("ij,ik->jk", J, J)
        free = ~(((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0)))
        if not free.any() or np.max(np.abs(g[free])) <= 1e-14 * max(cost, 1e-300):
            return MinimizeResult(x, cost, 1, "projected gradient is zero", nfev, r)
        Af = A[np.ix_(free, free)]
        while nfev < max_nfev:
            M = Af + lam * np.diag(np.diag(Af) + 1e-30)
            try:
                d = np.zeros(p)
                d[free] = np.linalg.solve(M, -g[free])
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            x_new = np.clip(x + d, lower, upper)
            r_new = fun(x_new)
            nfev += 1
            cost_new = 0.5 * float(np.einsum("i,i->", r_new, r_new))
            if cost_new < cost:
                step = x_new - x
                predicted = -(g @ step + 0.5 * step @ A @ step)
                small_f = cost - cost_new <= ftol * cost and predicted <= ftol * cost
                # a short step means convergence only when damping did not shorten it
                small_x = lam < 1e-2 and np.all(np.abs(step) <= xtol * (xtol + np.abs(x)))
                x, r, cost = x_new, r_new, cost_new
                lam = max(lam / 3.0, 1e-12)
                if small_f or small_x:
                    return MinimizeResult(
                        x,
                        cost,
                        2,
                        f"relative reduction of the cost below {ftol:g}"
                        if small_f
                        else f"step below xtol = {xtol:g}",
                        nfev,
                        r,
                    )
                break
            lam *= 4.0
            if lam > 1e16:
                return MinimizeResult(
                    x,
                    cost,
                    3,
                    "no step reduces the cost further (at a minimum to round-off)",
                    nfev,
                    r,
                )
    return MinimizeResult(x, cost, 0, f"evaluation budget max_nfev = {max_nfev} used up", nfev, r)
