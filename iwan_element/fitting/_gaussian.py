"""The Gaussian of :func:`~iwan_element.fitting.evidence.laplace_evidence` on its box: the
inverse and log-determinant of a Hessian whose diagonal spans decades, the covariance capped
at the uniform box's spread, the regression of the other parameters on one, and the
Gaussian's mass inside the unit box (``scipy.special.log_ndtr`` one interval at a time,
``scipy.stats.multivariate_normal.cdf`` when correlated).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import log_ndtr
from scipy.stats import multivariate_normal


def _regression(H, free, i):
    """``-H_ff^+ H_fi``: how the parameters ``free`` follow parameter ``i`` at the quadratic's
    optimum, through the pseudo-inverse of the diagonally scaled ``H_ff`` (a direction the
    data do not determine, 1e-9 of the largest, does not follow).
    """
    Hff = H[np.ix_(free, free)]
    dsc = np.sqrt(np.maximum(np.diag(Hff), 1e-300))
    inv = np.linalg.pinv(Hff / np.outer(dsc, dsc), rcond=1e-9, hermitian=True)
    return -(inv @ (H[free, i] / dsc)) / dsc


def _capped(cov, width):
    """``cov`` with each standard deviation at most the uniform box's, ``width / sqrt(12)``
    (a direction the data do not determine has the prior's spread, not the ridge's).
    """
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    cap = np.minimum(sd, np.asarray(width, float) / math.sqrt(12.0))
    f = np.where(sd > 0, cap / np.where(sd > 0, sd, 1.0), 0.0)
    return cov * np.outer(f, f)


def _inverse(H):
    """``(H^-1, ln det H)`` of a symmetric positive definite ``H`` whose diagonal may span
    many decades (the ridge along an undetermined direction next to a well-determined one):
    scaled to a unit diagonal first, then by its eigenvalues (no cut-off, which would drop
    the ridge's direction).
    """
    d = np.sqrt(np.diag(H))
    Hs = H / np.outer(d, d)
    w, V = np.linalg.eigh(Hs)
    w = np.maximum(w, 1e-300)
    inv = (V / w) @ V.T / np.outer(d, d)
    return 0.5 * (inv + inv.T), float(np.sum(np.log(w)) + 2.0 * np.sum(np.log(d)))


def _box_mass(centre, cov) -> float:
    """``ln P(N(centre, cov) in [0, 1]^m)``."""
    m = centre.size
    if m == 0:
        return 0.0
    sd = np.sqrt(np.diag(cov))
    a, b = (0.0 - centre) / sd, (1.0 - centre) / sd
    if m == 1:
        return float(_log_interval(a[0], b[0]))
    corr = cov / np.outer(sd, sd)
    if np.max(np.abs(corr - np.eye(m))) < 1e-3:  # independent: one interval each
        return float(sum(_log_interval(x, y) for x, y in zip(a, b)))
    mvn = multivariate_normal(
        mean=np.zeros(m),
        cov=corr,
        allow_singular=True,
        seed=np.random.default_rng(0),
        abseps=1e-7,
        releps=1e-4,
    )
    p = float(mvn.cdf(b, lower_limit=a))
    if not p > 1e-6:  # near the integrator's resolution: the tightest bound
        return float(min(_log_interval(x, y) for x, y in zip(a, b)))  # P(all) <= min P_i
    return math.log(p)


def _log_interval(a: float, b: float) -> float:
    """``ln (Phi(b) - Phi(a))`` for ``a < b``, accurate in either tail."""
    if a > 0:  # both in the upper tail: use the lower by symmetry
        a, b = -b, -a
    lb, la = float(log_ndtr(b)), float(log_ndtr(a))
    return lb + math.log1p(-math.exp(min(la - lb, 0.0))) if la < lb else -math.inf
