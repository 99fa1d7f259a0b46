"""Harmonic balance of a :class:`~.system.ModalSystem` under a harmonic force, with exact AFT.

The structure is condensed onto its joint coordinates (``docs/harmonic_balance.md`` section
3): with the receptances of :class:`~.system.ModalSystem` and the harmonic coefficients
``Z_h`` of the joint coordinates, ``G_h`` of the joints' force deficits and ``F_h`` of the
excitation (``F`` on the fundamental's cosine)::

    R_h = Z_h + H_zz(h W) G_h(Z) - H_zb(h W) F_h = 0          for every kept harmonic h,

the residual of Krack & Gross (Harmonic Balance for Nonlinear Vibration Problems, Springer
2019, ch. 2; ``docs/harmonic_balance.md`` section 3) multiplied by the dynamic compliance,
which is exact for the linear part.
``G(Z)`` is the alternating frequency-time evaluation on the exact steady loop of each joint
(:mod:`iwan_element.core.periodic`), and the Jacobian ``I + H_zz dG/dZ`` uses its exact sample
Jacobian (tangent plus reversal columns). Newton's method solves each frequency, starting
from the previous one's solution.
"""

from __future__ import annotations

import logging
import math
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import NDArray

from .basis import Harmonics

__all__ = [
    "HBPoint",
    "solve_point",
    "operators",
    "rate_operators",
    "residual",
    "point_outputs",
    "force_coefficients",
    "compose",
]

log = logging.getLogger(__name__)


class HBPoint(dict):
    """One converged (or not) point: ``cz`` (joint coefficients), ``W`` [rad/s], ``force`` [N],
    ``converged``, ``iterations``, ``residual`` (relative), plus :func:`point_outputs`.
    """


def operators(
    system, basis: Harmonics, W: float, *, xi: float = 0.0, exclude=None
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The receptances at every kept harmonic of ``W`` as real 4-D operators:
    ``(Lzz, Lpz, Lpb)`` with ``p`` the sensor and excitation ports.
    """
    H = [
        system.receptance(h * W, xi=xi, exclude=exclude if h == 1 else None)
        for h in basis.harmonics
    ]
    nz = system.n_z
    iz = list(range(nz))
    return (
        basis.linear_operator(H, iz, iz),
        basis.linear_operator(H, [nz, nz + 1], iz),
        basis.linear_operator(H, iz + [nz, nz + 1], [nz + 1]),
    )


def rate_operators(
    system, basis: Harmonics, W: float, rows, cols, *, xi: float = 0.0, exclude=None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(dL/dW, dL/dxi)``: the derivatives of the real operator of the receptances between
    ports ``rows`` and ``cols`` with respect to the fundamental ``W`` [rad/s] and to the
    self-excitation ``xi`` [1/s] (:meth:`ModalSystem.receptance_rate`).
    """
    dW, dX = [], []
    for h in basis.harmonics:
        if h == 0:
            z = np.zeros((system.n_z + 2,) * 2, complex)
            dW.append(z)
            dX.append(z)
            continue
        a, b = system.receptance_rate(W, h, xi=xi, exclude=exclude if h == 1 else None)
        dW.append(a)
        dX.append(b)
    return basis.linear_operator(dW, rows, cols), basis.linear_operator(dX, rows, cols)


def compose(L: np.ndarray, dcg: np.ndarray) -> np.ndarray:
    """``J[(p, c), (q, e)] = sum_d L[p, c, q, d] dcg[q, d, e]``: a real 4-D operator times the
    block-diagonal Jacobian of the nonlinear coordinates' forces, as one matrix of shape
    ``(n_p nc, n_q nc)`` (one batched matrix product over ``q``; the same ``einsum`` took
    nine times as long at the Brake-Reuss beam's 31 coordinates).
    """
    p, c, q, d = L.shape
    out = np.matmul(L.transpose(2, 0, 1, 3).reshape(q, p * c, d), dcg)
    return out.transpose(1, 0, 2).reshape(p * c, q * dcg.shape[2])


def force_coefficients(basis: Harmonics, force: float) -> np.ndarray:
    """Real coefficients of ``force cos(W t)`` [N]."""
    cf = np.zeros(basis.n_coefficients)
    for h, ia, _ in basis.cols:
        if h == 1:
            cf[ia] = force
    return cf


@overload
def residual(
    system, basis, W, force, cz, *, ops=None, jacobian: Literal[True] = True
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]: ...
@overload
def residual(
    system, basis, W, force, cz, *, ops=None, jacobian: Literal[False]
) -> tuple[NDArray[np.float64], None, NDArray[np.float64], NDArray[np.float64]]: ...
def residual(
    system, basis, W, force, cz, *, ops=None, jacobian: bool = True
) -> tuple[
    NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.float64], NDArray[np.float64]
]:
    """``(R, J, cg, D)`` of the harmonic balance at ``W`` [rad/s] (module docstring);
    ``R`` shape ``(n_z, nc)``, ``J`` shape ``(n_z nc, n_z nc)``.
    """
    Lzz, _, Lb = ops if ops is not None else operators(system, basis, W)
    cg, dcg, D = basis.nonlinear_forces(system, cz, W, jacobian=jacobian)
    cf = force_coefficients(basis, force)
    nz = system.n_z
    R = cz + np.einsum("pcqd,qd->pc", Lzz, cg) - Lb[:nz, :, 0, :] @ cf
    J = None
    if jacobian:
        n = cz.size
        J = compose(Lzz, dcg)
        J[np.diag_indices(n)] += 1.0
    return R, J, cg, D


