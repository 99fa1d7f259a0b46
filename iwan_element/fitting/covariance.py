"""The one covariance routine of the package's fits (docs/fitting.md, sections 1-4).

``cov = tau s^2 (J^T J)^-1`` for residuals ``r`` with Jacobian ``J`` in the fitting
variables ``theta`` (Seber and Wild 1989, *Nonlinear Regression*, Wiley, chapter 2),
computed through the SVD of the column-scaled Jacobian so that variables of different units
do not decide the rank; a direction whose scaled singular value is below ``cutoff`` times
the largest is degenerate (the data do not determine it) and every variable with a component
along it gets a NaN standard error. Optionally:

* the block sandwich (Kuensch 1989, Ann. Statist. 17:1217-1241; the batch-means form of the
  heteroskedasticity and autocorrelation consistent estimator of Newey and West 1987,
  Econometrica 55:703-708) for residuals in time order, each variance the larger of the
  plain and the sandwich one;
* the delta method to physical parameters ``p(theta)`` through their Jacobian ``Jp``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_int, check_scalar, finite_array

__all__ = ["Covariance", "covariance", "normal_inverse"]

#: Scaled singular values below this fraction of the largest are degenerate directions.
CUTOFF = 1e-7
#: A variable with a component above this along a degenerate (unit, scaled) direction is
#: not determined.
COMPONENT = 1e-3
#: Shortest block of the sandwich [residuals].
MIN_BLOCK = 20


@dataclass(frozen=True, eq=False)
class Covariance:
    """Result of :func:`covariance`.

    Attributes
    ----------
    covariance : ndarray, shape (q, q)
        Covariance of the parameters (``theta``, or ``p(theta)`` when ``Jp`` was given), in
        their units squared. Degenerate directions are left out (pseudo-inverse).
    stderr : ndarray, shape (q,)
        Standard errors; NaN for a parameter the data do not determine.
    correlation : ndarray, shape (q, q)
        Correlation matrix; NaN rows and columns where ``stderr`` is NaN.
    degenerate : ndarray of bool, shape (q,)
        ``True`` for a parameter with a component along a degenerate direction.
    s2 : float
        Residual variance used (``SSR / dof`` unless given).
    tau : float
        Correlation time [residuals] the variances were multiplied by.
    block : int
        Block length [residuals] of the sandwich, 0 when none was formed.
    widened : bool
        Whether the sandwich widened at least one variance.
    """

    covariance: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    degenerate: np.ndarray
    s2: float
    tau: float
    block: int
    widened: bool


def _scaled_svd(J: np.ndarray, cutoff: float):
    """``((J^T J)^+, unit degenerate directions in scaled variables (rows), column scale)``."""
    m, p = J.shape
    scale = np.sqrt(np.einsum("ij,ij->j", J, J))
    scale[scale == 0] = 1.0
    _, sv, Vt = np.linalg.svd(J / scale, full_matrices=False)
    if sv.size < p:  # fewer residuals than variables
        sv = np.append(sv, np.zeros(p - sv.size))
        Vt = np.linalg.svd(np.vstack([J / scale, np.zeros((p - m, p))]))[2]
    good = sv > cutoff * sv[0] if sv.size and sv[0] > 0 else np.zeros(p, bool)
    A_inv = (Vt[good].T / sv[good] ** 2) @ Vt[good] / np.outer(scale, scale)
    return A_inv, Vt[~good], scale


def normal_inverse(J, *, cutoff: float = CUTOFF) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """``(J^T J)^+`` through the SVD of the column-scaled ``J``, and the degenerate mask.

    Parameters
    ----------
    J : array_like, shape (m, p)
        Jacobian of the residuals (finite).
    cutoff : float, keyword-only
        Relative singular-value threshold of a degenerate direction, in ``(0, 1)``.

    Returns
    -------
    A_inv : ndarray, shape (p, p)
    degenerate : ndarray of bool, shape (p,)
        Variables with a component above 1e-3 along a degenerate direction.
    """
    J = finite_array("J", J, ndim=2)
    cutoff = check_scalar("cutoff", cutoff, low=0.0, high=1.0, low_open=True, high_open=True)
    A_inv, null, scale = _scaled_svd(J, cutoff)
    return A_inv, _degenerate(np.diag(1.0 / scale), null)


def _degenerate(Jp_s, null):
    """Parameters whose gradient in the scaled variables, ``Jp_s`` (rows), has a component
    above :data:`COMPONENT` of its length along a degenerate direction (rows of ``null``).
    """
    norm = np.sqrt(np.einsum("ij,ij->i", Jp_s, Jp_s))
    comp = np.abs(Jp_s @ null.T) if null.size else np.zeros((Jp_s.shape[0], 0))
    return np.any(comp > COMPONENT * norm[:, None], axis=1) & (norm > 0)


def _sandwich(J, r, A_inv, cov, tau, block):
    """The block sandwich (module docstring): ``cov`` widened where it is larger, the block
    length, and whether it widened anything. Blocks of ``max(20, 4 tau, block)`` residuals;
    small-sample factor ``nb / (nb - p)``; not formed with fewer than ``2 p`` blocks.
    """
    m, p = J.shape
    if m <= 4 * p:
        return cov, 0, False
    L = int(max(MIN_BLOCK, math.ceil(4.0 * tau), block))
    nb = m // L
    if nb < 2 * p:
        return cov, 0, False
    sc = np.einsum("bij,bi->bj", J[: nb * L].reshape(nb, L, p), r[: nb * L].reshape(nb, L))
    S = np.einsum("bj,bk->jk", sc, sc) * (m / (nb * L)) * nb / (nb - p)
    cov_s = A_inv @ S @ A_inv
    ds, dt = np.diag(cov_s), np.diag(cov)
    ok = np.isfinite(ds) & (ds > 0)
    # a parameter with no variance either way (a zero Jacobian column: not determined) keeps
    # its zero row; any other failure leaves the plain covariance
    if not np.all(np.isfinite(ds)) or not ok.any() or np.any(~ok & (dt > 0)):
        return cov, 0, False
    big = np.ones(p)
    big[ok] = np.sqrt(np.maximum(ds[ok], dt[ok]) / ds[ok])
    return cov_s * np.outer(big, big), L, bool(np.any(ds > dt))


def covariance(
    J,
    r=None,
    *,
    tau: float = 1.0,
    s2: float | None = None,
    dof: int | None = None,
    block: int | None = None,
    Jp=None,
    cutoff: float = CUTOFF,
) -> Covariance:
    """Covariance, standard errors and correlation of least-squares estimates.

    ``cov = tau s^2 (J^T J)^-1`` (docs/fitting.md section 1) through the column-scaled SVD;
    with ``block`` the block sandwich (section 2), with ``Jp`` the delta method (section 3).

    Parameters
    ----------
    J : array_like, shape (m, p)
        Jacobian of the residuals with respect to the fitting variables ``theta``.
    r : array_like, shape (m,), optional
        Residuals at the optimum; required unless ``s2`` is given and ``block`` is None.
    tau : float, keyword-only
        Integrated autocorrelation time of the residuals [residuals], ``> 0`` (1: white;
        :func:`iwan_element.identify.loops.noise.integrated_time`).
    s2 : float, optional, keyword-only
        Residual variance; default ``r @ r / dof``.
    dof : int, optional, keyword-only
        Residual degrees of freedom, default ``max(m - p, 1)``.
    block : int, optional, keyword-only
        Residuals in time order: form the block sandwich with blocks of at least this many
        residuals (0: ``max(20, 4 tau)``). None (default): no sandwich.
    Jp : array_like, shape (q, p), optional, keyword-only
        Jacobian of the reported parameters ``p(theta)``; default: ``theta`` itself.
    cutoff : float, keyword-only
        Relative singular-value threshold of a degenerate direction (default 1e-7).

    Returns
    -------
    Covariance

    Raises
    ------
    ValueError
        Non-finite or mis-shaped ``J``, ``r`` or ``Jp``; ``tau``, ``s2``, ``dof`` out of range;
        neither ``r`` nor ``s2``.
    """
    J = finite_array("J", J, ndim=2)
    m, p = J.shape
    if r is not None:
        r = finite_array("r", r, ndim=1)
        if r.size != m:
            raise ValueError(f"r must have one entry per row of J ({m}), got {r.size}")
    elif s2 is None or block is not None:
        raise ValueError("r (the residuals) is required unless s2 is given and block is None")
    tau = check_scalar("tau", tau, low=0.0, low_open=True)
    dof = max(m - p, 1) if dof is None else check_int("dof", dof, 1)
    s2 = float(r @ r) / dof if s2 is None else check_scalar("s2", s2, low=0.0)
    cutoff = check_scalar("cutoff", cutoff, low=0.0, high=1.0, low_open=True, high_open=True)
    A_inv, null, scale = _scaled_svd(J, cutoff)
    cov = tau * s2 * A_inv
    L, widened = 0, False
    if block is not None:
        cov, L, widened = _sandwich(J, r, A_inv, cov, tau, check_int("block", block, 0))
    if Jp is None:
        Jp_s = np.diag(1.0 / scale)
    else:
        Jp = finite_array("Jp", Jp, ndim=2)
        if Jp.shape[1] != p:
            raise ValueError(f"Jp must have {p} columns (one per column of J), got {Jp.shape[1]}")
        cov = Jp @ cov @ Jp.T
        Jp_s = Jp / scale  # d p / d(scaled theta)
    bad = _degenerate(Jp_s, null)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    se[bad] = math.nan
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    return Covariance(
        covariance=cov,
        stderr=se,
        correlation=corr,
        degenerate=bad,
        s2=s2,
        tau=tau,
        block=int(L),
        widened=widened,
    )
