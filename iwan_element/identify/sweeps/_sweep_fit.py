"""The receptance fit of :func:`~iwan_element.identify.sweeps.sweep.sweep_curve`.

The modal constant ``c``, the residual ``B`` of the other modes and smooth curves
``w_r(X)**2``, ``ln zeta_r(X)`` fitted to every point of every sweep at once (weighted least
squares on the complex receptance), then each kept point inverted with the fitted ``c`` and
``B`` and the inversions averaged in bins of ``ln X`` with standard errors that carry the
uncertainty of ``c`` and ``B`` (``docs/equations.md`` section 8.2; the algorithm in
``docs/sweeps.md``).
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy import optimize

from ...fitting import covariance
from .stepped_sine import _fit_sdof

log = logging.getLogger(__name__)


def _groups(lx, n_bins):
    """Bin index of each ``ln X``: clusters split at gaps wider than 0.1, each cluster cut
    into equal pieces no narrower than the whole range / ``n_bins``.
    """
    order = np.argsort(lx)
    srt = lx[order]
    width = max(np.ptp(lx) / n_bins, 1e-9)
    cuts = np.concatenate([[0], np.flatnonzero(np.diff(srt) > 0.1) + 1, [srt.size]])
    out = np.empty(lx.size, int)
    g = 0
    for a, b in zip(cuts[:-1], cuts[1:]):
        seg = srt[a:b]
        k = max(1, int(math.ceil((seg[-1] - seg[0]) / width - 1e-9)))
        piece = np.minimum(((seg - seg[0]) / max(seg[-1] - seg[0], 1e-300) * k).astype(int), k - 1)
        out[order[a:b]] = g + piece
        g += k
    return out, g


class _Model:
    """Receptance of one nonlinear mode with smooth ``w_r(X)**2``, ``ln zeta_r(X)``.

    Parameter vector: ``ln c``, ``B w0**2 / c``, then ``deg + 1`` coefficients of
    ``w_r**2 / w0**2 - 1`` and ``deg + 1`` of ``ln zeta_r``, polynomials in
    ``s = (ln X - mid) / half`` (``s`` in [-1, 1] over the data).
    """

    def __init__(self, W, X, H, w0, deg, residual):
        self.W, self.H, self.w0, self.deg, self.residual = W, H, w0, deg, residual
        lx = np.log(X)
        self.mid, self.half = 0.5 * (lx.max() + lx.min()), max(0.5 * np.ptp(lx), 1e-3)
        self.V = np.vander((lx - self.mid) / self.half, deg + 1, increasing=True)
        self.scale = np.abs(H)

    def curves(self, p, V=None):
        V = self.V if V is None else V
        n = self.deg + 1
        wr2 = self.w0**2 * (1.0 + V @ p[2 : 2 + n])
        zeta = np.exp(np.clip(V @ p[2 + n :], -50, 5))
        return wr2, zeta

    def receptance(self, p):
        c = math.exp(p[0])
        wr2, zeta = self.curves(p)
        wr = np.sqrt(np.abs(wr2))
        return c / (wr2 - self.W**2 + 2j * zeta * wr * self.W) + p[1] * c / self.w0**2

    def resid(self, p):
        if not self.residual:
            p = np.concatenate([p[:1], [0.0], p[1:]])
        r = (self.receptance(p) - self.H) / self.scale
        return np.concatenate([r.real, r.imag])

    def full(self, x):
        return x if self.residual else np.concatenate([x[:1], [0.0], x[1:]])


def _start(W, X, H, sweeps):
    """Linear single-mode fit of the sweep with the smallest peak response (nearly linear)."""
    i = min(sweeps, key=lambda i: float(np.max(X[i])))
    k = int(np.argmax(np.abs(H[i])))
    wr, zeta, A, B, _, _ = _fit_sdof(W[i], H[i], W[i][k], 1e-3)
    return wr, min(max(zeta, 1e-5), 0.2), abs(A), float(B.real)


def _fit(W, X, H, sweeps, deg, residual):
    """Least-squares fit of ``c``, ``B`` and the smooth curves; returns (model, x, cov, rms)."""
    wr0, z0, c0, B0 = _start(W, X, H, sweeps)
    m = _Model(W, X, H, wr0, deg, residual)
    n = deg + 1
    x0 = np.concatenate(
        [
            [math.log(c0)],
            [B0 * wr0**2 / c0] if residual else [],
            np.zeros(n),
            [math.log(z0)],
            np.zeros(n - 1),
        ]
    )
    sol = optimize.least_squares(
        m.resid, x0, method="lm", x_scale="jac", xtol=1e-12, ftol=1e-12, max_nfev=2000 * x0.size
    )
    dof = max(2 * W.size - x0.size, 1)
    rms = math.sqrt(2.0 * sol.cost / dof)
    J = sol.jac
    cov = covariance(J, s2=rms**2).covariance  # docs/fitting.md section 1
    log.debug("sweep fit: %s, rms relative error %.3g", sol.message, rms)
    return m, m.full(sol.x), cov, rms, bool(sol.success)


def _invert(W, H, c, B):
    """Natural frequency [rad/s] and damping ratio of each point (single-mode inversion)."""
    G = c / (H - B)
    wr = np.sqrt(np.maximum(W**2 + G.real, 1e-300))
    return wr, G.imag / (2.0 * wr * W)


def _point_std(W, H, c, B, rel):
    """Std of each point's w_r and zeta from a relative receptance error ``rel`` per component."""
    G = c / (H - B)
    wr = np.sqrt(np.maximum(W**2 + G.real, 1e-300))
    dG = np.abs(G) * rel * np.abs(H) / np.abs(H - B)
    return dG / (2.0 * wr), dG / (2.0 * wr * W)


