"""Damped sinusoids in multichannel records: subspace poles, stabilisation, least squares.

The numerical core of :func:`~iwan_element.identify.free_decay.free_decay_modes`
(``docs/modal_targets.md`` sections 2-4).

* :func:`subspace_poles`: the poles of a multichannel free decay at every model order from
  one SVD of its block Hankel matrix and the shift invariance of the signal subspace
  (LS-ESPRIT: R. Roy, T. Kailath, IEEE Trans. ASSP 37:984-995, 1989; in structural dynamics
  the eigensystem realization algorithm on free-decay data, J.-N. Juang, R. S. Pappa,
  J. Guidance 8:620-627, 1985; the matrix pencil, Y. Hua, T. K. Sarkar, IEEE Trans. ASSP
  38:814-824, 1990, is the same estimate up to its weighting).
* :func:`stable_poles`: the stabilisation check. A pole is physical when it reappears,
  within a tolerance in frequency and damping, at every order of a run of consecutive
  orders up to the highest; numerical poles (noise, model-order surplus) wander.
* :func:`fit_sinusoids`: Gauss-Newton least squares of ``y_j(tau) = Re(sum_i C_ij
  exp(s_i tau))`` for all poles and complex amplitudes at once (started at the subspace
  estimate), with the parameter covariance for noise of known correlation (band-passed,
  decimated white noise): ``A^-1 J^T Sigma J A^-1``, ``A = J^T J``, ``Sigma`` built from the
  noise autocorrelation ``rho(k)`` of each channel (the sandwich form for correlated errors,
  G. A. F. Seber, C. J. Wild, *Nonlinear Regression*, Wiley 1989, section 2.1.4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import optimize, signal

__all__ = ["subspace_poles", "stable_poles", "fit_sinusoids", "SinusoidFit", "basis", "amplitudes"]


def _hankel(y, rows):
    """Block Hankel matrix of ``y`` (m, N): ``rows`` block rows of m channels each."""
    m, n = y.shape
    k = n - rows + 1
    win = np.lib.stride_tricks.sliding_window_view(y, k, axis=1)  # (m, rows, k)
    return np.ascontiguousarray(win.transpose(1, 0, 2)).reshape(rows * m, k)


def subspace_poles(y, dt, orders, *, rows=None) -> dict[int, NDArray[np.complex128]]:
    """Continuous-time poles of the multichannel decay ``y`` at each model order.

    Parameters
    ----------
    y : ndarray, shape (m, N)
        Channels (weighted to comparable noise), uniformly sampled at ``dt`` [s].
    dt : float
        Sample interval [s].
    orders : sequence of int
        Model orders (number of poles, conjugates counted), each <= ``rows * m - m``.
    rows : int, optional
        Block rows of the Hankel matrix; default ``min(N // 3, max(orders) // m + 8)`` rounded
        up to cover three times the largest order.

    Returns
    -------
    dict
        ``{order: s}``: the poles with positive imaginary part [1/s] (one of each conjugate
        pair; real poles dropped).
    """
    m, n = y.shape
    nmax = max(orders)
    if rows is None:
        rows = max(int(math.ceil(3 * (nmax + m) / m)), 4)
    rows = int(min(rows, max(n // 2, 2)))
    Hk = _hankel(y, rows)
    lam, U = np.linalg.eigh(Hk @ Hk.T)  # left singular vectors, from the Gram matrix
    U = U[:, np.argsort(lam)[::-1]]
    out = {}
    for order in orders:
        order = min(order, U.shape[1], rows * m - m)
        Un = U[:, :order]
        phi = np.linalg.lstsq(Un[:-m], Un[m:], rcond=None)[0]
        z = np.linalg.eigvals(phi)
        z = z[np.abs(z) > 1e-12]
        s = np.log(z.astype(complex)) / dt
        out[order] = s[s.imag > 1e-9 * np.abs(s)]
    return out


def stable_poles(
    poles, *, f_tol=2e-3, z_tol=0.2, z_abs=2e-4, min_orders=4
) -> tuple[NDArray[np.complex128], NDArray[np.int_]]:
    """Physical poles of a stabilisation diagram: clusters of stable poles.

    A pole at order ``n`` is stable when the next lower order has a pole within ``f_tol``
    (relative) in frequency and within ``z_tol`` (relative) plus ``z_abs`` in damping ratio.
    Stable poles are grouped by frequency (neighbours within ``f_tol``); a group holding
    stable poles of at least ``min_orders`` distinct orders is physical, represented by the
    median of its members. Over-modelling at high orders (a pole split in two by noise or
    a slow drift) does not hide a pole that was stable over a run of lower orders.

    Returns
    -------
    s : ndarray of complex
        One pole per physical group, by ascending frequency.
    counts : ndarray of int
        Number of orders each was stable at.
    """
    orders = sorted(poles)

    def fz(s):
        w = np.abs(s)
        return w / (2 * math.pi), -s.real / np.maximum(w, 1e-300)

    members = []  # (f, pole, order)
    for lower, order in zip(orders[:-1], orders[1:]):
        cand, cur = poles[lower], poles[order]
        if cand.size == 0 or cur.size == 0:
            continue
        fc, zc = fz(cand)
        fs, zs = fz(cur)
        for s, f, z in zip(cur, fs, zs):
            k = int(np.argmin(np.abs(fc - f)))
            if abs(fc[k] - f) <= f_tol * f and abs(zc[k] - z) <= z_tol * abs(z) + z_abs:
                members.append((f, s, order))
    members.sort(key=lambda r: r[0])
    groups, cur = [], []
    for r in members:
        if cur and r[0] - cur[-1][0] > f_tol * r[0]:
            groups.append(cur)
            cur = []
        cur.append(r)
    if cur:
        groups.append(cur)
    out, counts = [], []
    for g in groups:
        n = len({r[2] for r in g})
        if n >= min_orders:
            v = np.array([r[1] for r in g])
            out.append(np.median(v.real) + 1j * np.median(v.imag))
            counts.append(n)
    return np.array(out, dtype=complex), np.array(counts, dtype=int)


def basis(tau, s) -> NDArray[np.float64]:
    """Real regressors ``exp(sigma tau) cos(w tau)`` and ``-exp(sigma tau) sin(w tau)``,
    shape (N, 2p): the model ``Re(C exp(s tau))`` with ``C = a + i b`` is ``basis @ [a; b]``.
    """
    e = np.exp(np.outer(tau, s.real))
    ph = np.outer(tau, s.imag)
    return np.hstack([e * np.cos(ph), -e * np.sin(ph)])


def amplitudes(tau, Y, s) -> NDArray[np.complex128]:
    """Least-squares complex amplitudes ``C`` (p, m) of the poles ``s`` in ``Y`` (m, N)."""
    B = basis(tau, s)
    coef = np.linalg.lstsq(B, Y.T, rcond=None)[0]
    p = s.size
    return coef[:p] + 1j * coef[p:]


@dataclass(frozen=True)
class SinusoidFit:
    """Result of :func:`fit_sinusoids` (internal).

    ``s`` (p,) complex poles [1/s]; ``C`` (p, m) complex amplitudes at ``tau = 0`` in the
    weighted units of ``Y``; ``cov`` the covariance of the parameter vector
    ``[sigma (p), omega (p), Re C (p*m, pole-major), Im C (p*m)]``; ``rms`` (m,) residual rms
    per channel (dof-corrected); ``resid`` (m, N) the residuals.
    """

    s: np.ndarray
    C: np.ndarray
    cov: np.ndarray
    rms: np.ndarray
    resid: np.ndarray
    converged: bool

    def params(self) -> NDArray[np.float64]:
        """The parameter vector the covariance refers to."""
        return np.concatenate([self.s.real, self.s.imag, self.C.real.ravel(), self.C.imag.ravel()])


def _unpack(x, p, m):
    s = x[:p] + 1j * x[p : 2 * p]
    a = x[2 * p : 2 * p + p * m].reshape(p, m)
    b = x[2 * p + p * m :].reshape(p, m)
    return s, a + 1j * b


def _model_jac(x, tau, p, m):
    """Model (N, m) and Jacobian (N, m, P) of ``Re(sum_i C_ij exp(s_i tau))``."""
    s, C = _unpack(x, p, m)
    E = np.exp(np.outer(tau, s))  # (N, p) complex
    Ec, Es = E.real, E.imag  # e cos, e sin
    model = Ec @ C.real - Es @ C.imag  # (N, m)
    n = tau.size
    J = np.zeros((n, m, x.size))
    # d/dsigma_i: tau Re(C E); d/domega_i: tau Re(i C E) = -tau Im(C E)
    for i in range(p):
        ce = E[:, i, None] * C[i][None, :]  # (N, m)
        J[:, :, i] = tau[:, None] * ce.real
        J[:, :, p + i] = -tau[:, None] * ce.imag
        for j in range(m):
            J[:, j, 2 * p + i * m + j] = Ec[:, i]
            J[:, j, 2 * p + p * m + i * m + j] = -Es[:, i]
    return model, J


def _correlated_cov(J, rho, s2):
    """``s2 A^-1 (sum_j J_j^T R J_j) A^-1``: ``R`` the Toeplitz noise correlation ``rho``,
    the same for every channel ``j`` (its product with ``J_j`` by FFT convolution).
    """
    n, m, P = J.shape
    A = np.einsum("tjp,tjq->pq", J, J)
    if rho.size > 1:
        kern = np.concatenate([rho[:0:-1], rho])
        RJ = (
            signal.fftconvolve(J, kern[:, None, None], mode="same", axes=0)
            if kern.size <= 2 * n - 1
            else None
        )
        if RJ is None:
            kern = kern[kern.size // 2 - (n - 1) : kern.size // 2 + n]
            RJ = signal.fftconvolve(J, kern[:, None, None], mode="same", axes=0)
        M = np.einsum("tjp,tjq->pq", J, RJ)
        M = 0.5 * (M + M.T)
    else:
        M = A
    Ainv = np.linalg.pinv(A)
    return s2 * Ainv @ M @ Ainv


def fit_sinusoids(tau, Y, s0, *, rho=None, max_nfev=200) -> SinusoidFit:
    """Least squares of all poles and amplitudes of ``Y`` (m, N) at times ``tau`` (N,) [s].

    ``Y``'s channels are assumed weighted to equal noise variance; ``rho`` is the noise
    autocorrelation coefficient at lags 0, 1, ... samples (``rho[0] = 1``; default white).
    """
    m, n = Y.shape
    p = s0.size
    C0 = amplitudes(tau, Y, s0)
    x0 = np.concatenate([s0.real, s0.imag, C0.real.ravel(), C0.imag.ravel()])
    target = Y.T

    def fun(x):
        return (_model_jac(x, tau, p, m)[0] - target).ravel()

    def jac(x):
        return _model_jac(x, tau, p, m)[1].reshape(n * m, x.size)

    scale = np.concatenate(
        [
            np.full(2 * p, 1.0 / max(tau[-1] - tau[0], 1e-300)),
            np.full(2 * p * m, max(float(np.abs(C0).max()), 1e-300)),
        ]
    )
    with np.errstate(over="ignore", invalid="ignore"):
        sol = optimize.least_squares(
            fun, x0, jac=jac, method="lm", x_scale=scale, xtol=1e-12, ftol=1e-12, max_nfev=max_nfev
        )
        x, ok = sol.x, bool(sol.success)
        model, J = _model_jac(x, tau, p, m)
    if not (
        np.all(np.isfinite(model))
        and np.all(np.isfinite(J))
        and sol.cost <= 0.5 * float(np.sum(fun(x0) ** 2))
    ):  # diverged: keep the subspace start
        x, ok = x0, False
        model, J = _model_jac(x, tau, p, m)
    resid = (target - model).T
    dof = max(n * m - x.size, 1)
    s2 = float(np.sum(resid**2)) / dof
    rms = np.sqrt(np.sum(resid**2, axis=1) / max(n - x.size / m, 1.0))
    rho = np.ones(1) if rho is None else np.asarray(rho, float)
    cov = _correlated_cov(J, rho, s2)
    s, C = _unpack(x, p, m)
    return SinusoidFit(s, C, cov, rms, resid, ok)
