"""Quasi-static modal analysis (QSMA) of a lap-jointed specimen.

Lacayo & Allen (MSSP 118:133-157, 2019; REFERENCE.md sec. 7 steps 1-6), on the linear beam
matrices extracted once from the Exudyn model (:func:`~iwan_element.models.assembly.linear_system`)
and the closed-form Iwan backbones of the contact points:

1. preload: the normal preload does not load the tangential elements here (no Poisson
   coupling), so ``x0 = 0`` and the stuck tangent is ``K = K0 + G^T diag(KT_i) G``;
2. mass-normalised eigenpair ``(w_k, phi)`` of ``(K, M)`` for the requested elastic mode;
3. static load ``alpha M phi``: Newton on ``K0 x + G^T F(G x) = alpha M phi`` with
   ``F_i`` the virgin backbone of point ``i`` (REFERENCE sec. 2) and its tangent, bordered
   with ``S x = X`` so that each requested sensor amplitude ``X`` is hit exactly;
4. ``q = phi^T M x`` and secant ``w^2 = alpha / q``;
5. Masing damping from the sum of the contact points' dissipations at their slip
   amplitudes ``u_i = |G_i x|`` (closed form, REFERENCE sec. 2) rather than the modal
   integral the reference code marks as inaccurate;
6. ``zeta = zeta_floor + D / (2 pi alpha q)``.

Free-free specimens: the rigid-body modes are removed by a penalty ``w_ref^2 M R R^T M``,
which the load (``R^T M phi = 0``) and the interface forces (``G R = 0``) never excite.
Limits (as the method's): one mode of fixed load shape, Masing rules, no normal-load
variation or separation, no inertia in the joint.
"""
from __future__ import annotations

import logging
import math

import numpy as np
import scipy.linalg as sla

from iwan_element import AmplitudeCurve, dissipation, normalized_backbone

from .assembly import linear_system
from .interface import contact_points
from .specimens import Specimen

__all__ = ["modal_amplitude_curve", "linear_modes", "static_modal_load"]

log = logging.getLogger(__name__)


def _check_mode(mode) -> int:
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode < 1:
        raise ValueError(f"mode must be an integer >= 1 (1: first elastic mode), got {mode!r}")
    return int(mode)


def _amplitudes(specimen: Specimen, amplitudes) -> np.ndarray:
    if amplitudes is None:
        lo, hi = specimen.amplitude_range
        return np.geomspace(lo, hi, 20)
    a = np.atleast_1d(np.asarray(amplitudes, dtype=float))
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError("amplitudes must be a non-empty 1-D sequence of finite values > 0 [m]")
    return a


def linear_modes(specimen: Specimen, *, mode: int = 1):
    """Stuck-interface mode of a specimen: ``(omega [rad/s], phi, rigid, L, points)``.

    ``phi`` (free coordinates) is mass-normalised with a positive sensor displacement;
    ``rigid`` holds the rigid-body modes (columns, mass-normalised; empty when clamped).
    """
    mode = _check_mode(mode)
    L = linear_system(specimen)
    pts = contact_points(specimen)
    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    w2, V = sla.eigh(K, L.M)
    rigid_mask = w2 < (2 * math.pi * 0.5) ** 2
    elastic = np.flatnonzero(~rigid_mask)
    if mode > elastic.size:
        raise ValueError(f"mode must be <= {elastic.size}, got {mode}")
    k = elastic[mode - 1]
    phi = V[:, k] / math.sqrt(V[:, k] @ L.M @ V[:, k])
    if L.S @ phi < 0:
        phi = -phi
    if abs(L.S @ phi) < 1e-9 * np.max(np.abs(phi)):
        log.warning("the sensor sits at a node of mode %d", mode)
    return math.sqrt(w2[k]), phi, V[:, rigid_mask], L, pts


def _interface_law(u, Fs, KT, phimax, chi, beta):
    """Virgin backbone force and tangent of every point (REFERENCE sec. 2)."""
    s = u / phimax
    F = Fs * normalized_backbone(s, chi, beta)
    a = np.minimum(np.abs(s), 1.0)
    kt = np.where(np.abs(s) < 1.0, KT * (1.0 - a ** (chi + 1.0) / (1.0 + beta)), 0.0)
    return F, kt


