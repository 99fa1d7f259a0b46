"""Nonlinear modes by the extended periodic motion concept (EPMC), with the exact joints.

Krack (Computers & Structures 154:59-71, 2015): the autonomous system
``M x'' + (C - xi M) x' + K x + f_nl = 0`` has a periodic solution for the mass-proportional
self-excitation ``xi`` that cancels the dissipation over a period; the nonlinear mode's
frequency is ``W`` and its modal damping ratio ``zeta = xi / (2 W)``
(``docs/harmonic_balance.md`` section 5). On a :class:`~.system.ModalSystem` the self-
excitation enters every kept mode's denominator, ``w_r^2 - w^2 + i w (2 zeta_r w_r - xi)``.

Unknowns: the joint coefficients ``Z``, ``W``, ``xi`` and the amplitude ``a`` of the mode's
own fundamental modal coordinate, whose phase is fixed (``q_r = a cos(W t) + ...``: the phase
normalisation). Equations: the condensed balance of the joint coordinates with the mode's
fundamental term written out, the mode's own fundamental equation (two real ones), and the
amplitude normalisation: the sensor's fundamental displacement amplitude equals the
requested ``X`` (the amplitude QSMA and the ring-downs report). Newton with the exact AFT
Jacobian; each amplitude starts from the previous one's solution.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..base.progress import finish, progress_bar, tick
from ..base.threads import one_blas_thread
from .balance import compose, operators, point_outputs, rate_operators
from .basis import Harmonics
from .result import slip_ratio

__all__ = ["epmc_branch"]

log = logging.getLogger(__name__)


def _rate_ops(system, basis, W, xi, r):
    """d/dW and d/dxi of the joint and sensor operators (the mode's own fundamental left
    out): ``[(dLzz_W, dLsz_W), (dLzz_xi, dLsz_xi)]``.
    """
    nz = system.n_z
    iz = list(range(nz))
    zz = rate_operators(system, basis, W, iz, iz, xi=xi, exclude=r)
    sz = rate_operators(system, basis, W, [nz], iz, xi=xi, exclude=r)
    return [(zz[0], sz[0]), (zz[1], sz[1])]


def _equations(system, basis, y, X, r, *, jacobian=True):
    """Residual and Jacobian of the EPMC equations in ``y = [Z.ravel(), W, xi, a]``."""
    nz, nc = system.n_z, basis.n_coefficients
    n = nz * nc
    cz = y[:n].reshape(nz, nc)
    W, xi, a = y[n], y[n + 1], y[n + 2]
    Lzz, Lpz, _ = operators(system, basis, W, xi=xi, exclude=r)
    cg, dcg, D = basis.nonlinear_forces(system, cz, W, jacobian=jacobian)
    h1 = [c for c in basis.cols if c[0] == 1][0]
    ia, ib = h1[1], h1[2]
    Yz, Ys = system.modes[:nz, r], system.modes[nz, r]
    Rz = cz + np.einsum("pcqd,qd->pc", Lzz, cg)
    Rz[:, ia] -= Yz * a
    den = system.denominators(W, xi=xi)[r]
    G1 = cg[:, ia] - 1j * cg[:, ib]
    Rm = den * a + Yz @ G1
    cs = -np.einsum("cqd,qd->c", Lpz[0], cg)
    cs[ia] += Ys * a
    amp = math.hypot(cs[ia], cs[ib])
    R = np.concatenate([Rz.ravel(), [Rm.real, Rm.imag, amp - X]])
    if not jacobian:
        return R, None, cg, D
    J = np.zeros((n + 3, n + 3))
    Jzz = compose(Lzz, dcg)
    Jzz[np.diag_indices(n)] += 1.0
    J[:n, :n] = Jzz
    (dLzz_W, dLpz_W), (dLzz_X, dLpz_X) = _rate_ops(system, basis, W, xi, r)
    J[:n, n] = np.einsum("pcqd,qd->pc", dLzz_W, cg).ravel()
    J[:n, n + 1] = np.einsum("pcqd,qd->pc", dLzz_X, cg).ravel()
    dRz_a = np.zeros((nz, nc))
    dRz_a[:, ia] = -Yz
    J[:n, n + 2] = dRz_a.ravel()
    dG1 = (Yz[:, None] * (dcg[:, ia, :] - 1j * dcg[:, ib, :])).reshape(n)
    dden_W = -2.0 * W + 1j * (2.0 * system.zeta[r] * system.omega[r] - xi)
    for row, part in ((n, np.real), (n + 1, np.imag)):
        J[row, :n] = part(dG1)
        J[row, n] = part(dden_W * a)
        J[row, n + 1] = part(-1j * W * a)
        J[row, n + 2] = part(den)
    dcs = -compose(Lpz[:1], dcg)
    g = np.array([cs[ia], cs[ib]]) / max(amp, 1e-300)
    J[n + 2, :n] = g @ dcs[[ia, ib]]
    for col, dL in ((n, dLpz_W), (n + 1, dLpz_X)):
        dcsx = -np.einsum("cqd,qd->c", dL[0], cg)
        J[n + 2, col] = g @ dcsx[[ia, ib]]
    J[n + 2, n + 2] = g[0] * Ys
    return R, J, cg, D


def _newton(system, basis, y, X, r, *, tol, max_iter):
    scale = np.abs(y).copy()
    n = y.size - 3
    scale[:n] = max(float(np.abs(y[:n]).max()), 1e-300)
    scale[n + 1] = max(scale[n + 1], 1e-4 * abs(y[n]))  # xi is 0 without a floor
    R, J, cg, D = _equations(system, basis, y, X, r)
    for it in range(1, max_iter + 1):
        step = np.linalg.solve(J * scale[None, :], -R) * scale
        lam = 1.0
        rn = np.linalg.norm(R)
        for _ in range(12):
            trial = y + lam * step
            R2, J2, cg2, D2 = _equations(system, basis, trial, X, r)
            if np.linalg.norm(R2) <= rn or lam < 1e-3:
                break
            lam *= 0.5
        y, R, J, cg, D = trial, R2, J2, cg2, D2
        if np.all(np.abs(lam * step) <= tol * scale):
            return y, cg, D, True, it
    return y, cg, D, False, max_iter


def epmc_branch(
    system, basis: Harmonics, amplitude, r: int, *, tol=1e-9, max_iter=40, progress: bool = False
) -> dict[str, NDArray[Any]]:
    """Nonlinear mode ``r`` (a kept-mode column) (one BLAS thread: :func:`_branch`)."""
    bar = progress_bar(progress, total=np.size(amplitude), desc="nonlinear_mode", unit="amplitude")
    try:
        with one_blas_thread():
            return _branch(system, basis, amplitude, r, tol=tol, max_iter=max_iter, bar=bar)
    finally:
        finish(bar)


def _branch(system, basis, amplitude, r, *, tol, max_iter, bar):
    """Nonlinear mode ``r`` (a kept-mode column) at sensor amplitudes ``amplitude`` [m]
    (solved in increasing order). Returns a dict of arrays: ``amplitude``, ``frequency``
    [Hz], ``damping_ratio`` [-], ``xi`` [1/s], ``converged``, ``iterations``,
    ``energy_error`` (self-excitation work against the joints' and the floor's loss),
    ``slip_ratio`` (n, n_j: each joint's slip amplitude over its ``phi_max``,
    :func:`~.result.slip_ratio`; NaN where Newton did not converge), ``wall_time``.
    """
    X = np.asarray(amplitude, float)
    order = np.argsort(X)
    nz, nc = system.n_z, basis.n_coefficients
    Ys = system.modes[nz, r]
    if abs(Ys) < 1e-12 * np.abs(system.modes[:, r]).max():
        raise ValueError(
            "the sensor sits at a node of this mode: its amplitude cannot set the mode's level"
        )
    ia = [c for c in basis.cols if c[0] == 1][0][1]
    w0, z0 = float(system.omega[r]), float(system.zeta[r])
    last = None  # (y, X) of the last converged amplitude
    out = {k: np.zeros(X.size) for k in ("frequency", "damping_ratio", "xi", "energy_error")}
    out["converged"] = np.zeros(X.size, bool)
    out["iterations"] = np.zeros(X.size, int)
    out["slip_ratio"] = np.full((X.size, len(system.joints)), np.nan)
    t0 = time.perf_counter()
    for k in order:
        if last is None:  # the linear mode at this amplitude
            cz = np.zeros((nz, nc))
            a0 = X[k] / abs(Ys)
            cz[:, ia] = system.modes[:nz, r] * a0 * np.sign(Ys)
            y = np.concatenate([cz.ravel(), [w0, 2 * z0 * w0, a0 * np.sign(Ys)]])
        else:  # the neighbour, scaled to this amplitude
            y = last[0].copy()
            y[:-3] *= X[k] / last[1]
            y[-1] *= X[k] / last[1]
        y, cg, D, ok, its = _newton(system, basis, y, X[k], r, tol=tol, max_iter=max_iter)
        W, xi, a = y[-3], y[-2], y[-1]
        po = point_outputs(
            system,
            basis,
            W,
            0.0,
            cg,
            D,
            xi=xi,
            modal=(r, a),
            ops=operators(system, basis, W, xi=xi, exclude=r),
        )
        # the self-excitation's work per period: xi pi W sum_h h^2 |Q_h|^2 over the modes
        e_in = po["self_excitation_work"]
        d = po["joint_dissipation"] + po["floor_dissipation"]
        out["frequency"][k] = W / (2 * math.pi)
        out["xi"][k] = xi
        out["damping_ratio"][k] = xi / (2 * W)
        out["energy_error"][k] = (e_in - d) / e_in if e_in else np.nan
        out["converged"][k] = ok
        out["iterations"][k] = its
        if ok:
            last = (y, X[k])
            out["slip_ratio"][k] = slip_ratio(system, basis, y[: nz * nc].reshape(nz, nc))
        if not ok:
            log.warning("EPMC did not converge at amplitude %.3g m", X[k])
        tick(bar, text=f"{X[k]:.3g} m")
    out["amplitude"] = X
    out["wall_time"] = time.perf_counter() - t0
    return out
