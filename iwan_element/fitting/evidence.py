"""The evidence (marginal likelihood) of a fitted least-squares model, by the Laplace
approximation on a box prior, and posterior model probabilities from evidences
(docs/probabilities.md; docs/fitting.md section 9).

A model with parameters ``theta`` (``k`` of them), noise-normalised residual ``r(theta)``
(residual over the noise standard deviation) and ``chi2 = |r|^2`` has the likelihood
``L = exp(-chi2 / (2 tau))`` on ``n / tau`` effective independent samples (``tau``: the
noise's correlation time in samples), up to a constant that is the same for every model of
the same data. With a uniform prior on the box ``lower <= theta <= upper`` its evidence is

``Z = (1 / V) int_box L(theta) dtheta``,  ``V`` the box's volume.

The Laplace approximation (MacKay 2003, *Information Theory, Inference, and Learning
Algorithms*, ch. 27-28; Beck and Yuen 2004, J. Eng. Mech. 130:192-203) expands ``chi2``
to second order about the fitted ``theta*`` with the Gauss-Newton Hessian ``J^T J``
(``J = dr/dtheta``) **and, for the parameters fitted on a bound, its gradient** ``2 J^T r``:
there the fitted value is a constrained optimum whose gradient does not vanish, and the
quadratic's own optimum lies outside the box. The Gaussian is then integrated over the
box (a truncated multivariate normal, :func:`scipy.stats.multivariate_normal.cdf` over the
parameters whose Gaussian reaches a bound), so an effect fitted at zero size (its parameter at the
bound) gets the half-Gaussian (or less) it has, not a whole one. For a model linear in ``theta``
this is exact (tests/test_evidence.py checks it against the closed form and a quadrature). A
direction the data do not determine (a singular ``J^T J``) integrates to the box's width
along it: the Occam factor of a parameter the data say nothing about is 1.

What it does not do: a likelihood that is not quadratic over its posterior's width (a force
that changes only to second order in a parameter near its bound, a posterior with two
modes). :mod:`iwan_element.diagnose.nested` checks such cases by nested sampling.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base.validation import check_scalar, finite_array
from ._gaussian import _box_mass, _capped, _inverse, _regression
from ._lines import line_integral, ridge_integral

__all__ = ["Evidence", "Ridge", "laplace_evidence", "posterior_probabilities"]

#: Ridge added to the box-scaled Hessian (units: box widths^-2): a direction the data do not
#: determine is a Gaussian of 1000 box widths, whose box mass is then computed exactly.
RIDGE = 1e-6
#: A parameter whose Gaussian is farther than this many standard deviations from both ends
#: of its box is not truncated (its box mass is 1 to 1e-9).
REACH = 6.0


@dataclass(frozen=True, eq=False)
class Evidence:
    """Result of :func:`laplace_evidence`.

    Attributes
    ----------
    log_evidence : float
        ``ln Z`` [-], without the constant ``-(n/2) ln(2 pi sigma^2)`` common to every model
        of the same data (differences between models are what count).
    log_likelihood : float
        ``-chi2 / (2 tau)`` at the fitted parameters.
    log_occam : float
        ``log_evidence - log_likelihood``: the Occam factor, the fraction of the prior box
        the data allow, with the gain of the quadratic's optimum beyond a bound.
    covariance : ndarray, shape (k, k)
        Posterior covariance of ``theta`` in the Gaussian approximation, ``(J^T J / tau)^-1``,
        each standard deviation at most the uniform box's (``width / sqrt(12)``, along a
        direction the data do not determine); a parameter integrated along its line has
        that line's variance (and no correlation).
    truncated : tuple of int
        Parameters whose Gaussian reaches a bound of the box (integrated as truncated).
    """

    log_evidence: float
    log_likelihood: float
    log_occam: float
    covariance: np.ndarray
    truncated: tuple


def laplace_evidence(
    J,
    r,
    theta,
    lower,
    upper,
    *,
    tau: float = 1.0,
    chi2_at=None,
    log_prior=None,
    prior_knots=None,
    switched_off=None,
    lines=None,
    ridge=None,
    open_ends=None,
) -> Evidence:
    """Laplace-approximated evidence of a least-squares model on a uniform box prior.

    Parameters
    ----------
    J : array_like, shape (n, k)
        Jacobian of the noise-normalised residual ``r`` in ``theta`` at the fit.
    r : array_like, shape (n,)
        Noise-normalised residual at the fit (residual over the noise std [-]).
    theta : array_like, shape (k,)
        Fitted parameters, inside the box.
    lower, upper : array_like, shape (k,)
        The prior box (finite, ``upper > lower``), in the units of ``theta``.
    tau : float, keyword-only
        Correlation time of the residual [samples], ``>= 1``: the likelihood is
        ``exp(-chi2 / (2 tau))``.
    chi2_at : callable, optional, keyword-only
        ``chi2_at(theta) -> chi2`` (the model's noise-normalised chi-square). When given,
        each parameter fitted **at a bound** of the box is integrated numerically along its
        profile line instead (:func:`._lines.line_integral`): the likelihood of an effect fitted at
        zero size is often not a Gaussian in its parameter (a force that changes only to
        second order in it, a Jacobian column that vanishes there), where the Gaussian
        would call the parameter undetermined and give it no Occam penalty. "Near a bound":
        within :data:`NEAR` of the box's width, or within 3 Gaussian standard deviations
        when these are below a third of the box (a parameter the data hardly determine is
        integrated by the Gaussian over the box).
    log_prior : callable, optional, keyword-only
        ``log_prior(theta) -> ndarray (k,)``: each parameter's log prior density (the prior
        is the product of independent ones over the box, each normalised over its range).
        Default: uniform. The density is taken at the fitted value for the Laplace part
        (it must vary slowly over the posterior's width there) and along the line for a
        parameter near a bound.
    prior_knots : array_like, shape (k,), optional, keyword-only
        Where each parameter's prior density peaks (NaN: nowhere), e.g. a log-uniform size
        prior about the "no effect" value: a parameter whose Gaussian reaches its knot
        (within 5 standard deviations) is integrated along its line too, with the grid
        refined about the knot.
    switched_off : dict, optional, keyword-only
        ``{i: (dependents, values)}``: parameters ``dependents`` (indices) that do nothing
        when parameter ``i`` (a size with a knot) sits at its knot (a clearance when the
        spring behind it has zero stiffness): the data then say nothing about them, and
        ``i``'s line integral is averaged over ``values`` (an array, one row per point of
        their prior, e.g. its quantiles) instead of taken at their fitted values, their
        Gaussian left out. Without it the evidence of an absent effect with such
        parameters is under-counted (tests/test_evidence.py).
    lines : array_like of bool, shape (k,), optional, keyword-only
        Which parameters may be integrated along their line (default all); the others are
        always left to the Gaussian (e.g. nuisances on boxes far wider than the data's
        range, where "near a bound" means nothing).
    ridge : Ridge, optional, keyword-only
        A curve through the fit along which the model does not change (with ``chi2_at``):
        the likelihood is then a ridge, not a peak, and its Gaussian depends on where along
        it the fit stopped (a singular Hessian: the box's width; at a kink where the ridge
        ends: a narrow peak). The evidence is the others' (Gaussian and lines) at the fit
        times the integral along the curve (:func:`_along_ridge`).
    open_ends : array_like of bool, shape (k,), optional, keyword-only
        Parameters whose Gaussian is neither truncated by their box nor moved by their
        gradient on a bound (default none): the cross-section of a ridge that goes on
        inside the box where it meets the box at the fit (:func:`_along_ridge`).

    Returns
    -------
    Evidence

    Raises
    ------
    ValueError
        Shapes that do not match, a box that is not finite or empty, ``theta`` outside it.
    """
    J, r, theta, lo, hi = _checked(J, r, theta, lower, upper)
    k, width = theta.size, hi - lo
    tau = check_scalar("tau", tau, low=1.0)
    log_like = -0.5 * float(r @ r) / tau
    if k == 0:
        return Evidence(log_like, log_like, 0.0, np.zeros((0, 0)), ())
    if ridge is not None and chi2_at is not None:
        return _along_ridge(
            J, r, theta, lo, hi, tau, chi2_at, log_prior, prior_knots, switched_off, lines, ridge
        )
    # each parameter's log prior density relative to the uniform box's, as a function
    rel = (
        (lambda th: np.zeros(k))
        if log_prior is None
        else (lambda th: np.asarray(log_prior(th), float) + np.log(hi - lo))
    )
    Ju = J * width / math.sqrt(tau)  # box units: u = (theta - lower) / width
    H = Ju.T @ Ju + RIDGE * np.eye(k)
    g = Ju.T @ (r / math.sqrt(tau))  # chi2/(2 tau) ~ c + g.d + d.H.d / 2
    # the gradient counts only where the fit sits on a bound (a constrained optimum); inside,
    # it is the fit's stopping tolerance and, along a direction the data hardly determine,
    # would move the quadratic's optimum by box widths for nothing
    opened = np.zeros(k, bool) if open_ends is None else np.asarray(open_ends, bool).reshape(k)
    on = ((theta <= lo + ON_BOUND * width) | (theta >= hi - ON_BOUND * width)) & ~opened
    g = np.where(on, g, 0.0)
    Hinv, logdet = _inverse(H)
    shift = -Hinv @ g  # the quadratic's optimum, from the fit
    gain = 0.5 * float(g @ Hinv @ g)  # its log-likelihood above the fit's
    centre = (theta - lo) / width + shift
    sd = np.sqrt(np.maximum(np.diag(Hinv), 1e-300))
    reach = (
        (np.minimum(centre, 1.0 - centre) < REACH * sd) | (centre < 0) | (centre > 1)
    ) & ~opened
    idx = np.flatnonzero(reach)
    log_mass = _box_mass(centre[idx], Hinv[np.ix_(idx, idx)])
    log_gauss = 0.5 * k * math.log(2.0 * math.pi) - 0.5 * logdet
    log_occam = gain + log_gauss + log_mass + float(np.sum(rel(theta)))
    cov = _capped(Hinv, 1.0) * np.outer(width, width)
    if chi2_at is not None:
        near, knots = _near_bound(theta, lo, hi, sd, prior_knots, lines)
        if near.size:
            return _with_lines(
                J,
                r,
                theta,
                lo,
                hi,
                tau,
                near,
                chi2_at,
                log_like,
                sd * width,
                rel,
                knots,
                dict(switched_off or {}),
                opened,
            )
    return Evidence(log_like + log_occam, log_like, log_occam, cov, tuple(int(i) for i in idx))


def _checked(J, r, theta, lower, upper):
    """:func:`laplace_evidence`'s arrays checked: ``(J, r, theta, lower, upper)``."""
    r = finite_array("r", r, ndim=1)
    theta = finite_array("theta", theta, ndim=1, min_size=0)
    k = theta.size
    J = finite_array("J", J, ndim=None, min_size=0).reshape(r.size, k)
    lo = finite_array("lower", lower, ndim=1, min_size=0)
    hi = finite_array("upper", upper, ndim=1, min_size=0)
    if lo.size != k or hi.size != k or not np.all(hi > lo):
        raise ValueError("lower and upper must have one finite entry per parameter, upper > lower")
    width = hi - lo
    if np.any(theta < lo - 1e-9 * width) or np.any(theta > hi + 1e-9 * width):
        raise ValueError("theta must lie inside the box [lower, upper]")
    return J, r, theta, lo, hi