def static_modal_load(specimen: Specimen, amplitudes, *, mode: int = 1,
                      tol: float = 1e-10, max_iter: int = 60):
    """Nonlinear static solutions under ``alpha M phi`` reaching sensor amplitudes ``X``.

    Returns
    -------
    dict
        ``alpha`` (n,), ``x`` (n, n_free), ``q`` (n,), ``slip`` (n, n_points), ``omega0``,
        ``phi``, ``system`` (LinearSystem), ``points`` (ContactPoints), ``warnings``.
    """
    X = _amplitudes(specimen, amplitudes)
    w0, phi, R, L, pts = linear_modes(specimen, mode=mode)
    itf = specimen.interface
    Fs, KT, pm = pts.Fs, pts.KT, pts.phi_max
    A = L.K0.copy()
    if R.size:
        MR = L.M @ R
        A += w0 * w0 * (MR @ MR.T)
    b = L.M @ phi
    G, S = L.G, L.S
    n = A.shape[0]
    order = np.argsort(X)
    out_x = np.zeros((X.size, n))
    out_a = np.zeros(X.size)
    warns = []
    x = np.zeros(n)
    alpha = 0.0
    for j in order:
        Xt = X[j]
        scale = Xt / (S @ phi)
        if alpha == 0.0:
            x, alpha = phi * scale, w0 * w0 * scale
        else:
            r = Xt / (S @ x)
            x, alpha = x * r, alpha * r
        for it in range(max_iter):
            u = G @ x
            F, kt = _interface_law(u, Fs, KT, pm, itf.chi, itf.beta)
            res = np.concatenate([A @ x + G.T @ F - alpha * b, [S @ x - Xt]])
            J = np.zeros((n + 1, n + 1))
            J[:n, :n] = A + G.T @ (kt[:, None] * G)
            J[:n, n] = -b
            J[n, :n] = S
            d = np.linalg.solve(J, -res)
            x += d[:n]
            alpha += d[n]
            if np.linalg.norm(d[:n]) <= tol * np.linalg.norm(x):
                break
        else:
            warns.append(f"static solve at X = {Xt:.3e} m did not converge in {max_iter} "
                         "Newton iterations")
        out_x[j], out_a[j] = x, alpha
    q = out_x @ (L.M @ phi)
    return {"amplitude": X, "alpha": out_a, "x": out_x, "q": q, "slip": out_x @ G.T,
            "omega0": w0, "phi": phi, "system": L, "points": pts, "warnings": warns}


def modal_amplitude_curve(specimen: Specimen, *, mode: int = 1, amplitudes=None) -> AmplitudeCurve:
    """Amplitude-dependent frequency and damping of a mode by quasi-static modal analysis.

    Parameters
    ----------
    specimen : Specimen
    mode : int, keyword-only
        Elastic mode number (1: the lowest elastic mode).
    amplitudes : array_like, optional, keyword-only
        Displacement amplitudes at the specimen's sensor point [m]; default 20 log-spaced
        amplitudes over ``specimen.amplitude_range``.

    Returns
    -------
    AmplitudeCurve
        ``method="qsma"``; ``frequency`` is the secant natural frequency [Hz],
        ``damping_ratio`` the Masing damping of the contact points plus the specimen's
        damping floor.
    """
    if not isinstance(specimen, Specimen):
        raise ValueError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    r = static_modal_load(specimen, amplitudes, mode=mode)
    slip = np.abs(r["slip"])
    D = np.zeros(r["amplitude"].size)
    for i, p in enumerate(r["points"].params):
        D += dissipation(slip[:, i], p)
    alpha, q = r["alpha"], r["q"]
    w = np.sqrt(alpha / q)
    zeta = specimen.interface.damping_floor + D / (2 * math.pi * alpha * q)
    return AmplitudeCurve(
        r["amplitude"], w / (2 * math.pi), zeta, method="qsma",
        notes=(f"{specimen.name}: mode {mode}, {len(r['points'])} contact points, amplitude = "
               f"transverse displacement at x = {specimen.sensor_position:.4g} m; linear "
               f"(stuck) frequency {r['omega0'] / (2 * math.pi):.4f} Hz"),
        warnings=tuple(r["warnings"]))
