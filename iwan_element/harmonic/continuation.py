"""Pseudo-arclength continuation of the harmonic balance along frequency at a fixed force.

Keller's method (``docs/harmonic_balance.md`` section 4): the unknowns ``y = (Z / s_z,
W / s_W)`` (joint coefficients and frequency, scaled so that a step of one is the band's
width in frequency and the band's largest linear slip in amplitude) follow the solution curve
``R(y) = 0`` by its unit tangent ``t`` (the null vector of ``[dR/dZ, dR/dW]``, oriented as the
previous one). A predictor ``y + ds t`` is corrected by Newton's method on ``R = 0`` together
with ``t . (y - y_pred) = 0`` (the hyperplane through the predictor normal to the tangent),
so the curve is traced through turning points where the frequency alone could not
parametrise it. The step ``ds`` grows when the corrector converges in few iterations and is
halved when it needs many, fails, or the tangent turns by more than 10 degrees.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from ..base.threads import one_blas_thread
from ..base.validation import plain_number
from .balance import (
    force_coefficients,
    operators,
    point_outputs,
    rate_operators,
    residual,
    solve_point,
)
from .basis import Harmonics, check_harmonics
from .response import assemble_response, linear_start
from .result import FrequencyResponse
from .system import ModalSystem

__all__ = ["trace"]

log = logging.getLogger(__name__)


def _augmented(system, basis, y, force, sz, sW):
    """``(R, [dR/dZ, dR/dW], cg, D)`` at scaled ``y`` (residual in units of ``sz``)."""
    nz = system.n_z
    n = y.size - 1
    cz = y[:n].reshape(nz, -1) * sz
    W = y[n] * sW
    ops = operators(system, basis, W)
    R, J, cg, D = residual(system, basis, W, force, cz, ops=ops)
    iz = list(range(nz))
    dzz, _ = rate_operators(system, basis, W, iz, iz)
    dzb, _ = rate_operators(system, basis, W, iz, [nz + 1])
    dR_dW = np.einsum("pcqd,qd->pc", dzz, cg) - dzb[:, :, 0, :] @ force_coefficients(basis, force)
    A = np.empty((n, n + 1))
    A[:, :n] = J  # dR/dZ * sz / sz
    A[:, n] = dR_dW.ravel() * sW / sz
    return R.ravel() / sz, A, cg, D, ops


def _tangent(A, t_prev):
    n = A.shape[0]
    M = np.vstack([A, t_prev[None, :]])
    rhs = np.zeros(n + 1)
    rhs[n] = 1.0
    t = np.linalg.solve(M, rhs)
    return t / np.linalg.norm(t)


def trace(
    system: ModalSystem,
    *,
    force: float,
    band,
    harmonics=(1, 3, 5),
    samples=None,
    step: float = 0.02,
    max_points: int = 2000,
    tol: float = 1e-9,
) -> FrequencyResponse:
    """Trace the frequency response curve at one force level through its turning points.

    Parameters
    ----------
    system : ModalSystem
    force : float
        Fundamental force amplitude [N], > 0.
    band : (float, float)
        Start and end frequency [Hz] (the curve is traced from the first towards the second).
    harmonics, samples : keyword-only
        As :func:`~iwan_element.harmonic.harmonic_balance`.
    step : float, keyword-only
        Initial arclength step in scaled units (fraction of the band), in ``(0, 0.5]``.
    max_points : int, keyword-only
        Largest number of points traced.
    tol : float, keyword-only
        Newton's relative tolerance.

    Returns
    -------
    FrequencyResponse
        The points in the order traced (frequency need not be monotonic: at a turning point
        it reverses); ``metadata["turning_points"]`` counts them.
    """
    if not isinstance(system, ModalSystem):
        raise ValueError(f"system must be a ModalSystem, got {type(system).__name__}")
    force = plain_number(force)
    if (
        isinstance(force, bool)
        or not isinstance(force, (int, float))
        or not math.isfinite(force)
        or force <= 0
    ):
        raise ValueError(f"force must be a finite amplitude > 0 [N], got {force!r}")
    try:
        f0, f1 = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ValueError(f"band must be (start, end) frequencies [Hz], got {band!r}") from None
    if not (f0 > 0 and f1 > 0 and f0 != f1 and math.isfinite(f0) and math.isfinite(f1)):
        raise ValueError(f"band must be two different frequencies > 0 [Hz], got {band!r}")
    step = plain_number(step)
    if not (isinstance(step, (int, float)) and not isinstance(step, bool) and 0 < step <= 0.5):
        raise ValueError(f"step must be in (0, 0.5], got {step!r}")
    basis = Harmonics(*check_harmonics(harmonics, samples))
    t0 = time.perf_counter()
    with one_blas_thread():
        points, turns = _walk(
            system, basis, float(force), f0, f1, float(step), int(max_points), tol
        )
    return assemble_response(
        points,
        basis,
        system,
        time.perf_counter() - t0,
        turning_points=turns,
        route="pseudo-arclength continuation",
    )


def _walk(system, basis, force, f0, f1, ds, max_points, tol):
    W0, W1 = 2 * math.pi * f0, 2 * math.pi * f1
    sW = abs(W1 - W0)
    p = solve_point(system, basis, W0, force, linear_start(system, basis, W0, force), tol=tol)
    sz = max(float(np.abs(p["cz"]).max()), 1e-300)
    y = np.concatenate([p["cz"].ravel() / sz, [W0 / sW]])
    points = [p]
    n = y.size - 1
    t = np.zeros(n + 1)
    t[n] = math.copysign(1.0, W1 - W0)
    _, A, _, _, _ = _augmented(system, basis, y, force, sz, sW)
    t = _tangent(A, t)
    turns = 0
    ds_min, ds_max, cos_max = 1e-6, 0.05, math.cos(math.radians(10.0))
    while len(points) < max_points and (y[n] * sW - W1) * math.copysign(1.0, W1 - W0) < 0:
        yp = y + ds * t
        ok, yc, its, out = _correct(system, basis, yp, t, force, sz, sW, tol)
        if not ok:
            ds *= 0.5
            if ds < ds_min:
                log.warning(
                    "continuation stopped at %.6g Hz: the corrector failed",
                    y[n] * sW / (2 * math.pi),
                )
                break
            continue
        if yc[n] <= 0 or abs(yc[n] * sW - 0.5 * (W0 + W1)) > 1.5 * sW:
            log.warning(
                "continuation left the band at %.6g Hz (an unbounded resonance: the "
                "joints cannot limit the response at this force)",
                yc[n] * sW / (2 * math.pi),
            )
            break
        R, A, cg, D, ops = out
        t_new = _tangent(A, t)
        if t_new[n] * t[n] < 0:
            turns += 1
        bend = float(t_new @ t)
        y, t = yc, t_new
        W = y[n] * sW
        cz = y[:n] * sz
        pt = {
            "cz": cz.reshape(system.n_z, -1),
            "W": W,
            "force": force,
            "converged": True,
            "iterations": its,
            "cg": cg,
            "D": D,
        }
        pt.update(point_outputs(system, basis, W, force, cg, D, ops=ops))
        points.append(pt)
        big = float(np.abs(cz).max())
        if big > 2.0 * sz:  # the amplitude scale follows the response
            y[:n] *= sz / big
            t[:n] *= sz / big
            t /= np.linalg.norm(t)
            sz = big
        if bend < cos_max:
            ds *= 0.5
        elif its <= 3:
            ds = min(ds * 1.5, ds_max)
        elif its >= 8:
            ds *= 0.5
    return points, turns


def _correct(system, basis, yp, t, force, sz, sW, tol, max_iter=12):
    """Newton on ``R(y) = 0, t . (y - yp) = 0`` from the predictor ``yp``."""
    y = yp.copy()
    n = y.size - 1
    for it in range(1, max_iter + 1):
        R, A, cg, D, ops = _augmented(system, basis, y, force, sz, sW)
        M = np.vstack([A, t[None, :]])
        rhs = -np.concatenate([R, [t @ (y - yp)]])
        try:
            d = np.linalg.solve(M, rhs)
        except np.linalg.LinAlgError:
            return False, y, it, None
        y = y + d
        if np.max(np.abs(d)) <= tol * max(1.0, float(np.max(np.abs(y[:n])))):
            out = _augmented(system, basis, y, force, sz, sW)
            return True, y, it, out
    return False, y, max_iter, None