def _near_bound(theta, lo, hi, sd, prior_knots, lines):
    """``(near, knots)``: the parameters :func:`laplace_evidence` integrates along their lines
    (near a bound, or whose Gaussian reaches their prior's knot; ``sd`` in box widths), and
    the knots (NaN: none).
    """
    k, width = theta.size, hi - lo
    dist = np.minimum(theta - lo, hi - theta) / width
    knots = np.full(k, np.nan) if prior_knots is None else np.asarray(prior_knots, float).reshape(k)
    spike = np.isfinite(knots) & (np.abs(theta - np.nan_to_num(knots)) < 5.0 * sd * width)
    # a parameter the data hardly determine (its Gaussian wider than a third of the box)
    # is left to the Gaussian, which integrates it over the box
    ok = np.ones(k, bool) if lines is None else np.asarray(lines, bool).reshape(k)
    near = np.flatnonzero(ok & ((dist < NEAR) | ((dist < 3.0 * sd) & (sd < 0.3)) | spike))
    return near, knots


#: A parameter this close to a bound (fraction of the box width) is integrated along its line.
NEAR = 1e-3
#: A parameter this close to a bound (fraction of the box width) is fitted on it (an active
#: bound of the bounded least squares): only there does the gradient count.
ON_BOUND = 1e-6