def _bin_means(y, s, groups, n_bins):
    """Inverse-variance mean per bin, its propagated std and its observed-scatter std."""
    out = np.full((n_bins, 3), np.nan)
    for b in range(n_bins):
        m = groups == b
        if m.sum() < 2:
            continue
        w = 1.0 / s[m] ** 2
        mean = float(np.sum(w * y[m]) / w.sum())
        obs = math.sqrt(float(np.sum(w * (y[m] - mean) ** 2) / w.sum()) / (m.sum() - 1))
        out[b] = mean, math.sqrt(1.0 / w.sum()), obs
    return out


def _binned(W, F, H, keep, c, B, cov_cB, rel, n_bins):
    """Bin the kept points' inversions in ln X; standard errors with c, B uncertainty.

    ``X = |H - B| F`` is the displacement amplitude of the mode itself (the residual of the
    other modes taken out).
    """
    W, H = W[keep], H[keep]
    X = np.abs(H - B) * F[keep]
    groups, n_bins = _groups(np.log(X), n_bins)
    s_wr, s_z = _point_std(W, H, c, B, rel)

    def means(cc, bb):
        wr, z = _invert(W, H, cc, bb)
        return _bin_means(wr, s_wr, groups, n_bins), _bin_means(z, s_z, groups, n_bins)

    (mw, mz) = means(c, B)
    lam, vec = np.linalg.eigh(cov_cB)
    sys_w, sys_z = np.zeros(n_bins), np.zeros(n_bins)
    for k in range(lam.size):
        d = math.sqrt(max(lam[k], 0.0)) * vec[:, k]
        pw, pz = means(c + d[0], B + (d[1] if d.size > 1 else 0.0))
        sys_w += (pw[:, 0] - mw[:, 0]) ** 2
        sys_z += (pz[:, 0] - mz[:, 0]) ** 2
    ok = np.isfinite(mw[:, 0])
    amp = np.array([math.exp(np.mean(np.log(X[groups == b]))) for b in np.flatnonzero(ok)])
    sw = np.sqrt(np.maximum(mw[ok, 1], mw[ok, 2]) ** 2 + sys_w[ok])
    sz = np.sqrt(np.maximum(mz[ok, 1], mz[ok, 2]) ** 2 + sys_z[ok])
    excess = float(np.median(np.concatenate([mw[ok, 2] / mw[ok, 1], mz[ok, 2] / mz[ok, 1]])))
    return amp, mw[ok, 0], mz[ok, 0], sw, sz, excess


def _identify(W, H, F, sweeps, deg, residual, frac, bins):
    """Fit ``c`` and ``B``, invert the kept points and bin them (see the module docstring)."""
    scale = float(np.max(np.abs(H)))  # fit in units of the largest receptance
    H = H / scale
    X = np.abs(H) * F * scale
    warns = []
    if deg < 1:
        deg = 1
        warns.append("one sweep at one amplitude: the amplitude dependence is not identified")
    m, x, cov, rms, ok = _fit(W, X, H, sweeps, deg, residual)
    c, B = math.exp(x[0]), x[1] * math.exp(x[0]) / m.w0**2
    cov_cB = _cov_cB(x, cov, m.w0, residual)
    keep = np.zeros(W.size, bool)
    for i in sweeps:
        keep[i] = np.abs(H[i]) >= frac * np.max(np.abs(H[i]))
    if keep.sum() < 3:
        steps = [float(np.median(np.diff(np.sort(W[i])))) / (2 * math.pi) for i in sweeps]
        raise ValueError(
            f"peak_fraction: only {int(keep.sum())} point(s) of the sweeps lie at or above "
            f"{frac:g} x their sweep's peak |X/F|, and at least 3 are needed to read a "
            f"frequency and a damping ratio: the frequency steps (median {min(steps):.3g} Hz) "
            "are coarse against the resonance's width; sweep more finely near the peak or "
            "lower peak_fraction"
        )
    n_bins = int(np.clip(round(keep.sum() / 8), 3, 12)) if bins is None else bins
    amp, wr, z, sw, sz, excess = _binned(W, F * scale, H, keep, c, B, cov_cB, rms, n_bins)
    log.debug("bin scatter / propagated error: median %.3g", excess)
    warns += _warnings(ok, rms, z, amp)
    Xk = np.abs(H[keep] - B) * F[keep] * scale
    return {
        "curve": (amp, wr, z, sw, sz),
        "c": c * scale,
        "B": B * scale,
        "keep": keep,
        "span": (float(Xk.min()), float(Xk.max())),
        "n_bins": n_bins,
        "rms": rms,
        "deg": deg,
        "warnings": tuple(warns),
    }


def _cov_cB(x, cov, w0, residual):
    """Covariance of (c, B) from that of (ln c, B w0**2 / c)."""
    c = math.exp(x[0])
    if not residual:
        return np.array([[c * c * cov[0, 0]]])
    Jt = np.array([[c, 0.0], [x[1] * c / w0**2, c / w0**2]])
    return Jt @ cov[:2, :2] @ Jt.T


def _warnings(ok, rms, z, amp):
    warns = []
    if not ok:
        warns.append("the fit of the modal constant did not converge")
    if rms > 0.1:
        warns.append(
            f"the single nonlinear mode fits the sweeps to only {100 * rms:.2g} % rms "
            "(another mode nearby, or not a drive-point measurement?)"
        )
    if np.any(z <= 0):
        warns.append("some bins have a damping ratio <= 0 (noise or a wrong phase reference)")
    if amp.size < 3:
        warns.append(f"only {amp.size} amplitude bin(s)")
    return warns
