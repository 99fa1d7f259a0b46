"""Frequency response at given frequencies and forces: the harmonic balance driver."""

from __future__ import annotations

import logging
import math
import time

import numpy as np
from numpy.typing import NDArray

from ..base.progress import finish, progress_bar, tick
from ..base.threads import one_blas_thread
from ..base.validation import finite_array, plain_number
from .balance import force_coefficients, operators, solve_point
from .basis import Harmonics, check_harmonics
from .result import FrequencyResponse, macroslip_lines, slip_ratio
from .system import ModalSystem

__all__ = ["harmonic_balance", "check_frequency_force", "assemble_response", "linear_start"]

log = logging.getLogger(__name__)


def check_frequency_force(frequency, force) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validated ``(frequency [Hz], force [N])`` arrays of one length (a scalar force is
    repeated).
    """
    f = np.atleast_1d(finite_array("frequency", frequency, ndim=None)).astype(float)
    if f.ndim != 1 or f.size == 0 or np.any(f <= 0):
        raise ValueError(
            f"frequency must be a non-empty 1-D array of frequencies > 0 [Hz], got shape {f.shape}"
        )
    F = np.atleast_1d(finite_array("force", force, ndim=None)).astype(float)
    if F.size == 1:
        F = np.full(f.size, float(F.ravel()[0]))
    if F.shape != f.shape:
        raise ValueError(f"force must be one value or one per frequency ({f.size}), got {F.size}")
    if np.any(F <= 0):
        raise ValueError("force must be amplitudes > 0 [N]")
    return f, F


def linear_start(system, basis, W, force) -> NDArray[np.float64]:
    """The stuck (linear) response's joint coefficients at ``W``."""
    _, _, Lb = operators(system, basis, W)
    return Lb[: system.n_z, :, 0, :] @ force_coefficients(basis, force)


def harmonic_balance(
    system: ModalSystem,
    *,
    frequency,
    force,
    harmonics=(1, 3, 5),
    samples=None,
    tol: float = 1e-9,
    max_iter: int = 40,
    progress: bool = False,
) -> FrequencyResponse:
    """Steady response of a :class:`ModalSystem` to ``force cos(2 pi f t)`` at each frequency.

    Each point starts from the previous one's solution (scaled by the force ratio; from the
    linear response when that fails), which is natural-parameter continuation; for a curve
    with turning points use :func:`~iwan_element.harmonic.continuation.trace`.

    Parameters
    ----------
    system : ModalSystem
    frequency : array_like, shape (n,)
        Excitation frequencies [Hz], solved in the order given.
    force : float or array_like, shape (n,)
        Fundamental force amplitude at the excitation port [N] (one per frequency for a
        response-controlled test).
    harmonics : int or sequence of int, keyword-only
        Harmonics kept (``check_harmonics``; default the odd ones up to 5).
    samples : int, optional, keyword-only
        Time samples per period of the AFT (default: the power of two ``>= 8 H``, >= 64).
    tol : float, keyword-only
        Newton's relative tolerance on the step and the residual.
    max_iter : int, keyword-only
        Newton iterations per point.
    progress : bool, keyword-only
        Show a tqdm bar over the frequencies with its ETA (``iwan_element.base.progress``;
        silent under CI).

    Returns
    -------
    FrequencyResponse
    """
    if not isinstance(system, ModalSystem):
        raise ValueError(f"system must be a ModalSystem, got {type(system).__name__}")
    f, F = check_frequency_force(frequency, force)
    basis = Harmonics(*check_harmonics(harmonics, samples))
    tol = plain_number(tol)
    if not (isinstance(tol, float) and 0 < tol < 1e-3):
        raise ValueError(f"tol must be a float in (0, 1e-3), got {tol!r}")
    t0 = time.perf_counter()
    bar = progress_bar(progress, total=f.size, desc="harmonic_balance", unit="point")
    try:
        with one_blas_thread():
            points = _sweep(system, basis, f, F, tol, max_iter, bar)
    finally:
        finish(bar)
    return assemble_response(points, basis, system, time.perf_counter() - t0)


def _sweep(system, basis, f, F, tol, max_iter, bar):
    """Solve every frequency in order, each from its neighbour (see harmonic_balance)."""
    points, prev = [], None
    for k in range(f.size):
        W = 2 * math.pi * f[k]
        p = None
        if prev is not None:
            p = solve_point(
                system,
                basis,
                W,
                F[k],
                prev["cz"] * (F[k] / prev["force"]),
                tol=tol,
                max_iter=max_iter,
            )
        if p is None or not p["converged"]:  # the linear response as the start
            p = solve_point(
                system,
                basis,
                W,
                F[k],
                linear_start(system, basis, W, F[k]),
                tol=tol,
                max_iter=max_iter,
            )
        if not p["converged"]:
            log.warning("harmonic balance did not converge at %.6g Hz", f[k])
        points.append(p)
        prev = p if p["converged"] else prev
        tick(bar, text=f"{f[k]:.6g} Hz")
    return points


def assemble_response(points, basis, system, wall, **meta) -> FrequencyResponse:
    """The :class:`FrequencyResponse` of solved points (shared with the continuation)."""
    Z = basis.complex(np.array([p["sensor"] for p in points]))
    k1 = [h for h, _, _ in basis.cols].index(1)
    phase = np.angle(Z[:, k1])
    phase[phase > 0.5 * math.pi] -= 2 * math.pi  # receptance-like: 0 .. -pi
    ok = np.array([p["converged"] for p in points], bool)
    ratio = np.array(
        [
            slip_ratio(system, basis, p["cz"]) if c else np.full(len(system.joints), np.nan)
            for p, c in zip(points, ok)
        ]
    )
    f = np.array([p["W"] for p in points]) / (2 * math.pi)
    return FrequencyResponse(
        frequency=f,
        force=np.array([p["force"] for p in points]),
        amplitude=np.abs(Z[:, k1]),
        phase=phase,
        harmonics=Z,
        harmonic_numbers=basis.harmonics,
        converged=np.array([p["converged"] for p in points], bool),
        iterations=np.array([p["iterations"] for p in points], int),
        input_work=np.array([p["input_work"] for p in points]),
        joint_dissipation=np.array([p["joint_dissipation"] for p in points]),
        floor_dissipation=np.array([p["floor_dissipation"] for p in points]),
        wall_time=wall,
        metadata={"samples": basis.samples, "system": system.notes, **meta},
        slip_ratio=ratio,
        warnings=macroslip_lines(
            ratio, f, unit="Hz", what="frequencies", groups=system.joint_groups
        ),
    )
