"""Integrals of a likelihood along a line (or a curve) through a fitted model's parameters,
for :func:`iwan_element.fitting.evidence.laplace_evidence` where its Gaussian is not enough
(docs/probabilities.md section 3): the log-likelihood evaluated adaptively on a grid
(:func:`adaptive_line`), each piece between two evaluated points integrated as an
exponential (:func:`exp_pieces`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "line_integral",
    "ridge_integral",
    "adaptive_line",
    "exp_pieces",
    "LINE_STEPS",
    "LINE_DEPTH",
]

#: Steps of the line integral from the bound, as fractions of the box width (geometric,
#: factor sqrt(2)), to which steps of a sixth of the Gaussian's standard deviation around
#: the fitted value are added.
LINE_STEPS = np.geomspace(1e-8, 1.0, 55)
#: The line integral stops where the likelihood has fallen by this many nats.
LINE_DEPTH = 30.0


def line_integral(chi2_at, theta, d, i, lo, hi, tau, chi0, t_fit, sd, rel, knot):
    """``(mean, second moment, ln integral)`` over ``t`` of the likelihood
    ``exp(-(chi2(theta + t d) - chi0) / (2 tau))`` times the moving parameter's prior density
    relative to the box's (``rel``), from the bound (``t = 0``) across the box along ``d``
    (others clipped to the box); ``i``: the moving parameter, ``t_fit`` the fit's place on
    the line, ``sd`` its Gaussian standard deviation, ``knot`` the place of a peak of its
    prior density (NaN: none).

    The likelihood is evaluated at geometric steps from the bound (:data:`LINE_STEPS`; left
    out when the bound is more than 10 ``sd`` away) and at 49 steps over ``t_fit +- 8 sd``,
    stopped :data:`LINE_DEPTH` nats below its top past the fit; the log-likelihood is
    interpolated linearly between them onto a grid that adds geometric steps about the
    prior's peak, where the prior density is evaluated exactly; each piece is integrated as
    an exponential between its ends (exact for an exponential decay).
    """
    w = hi[i] - lo[i]
    near = t_fit < 10.0 * sd
    grid = w * LINE_STEPS if near else np.zeros(0)
    if sd < w:
        grid = np.concatenate([grid, t_fit + sd * np.linspace(-8.0, 8.0, 49)])
    grid = np.unique(np.clip(np.concatenate([[0.0] if near else [], grid]), 0.0, w))

    def loglike(t):
        v = -0.5 * (float(chi2_at(np.clip(theta + t * d, lo, hi))) - chi0) / tau
        # a line that finds a far better likelihood than the fit (a force that jumps with
        # the parameter, a fit stopped on the wrong side of a cliff) does not count it: the
        # explanation is scored at its fit, as its likelihood is reported
        return min(v, 0.0) if math.isfinite(v) else -1e300

    def logw(t):
        return float(rel(np.clip(theta + t * d, lo, hi))[i])

    ts, ll = adaptive_line(loglike, logw, grid, t_fit)
    fine = ts
    if math.isfinite(knot):
        tk = abs(knot - (lo[i] if d[i] > 0 else hi[i]))
        off = w * np.geomspace(1e-7, 1.0, 57)
        fine = np.unique(
            np.concatenate([ts, np.clip(np.concatenate([tk - off, [tk], tk + off]), ts[0], ts[-1])])
        )
    fs = np.interp(fine, ts, ll) + np.array([logw(t) for t in fine])
    return exp_pieces(fine, fs)


#: Every this many points of the line's grid are evaluated first (:func:`adaptive_line`).
LINE_STRIDE = 8
#: A piece of the line is refined while the error its linear log-likelihood may make is
#: above this fraction of the line's integral.
LINE_TOL = 1e-3


def adaptive_line(loglike, logw, grid, t_fit):
    """``(ts, ll)``: the log-likelihood ``loglike(t)`` on the points of ``grid`` (sorted)
    needed to integrate ``exp(ll + logw)`` as well as on the whole grid.

    Every :data:`LINE_STRIDE`-th point (and the one nearest the fit) is evaluated first, in
    order, stopping :data:`LINE_DEPTH` nats below the top past the fit; then a piece between
    two evaluated points is bisected (on the grid's indices) while the error a linear
    log-likelihood may make on it, its mass times ``min(|d ll|, 1) / 2``, is above
    :data:`LINE_TOL` of the integral so far. Where the likelihood is flat or negligible
    (most of a size's geometric steps from zero, the far tail past the fit) the grid's
    points are left out; where it falls, every point is evaluated.
    """
    n = grid.size
    first = set(range(0, n, LINE_STRIDE)) | {n - 1, int(np.argmin(np.abs(grid - t_fit)))}
    vals, top = {}, -math.inf
    for j in sorted(first):
        vals[j] = loglike(grid[j])
        top = max(top, vals[j])
        if grid[j] > t_fit and vals[j] < top - LINE_DEPTH:
            break
    while True:
        idx = sorted(vals)
        ts, ll = grid[idx], np.array([vals[j] for j in idx])
        f = ll + np.array([logw(t) for t in ts])
        total = math.exp(exp_pieces(ts, f)[2] - f.max()) if ts.size > 1 else 0.0
        new = []
        for a, b, fa, fb, la, lb in zip(idx[:-1], idx[1:], f[:-1], f[1:], ll[:-1], ll[1:]):
            if b - a < 2:
                continue
            mass = (grid[b] - grid[a]) * math.exp(max(fa, fb) - f.max())
            if mass * 0.5 * min(abs(lb - la), 1.0) > LINE_TOL * total:
                new.append((a + b) // 2)
        if not new:
            return ts, ll
        for j in new:
            vals[j] = loglike(grid[j])


def exp_pieces(ts, fs):
    """``(mean, second moment, ln integral)`` of ``exp(f(t))`` given at ``ts``, each piece an
    exponential between its ends.
    """
    top = fs.max()
    total = m1 = m2 = 0.0
    for a, b, fa, fb in zip(ts[:-1], ts[1:], fs[:-1] - top, fs[1:] - top):
        h = b - a
        s = (fb - fa) / h  # log slope of the piece
        ea, eb = math.exp(fa), math.exp(fb)
        if abs(s * h) < 1e-6:  # flat: the trapezoid
            i0, i1, i2 = (
                h * 0.5 * (ea + eb),
                h * 0.5 * (a * ea + b * eb),
                h * 0.5 * (a * a * ea + b * b * eb),
            )
        else:  # int exp(fa + s (t - a)) t^j dt, j = 0, 1, 2
            i0 = (eb - ea) / s
            i1 = (b * eb - a * ea) / s - i0 / s
            i2 = (b * b * eb - a * a * ea) / s - 2.0 * i1 / s
        total += i0
        m1 += i1
        m2 += i2
    if not total > 0:
        return 0.0, 0.0, -math.inf
    return m1 / total, m2 / total, top + math.log(total)


def ridge_integral(chi2_at, curve, s_fit, s_lo, s_hi, lo, hi, tau, chi0, rel, width):
    """``(mean, second moment, ln integral)`` over ``s`` in ``[s_lo, s_hi]`` of
    ``exp(-(chi2(curve(s)) - chi0) / (2 tau))`` times the density ratio of the curve's
    parametrisation and the prior's along it, relative to the fit's (``s_fit``):
    ``curve(s) -> (theta, ln jacobian)``, ``rel(theta)``: each parameter's log prior
    density relative to its box's, ``width``: the box width of ``s``'s parameter (the
    integral includes its uniform prior, ``1 / width``). A point of the curve outside the
    box ``[lo, hi]`` has no prior mass. The grid: geometric steps either side of the fit
    (:data:`LINE_STEPS` of ``width``) and 33 even steps over the range, evaluated by
    :func:`adaptive_line`.
    """
    th0, w0 = curve(s_fit)
    r0 = float(np.sum(rel(th0)))

    def point(s):
        th, w = curve(s)
        inside = np.all(th >= lo) and np.all(th <= hi)
        return th, (w - w0 + float(np.sum(rel(th))) - r0) if inside else -1e300

    def loglike(s):
        th, w = point(s)
        if w <= -1e300:
            return -1e300
        v = -0.5 * (float(chi2_at(th)) - chi0) / tau
        return min(v, 0.0) if math.isfinite(v) else -1e300

    grid = np.concatenate(
        [
            s_fit - width * LINE_STEPS,
            s_fit + width * LINE_STEPS,
            np.linspace(s_lo, s_hi, 33),
            [s_fit],
        ]
    )
    grid = np.unique(np.clip(grid, s_lo, s_hi))
    ts, ll = adaptive_line(loglike, lambda s: point(s)[1], grid, s_fit)
    # the density ratio on every point of the grid (it costs no evaluation of the model),
    # the log-likelihood interpolated between the points evaluated
    fine = grid[(grid >= ts[0]) & (grid <= ts[-1])]
    f = np.interp(fine, ts, ll) + np.array([point(s)[1] for s in fine])
    mean, second, log_int = exp_pieces(fine, f)
    return mean, second, log_int - math.log(width)