def _with_lines(
    J, r, theta, lo, hi, tau, at, chi2_at, log_like, sd, rel, knots, groups, opened
) -> Evidence:
    """The evidence with the parameters ``at`` (near a bound) integrated along their profile
    lines from that bound across the box, and the others by the Laplace approximation
    (:func:`laplace_evidence`); ``sd``: the Gaussian's standard deviations, ``rel``: the
    log prior densities relative to the box's, ``groups``: ``{size: (dependents, values)}``
    (see :func:`laplace_evidence`'s ``switched_off``).
    """
    k = theta.size
    off = {
        i: g
        for i, g in groups.items()
        if i in at
        and math.isfinite(knots[i])
        and abs(theta[i] - knots[i]) <= NEAR * (hi[i] - lo[i])
    }
    deps = sorted({j for dep, _ in off.values() for j in dep} - set(at))
    free = np.setdiff1d(np.arange(k), np.concatenate([at, deps]).astype(int))
    inner = laplace_evidence(
        J[:, free], r, theta[free], lo[free], hi[free], tau=tau, open_ends=opened[free]
    )
    H = J.T @ J
    chi0 = float(r @ r)
    log_occam = inner.log_occam + float(np.sum(rel(theta)[free]))
    cov = np.zeros((k, k))
    cov[np.ix_(free, free)] = inner.covariance
    for j in deps:  # their prior's spread (the data say nothing)
        cov[j, j] = (hi[j] - lo[j]) ** 2 / 12.0
    for i in at:
        d = np.zeros(k)
        d[i] = 1.0 if theta[i] - lo[i] <= hi[i] - theta[i] else -1.0
        if free.size:  # the others follow their regression on theta_i,
            d[free] = _regression(H, free, i) * d[i]  # along determined directions
        bound = lo[i] if d[i] > 0 else hi[i]
        t_fit = abs(theta[i] - bound)
        origin = theta - t_fit * d  # the line through the fit, from the bound
        dep, values = off.get(i, ((), np.zeros((1, 0))))
        logs, moments = [], []
        for vals in values:  # the switched-off parameters over their prior
            o = origin.copy()
            o[list(dep)] = vals
            mean, second, log_int = line_integral(
                chi2_at, o, d, i, lo, hi, tau, chi0, t_fit, sd[i], rel, knots[i]
            )
            logs.append(log_int)
            moments.append((mean, second))
        top = max(logs)
        wts = np.exp(np.array(logs) - top)
        log_occam += top + math.log(wts.mean()) - math.log(hi[i] - lo[i])
        mean, second = (
            np.average(np.array(moments), axis=0, weights=wts) if wts.sum() > 0 else moments[0]
        )
        cov[i, i] = min(max(second - mean * mean, 0.0), (hi[i] - lo[i]) ** 2 / 12.0)
    return Evidence(
        log_like + log_occam,
        log_like,
        log_occam,
        cov,
        tuple(int(i) for i in inner.truncated) + tuple(int(i) for i in at),
    )