def solve_point(system, basis, W, force, cz0, *, tol=1e-9, max_iter=40) -> HBPoint:
    """Newton's method at one frequency ``W`` [rad/s] from the start ``cz0``."""
    ops = operators(system, basis, W)
    cz = np.array(cz0, dtype=float)
    scale = max(float(np.abs(ops[2][:-2, :, 0, :]).max()) * abs(force), 1e-300)
    R, J, cg, D = residual(system, basis, W, force, cz, ops=ops)
    rn = float(np.linalg.norm(R))
    it = 0
    ok = False
    for it in range(1, max_iter + 1):  # noqa: B007  the count is reported after the loop
        step = np.linalg.solve(J, -R.ravel()).reshape(cz.shape)
        lam = 1.0
        for _ in range(12):  # backtracking on the residual norm
            trial = cz + lam * step
            R2, J2, cg2, D2 = residual(system, basis, W, force, trial, ops=ops)
            rn2 = float(np.linalg.norm(R2))
            if rn2 <= rn or rn2 <= tol * scale:
                break
            lam *= 0.5
        cz, R, J, cg, D, rn = trial, R2, J2, cg2, D2, rn2
        size = max(float(np.linalg.norm(cz)), 1e-300)
        if lam * float(np.linalg.norm(step)) <= tol * size and rn <= 1e3 * tol * size:
            ok = True
            break
    out = HBPoint(
        cz=cz,
        W=W,
        force=force,
        converged=ok,
        iterations=it,
        residual=rn / max(float(np.linalg.norm(cz)), 1e-300),
        cg=cg,
        D=D,
    )
    out.update(point_outputs(system, basis, W, force, cg, D, ops=ops))
    return out


def point_outputs(
    system, basis, W, force, cg, D, *, ops=None, xi=0.0, modal=None
) -> dict[str, Any]:
    """Sensor and excitation-point coefficients and the energy per period of a solution.

    Returns a dict: ``sensor`` (nc,) [m], ``excitation`` (nc,) [m], ``input_work``,
    ``joint_dissipation``, ``floor_dissipation`` and ``self_excitation_work`` (the work of
    the self-excitation ``xi M x'`` of a nonlinear mode, 0 without it) [J per period];
    ``modal = (r, a)`` puts in the explicit fundamental ``a`` of a nonlinear mode
    (:mod:`.nlmode`).
    """
    _, Lpz, Lpb = ops if ops is not None else operators(system, basis, W, xi=xi)
    cf = force_coefficients(basis, force)
    nz = system.n_z
    ports = -np.einsum("pcqd,qd->pc", Lpz, cg) + Lpb[nz:, :, 0, :] @ cf
    # modal coordinates for the floor's dissipation: Q_rh = (Y_br F_h - Y_zr^T G_h) / den_rh
    Gc = basis.complex(cg)
    Fc = basis.complex(cf[None, :])[0]
    Y = system.modes
    c_r = 2.0 * system.zeta * system.omega
    D_floor = W_self = 0.0
    for k, (h, _, _) in enumerate(basis.cols):
        if h == 0:
            continue
        d = system.denominators(h * W, xi=xi)
        Q = (Y[nz + 1] * Fc[k] - Y[:nz].T @ Gc[:, k]) / d
        if modal is not None and h == 1:
            r, q1 = modal
            Q[r] = q1
        q2 = math.pi * W * h * h * np.abs(Q) ** 2
        D_floor += float(np.sum(c_r * q2))
        W_self += xi * float(np.sum(q2))
    if modal is not None:
        r, q1 = modal
        ports = ports + np.outer(
            Y[nz:, r], basis.real(np.array([q1 if h == 1 else 0.0 for h, _, _ in basis.cols]))
        )
    sin1 = [ib for h, _, ib in basis.cols if h == 1][0]
    return {
        "sensor": ports[0],
        "excitation": ports[1],
        "input_work": math.pi * force * float(ports[1][sin1]),
        "joint_dissipation": float(np.sum(D)),
        "floor_dissipation": D_floor,
        "self_excitation_work": W_self,
    }