@dataclass(frozen=True)
class Ridge:
    """A curve through a fit along which the model does not change (for
    :func:`laplace_evidence`).

    Attributes
    ----------
    index : int
        The parameter that moves along the curve (its value is the curve's coordinate).
    curve : callable
        ``curve(s) -> (theta, ln jacobian)``: the parameters where ``theta[index] = s``, and
        the log of ``|det d(others) / d(invariants)|`` there (the density of the others'
        box measure per unit of what the data determine; constants left out).
    lower, upper : float
        The range of ``s`` over which the curve is defined.
    """

    index: int
    curve: object
    lower: float
    upper: float


def _along_ridge(
    J, r, theta, lo, hi, tau, chi2_at, log_prior, knots, switched_off, lines, ridge
) -> Evidence:
    """:func:`laplace_evidence` with parameter ``ridge.index`` held at the fit, times the
    integral of the likelihood along ``ridge.curve`` (:func:`._lines.ridge_integral`): ``Z =
    int ds Z_others(s)``, ``Z_others(s)`` the others' evidence at ``s``, which is the fit's
    times the curve's density ratio (the likelihood the same along the ridge). The
    covariance of the moving parameter is the curve's spread along its tangent.
    """
    k, i = theta.size, int(ridge.index)
    keep = np.array([j for j in range(k) if j != i])
    pos = {int(j): n for n, j in enumerate(keep)}

    def full(th_sub):
        th = theta.copy()
        th[keep] = th_sub
        return th

    groups = {
        pos[a]: (tuple(pos[j] for j in dep), vals)
        for a, (dep, vals) in (switched_off or {}).items()
        if a != i and i not in dep
    }
    width = hi[i] - lo[i]
    eps = 1e-6 * width
    tangent = (ridge.curve(theta[i] + eps)[0] - ridge.curve(theta[i] - eps)[0]) / (2 * eps)
    # the parameters that move along the ridge are not truncated by their box at the fit
    # (where the ridge meets it, it goes on inside) nor integrated along a line from it:
    # their box is the ridge integral's
    moving = (np.abs(tangent) > 1e-9 * (hi - lo) / width)[keep]
    ok = np.ones(k - 1, bool) if lines is None else np.asarray(lines, bool)[keep]
    sub = laplace_evidence(
        J[:, keep],
        r,
        theta[keep],
        lo[keep],
        hi[keep],
        tau=tau,
        open_ends=moving,
        chi2_at=lambda th_sub: chi2_at(full(th_sub)),
        log_prior=None
        if log_prior is None
        else (lambda th_sub: np.asarray(log_prior(full(th_sub)), float)[keep]),
        prior_knots=None if knots is None else np.asarray(knots, float)[keep],
        switched_off=groups,
        lines=ok & ~moving,
    )
    rel = (
        (lambda th: np.zeros(k))
        if log_prior is None
        else (lambda th: np.asarray(log_prior(th), float) + np.log(hi - lo))
    )
    s_lo, s_hi = max(ridge.lower, lo[i]), min(ridge.upper, hi[i])
    mean, second, log_int = ridge_integral(
        chi2_at, ridge.curve, theta[i], s_lo, s_hi, lo, hi, tau, float(r @ r), rel, width
    )
    log_occam = sub.log_occam + log_int + float(rel(theta)[i])
    cov = np.zeros((k, k))
    cov[np.ix_(keep, keep)] = sub.covariance
    cov += min(max(second - mean * mean, 0.0), width**2 / 12.0) * np.outer(tangent, tangent)
    log_like = sub.log_likelihood
    return Evidence(
        log_like + log_occam,
        log_like,
        log_occam,
        cov,
        tuple(int(keep[j]) for j in sub.truncated) + (i,),
    )


def posterior_probabilities(log_evidence: dict, log_prior: dict | None = None) -> dict:
    """Posterior probabilities of models from their log evidences and log prior weights.

    Parameters
    ----------
    log_evidence : dict
        ``{model key: ln Z}`` (same data, same constant left out).
    log_prior : dict, optional
        ``{model key: ln prior weight}`` (normalised here); default: equal.

    Returns
    -------
    dict
        ``{model key: probability}``, summing to 1, in the order of ``log_evidence``.
    """
    if not log_evidence:
        raise ValueError("log_evidence must hold at least one model")
    keys = list(log_evidence)
    lp = np.array(
        [log_evidence[k] + (0.0 if log_prior is None else log_prior[k]) for k in keys], float
    )
    if not np.any(np.isfinite(lp)):
        raise ValueError("no model has a finite log evidence")
    lp = np.where(np.isfinite(lp), lp, -np.inf)
    w = np.exp(lp - lp.max())
    w /= w.sum()
    return {k: float(p) for k, p in zip(keys, w)}
