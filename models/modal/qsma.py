"""Quasi-static modal analysis (QSMA) of a lap-jointed specimen.

Lacayo & Allen (MSSP 118:133-157, 2019; docs/equations.md section 7 steps 1-6), on the linear beam
matrices extracted once from the Exudyn model
(:func:`~iwan_element.models.reduced.dispatch.linear_system`) and the closed-form Iwan backbones of
the contact points:

1. preload: the normal preload does not load the tangential elements here (no Poisson
   coupling), so ``x0 = 0`` and the stuck tangent is ``K = K0 + G^T diag(KT_i) G``;
2. mass-normalised eigenpair ``(w_k, phi)`` of ``(K, M)`` for the requested elastic mode;
3. static load ``alpha M phi``: ``K0 x + G^T F(G x) = alpha M phi`` with ``F_i`` the virgin
   backbone of point ``i`` (docs/equations.md section 2), condensed statically onto the
   contact slips ``u = G x`` and solved by Newton with the backbones' tangents, bordered with
   ``S x = X`` so that each requested sensor amplitude ``X`` is hit exactly;
4. ``q = phi^T M x`` and secant ``w^2 = alpha / q``;
5. Masing damping from the sum of the contact points' dissipations at their slip
   amplitudes ``u_i = |G_i x|`` (closed form, docs/equations.md section 2) rather than the modal
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
from functools import lru_cache
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from iwan_element import AmplitudeCurve, dissipation
from iwan_element.base.threads import one_blas_thread
from iwan_element.base.validation import check_magnitude, finite_array
from iwan_element.core.masing import constants_from_arrays, masing_rows
from iwan_element.effects import EFFECTS

from ..reduced.dispatch import (
    check_kept_mode,
    check_specimen,
    contact_points,
    linear_system,
)
from ..reduced.model import reduced_model, stuck_key, stuck_modes
from ..solid.specimen import SolidSpecimen
from ..specimens.specimen import Specimen
from .interface import interface_laws
from .interface_fit import fit_interface_effects
from .limits import macroslip_report, size_warnings

if TYPE_CHECKING:
    from ..linear.system import LinearSystem
    from ..specimens.contact import ContactPoints

__all__ = [
    "modal_amplitude_curve",
    "linear_modes",
    "natural_frequencies",
    "static_modal_load",
    "extrapolation_warnings",
    "resolve_interface_effects",
]

log = logging.getLogger(__name__)

#: A 1-D or solid specimen, the same kind in and out.
SpecimenT = TypeVar("SpecimenT", bound=Specimen | SolidSpecimen)


def _check_mode(mode) -> int:
    if isinstance(mode, bool) or not isinstance(mode, (int, np.integer)) or mode < 1:
        raise ValueError(f"mode must be an integer >= 1 (1: first elastic mode), got {mode!r}")
    return int(mode)


def _amplitudes(specimen: Specimen | SolidSpecimen, amplitude) -> np.ndarray:
    if amplitude is None:
        lo, hi = specimen.amplitude_range
        return np.geomspace(lo, hi, 20)
    a = check_magnitude("amplitude", finite_array("amplitude", amplitude, ndim=None), unit="m")
    a = np.atleast_1d(a)
    if a.ndim != 1 or a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise ValueError("amplitude must be a non-empty 1-D sequence of finite values > 0 [m]")
    return a


def linear_modes(
    specimen: Specimen | SolidSpecimen, *, mode: int = 1
) -> tuple[float, NDArray[np.float64], NDArray[np.float64], LinearSystem, ContactPoints]:
    """Stuck-interface mode of a specimen: ``(omega [rad/s], phi, rigid, L, points)``.

    Read from the specimen's reduced model's eigenproblem
    (:func:`~iwan_element.models.reduced.model.stuck_modes`: the same modes harmonic balance, EPMC
    and the transient use). ``phi`` (free coordinates)
    is mass-normalised with a positive sensor displacement; ``rigid`` holds the rigid-body
    modes (columns, mass-normalised; empty when clamped). A mode beyond those a solid's
    reduction kept is refused
    (:func:`~iwan_element.models.reduced.dispatch.check_kept_mode`).
    """
    mode = _check_mode(mode)
    L, pts, w, V, n_low = stuck_modes(specimen)
    n_rigid = L.rigid_body_modes
    if n_low > n_rigid:
        log.warning(
            "%d elastic mode(s) below 0.5 Hz (the interface lets the beams slide "
            "almost freely); mode numbers count from the next one",
            n_low - n_rigid,
        )
    k = max(n_low, n_rigid) + mode - 1
    check_kept_mode(specimen, k, name="mode", value=mode, offset=max(n_low, n_rigid))
    if k >= w.size:
        raise ValueError(f"mode must be <= {w.size - max(n_low, n_rigid)}, got {mode}")
    phi = V[:, k]
    if abs(L.S @ phi) < 1e-9 * np.max(np.abs(phi)):
        log.warning("the sensor sits at a node of mode %d", mode)
    return float(w[k]), phi.copy(), V[:, :n_rigid].copy(), L, pts


def natural_frequencies(
    specimen: Specimen, *, n_modes: int = 3, interface: str = "stuck"
) -> np.ndarray:
    """Lowest natural frequencies [Hz] of the linearised specimen, with or without the joint.

    Parameters
    ----------
    specimen : Specimen
    n_modes : int, keyword-only
        How many (>= 1), rigid-body modes of a free-free specimen included (about 0 Hz). A
        solid gives no more than its reduction kept (``kept_modes``: ValueError beyond, the
        rest of its basis being attachment shapes, not modes).
    interface : {"stuck", "none"}, keyword-only
        ``"stuck"``: every contact point at its tangential stiffness ``KT_i`` (the small-
        amplitude limit, ``K0 + G^T diag(KT) G``; :func:`linear_modes` gives the shapes);
        ``"none"``: no tangential stiffness, the beams held together by the normal contact
        springs only (the limit of a fully slipped lap; beam B's axial sliding is then a
        mode at about 0 Hz).

    Returns
    -------
    ndarray, shape (n_modes,)
    """
    if interface not in ("stuck", "none"):
        raise ValueError(f"interface must be 'stuck' or 'none', got {interface!r}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ValueError(f"n_modes must be an integer >= 1, got {n_modes!r}")
    check_kept_mode(specimen, int(n_modes) - 1, name="n_modes", value=n_modes, offset=0)
    if interface == "stuck":  # the one stuck eigenproblem (reduced model)
        w = stuck_modes(specimen)[2]
        return w[: min(int(n_modes), w.size)] / (2 * math.pi)
    L = linear_system(specimen)
    top = min(int(n_modes), L.K0.shape[0]) - 1
    with one_blas_thread():
        w2 = sla.eigh(L.K0, L.M, subset_by_index=[0, top], eigvals_only=True)
    return np.sqrt(np.abs(w2)) / (2 * math.pi)


def _interface_law(u, Fs, KT, phimax, chi, beta):
    """Virgin-curve force [N] and tangent [N/m] of every point: one step from rest of the
    package's exact Masing kernel (:func:`iwan_element.core.masing.masing_rows`), one
    parameter set per point.
    """
    u = np.asarray(u, float)
    Fs, KT, phimax = (np.broadcast_to(x, u.shape) for x in (Fs, KT, phimax))
    C = constants_from_arrays(Fs, KT, chi, beta, phi_max=phimax)
    F, K, _, _ = masing_rows(C, u.reshape(-1, 1))
    return F.reshape(u.shape), K.reshape(u.shape)


def _prepare_key(specimen: Specimen | SolidSpecimen, mode: int):
    return stuck_key(specimen), mode


@lru_cache(maxsize=32)
def _condensed(key):
    """Static condensation onto the contact slips (depends on geometry and KT_i only).

    With the stuck tangent ``A = K0 + G^T diag(KT) G`` (plus the rigid-body penalty) and
    the interface force deficit ``d(u) = F(u) - KT u``, every static state is
    ``x = alpha A^-1 M phi - A^-1 G^T d(u)`` and ``A^-1 M phi = phi / w0^2``. The port
    quantities (``C = G A^-1 G^T``, ``S A^-1 G^T`` and the mode at the slips and the sensor)
    are read from the specimen's reduced model
    (:func:`~iwan_element.models.reduced.model.reduced_model`: its static flexibility at the ports
    is exact, kept modes plus residual); ``A^-1 G^T`` on every
    coordinate is kept for the release state ``x`` of the transient.
    """
    specimen, mode = key
    with one_blas_thread():  # small dense problems: threads only contend
        w0, phi, R, L, pts = linear_modes(specimen, mode=mode)
        A = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
        if R.size:
            MR = L.M @ R
            A = A + w0 * w0 * (MR @ MR.T)
        YG = sla.cho_solve(sla.cho_factor(A), L.G.T)
    red = reduced_model(specimen, n_modes=max(8, mode))
    sysm = red.system
    nz = sysm.n_z
    H0 = sysm.receptance(0.0).real
    Y = sysm.modes[:, red.mode_index(mode)] / (w0 * w0)
    return {
        "w0": w0,
        "phi": phi,
        "L": L,
        "Yb": phi / (w0 * w0),
        "YG": YG,
        "C": H0[:nz, :nz],
        "ub": Y[:nz],
        "sb": float(Y[nz]),
        "sG": H0[nz, :nz],
        "qb": 1.0 / (w0 * w0),
        "qG": Y[:nz],
    }


def static_modal_load(
    specimen: Specimen | SolidSpecimen,
    amplitude,
    *,
    mode: int = 1,
    tol: float = 1e-12,
    max_iter: int = 60,
) -> dict[str, Any]:
    """Nonlinear static solutions under ``alpha M phi`` reaching sensor amplitudes ``X``.

    Newton on the condensed equations (:func:`_condensed`) in the contact slips ``u`` and
    the load factor ``alpha``, bordered with ``S x = X``.

    Returns
    -------
    dict
        ``amplitude`` (n,), ``alpha`` (n,), ``x`` (n, n_free), ``q`` (n,), ``slip``
        (n, n_points), ``omega0``, ``phi``, ``system`` (LinearSystem), ``points``
        (ContactPoints), ``warnings``.
    """
    X = _amplitudes(specimen, amplitude)
    mode = _check_mode(mode)
    specimen = resolve_interface_effects(specimen)
    laws = interface_laws(specimen)
    c = _condensed(_prepare_key(specimen, mode))
    pts = contact_points(specimen)
    itf = specimen.interface
    Fs, KT, pm = pts.Fs, pts.KT, pts.phi_max
    C, ub, sb, sG = c["C"], c["ub"], c["sb"], c["sG"]
    n = len(KT)
    eye = np.eye(n)
    out_u = np.zeros((X.size, n))
    out_a = np.zeros(X.size)
    warns = []
    u, alpha, X_prev = None, 0.0, None
    for j in np.argsort(X):
        Xt = X[j]
        if u is None:
            alpha = Xt / sb
            u = alpha * ub
        else:
            r = Xt / X_prev
            u, alpha = u * r, alpha * r
        for _ in range(max_iter):
            F, kt = _interface_law(u, Fs, KT, pm, itf.chi, itf.beta)
            if laws is not None:  # the interface effects beside each point's joint
                Fe, Ke = laws.backbone(u)
                F, kt = F + Fe, kt + Ke
            d = F - KT * u
            res = np.concatenate([u - alpha * ub + C @ d, [alpha * sb - sG @ d - Xt]])
            J = np.empty((n + 1, n + 1))
            J[:n, :n] = eye + C * (kt - KT)[None, :]
            J[:n, n] = -ub
            J[n, :n] = -sG * (kt - KT)
            J[n, n] = sb
            step = np.linalg.solve(J, -res)
            u += step[:n]
            alpha += step[n]
            if np.max(np.abs(step[:n])) <= tol * max(np.max(np.abs(u)), 1e-300) and abs(
                step[n]
            ) <= tol * abs(alpha):
                break
        else:
            warns.append(_unsolved(Xt, max_iter, np.abs(u) / pm, X_prev, out_u, X, pm))
        out_u[j], out_a[j], X_prev = u, alpha, Xt
    F, _ = _interface_law(out_u, Fs, KT, pm, itf.chi, itf.beta)
    if laws is not None:
        F = F + laws.backbone(out_u)[0]
    d = F - KT * out_u
    x = out_a[:, None] * c["Yb"][None, :] - d @ c["YG"].T
    q = out_a * c["qb"] - d @ c["qG"]
    return {
        "amplitude": X,
        "alpha": out_a,
        "x": x,
        "q": q,
        "slip": out_u,
        "omega0": c["w0"],
        "phi": c["phi"],
        "system": c["L"],
        "points": pts,
        "slip_ratio": np.abs(out_u) / pm,
        "warnings": warns,
        "laws": laws,
    }


def _unsolved(Xt, max_iter, ratio, X_prev, out_u, X, pm) -> str:
    """Why the static solve at ``Xt`` [m] stopped: the slip state of its last iterate
    (``ratio``: slip over ``phi_max`` per point) and the largest amplitude solved before it.
    """
    n, full = ratio.size, int(np.sum(ratio >= 1.0))
    if full == n:
        state = (
            f"the interface fully slipped at its last iterate (macroslip: all {n} contact "
            "points at or beyond their slip displacement phi_max), where the lap holds no "
            "more than its slip forces mu N"
        )
    else:
        state = f"{full} of {n} contact points fully slipped (beyond phi_max) at its last iterate"
    if X_prev is not None:
        k = int(np.flatnonzero(X == X_prev)[0])
        n_prev = int(np.sum(np.abs(out_u[k]) / pm >= 1.0))
        state += (
            f"; the largest amplitude solved: X = {X_prev:.3e} m ({n_prev} of {n} fully slipped)"
        )
    return (
        f"static solve at X = {Xt:.3e} m did not converge in {max_iter} Newton iterations: {state}"
    )


def modal_amplitude_curve(specimen: Specimen, *, mode: int = 1, amplitude=None) -> AmplitudeCurve:
    """Amplitude-dependent frequency and damping of a mode by quasi-static modal analysis.

    Parameters
    ----------
    specimen : Specimen
    mode : int, keyword-only
        Elastic mode number (1: the lowest elastic mode).
    amplitude : array_like, optional, keyword-only
        Displacement amplitudes at the specimen's sensor point [m]; default 20 log-spaced
        amplitudes over ``specimen.amplitude_range``.

    Returns
    -------
    AmplitudeCurve
        ``method="qsma"``; ``frequency`` is the secant natural frequency [Hz],
        ``damping_ratio`` the Masing damping of the contact points plus the specimen's
        damping floor, with the modal forms of the specimen's ``effects`` on this mode
        applied on top (``docs/vibration_effects.md``). ``warnings`` states amplitudes
        outside the specimen's (or an effect's) calibrated range (its documented
        ``amplitude_range`` when it has none) or its size, and the bolts whose contact is
        fully slipped (:mod:`~iwan_element.models.modal.limits`; also logged); a whole lap
        fully slipped makes it not usable (``failures``).

    Raises
    ------
    ValueError
        Where the static solve does not converge (the interface lost in macroslip): the
        amplitude, its slip state and the largest amplitude solved.
    """
    check_specimen(specimen)
    specimen = resolve_interface_effects(specimen)
    r, f, zeta = _curve(specimen, mode, amplitude)
    X = r["amplitude"]
    names = [e.name for e in specimen.effects if e.mode == mode]
    slipped, failures = macroslip_report(specimen, r["slip_ratio"], X, unit="m", what="amplitudes")
    warns = extrapolation_warnings(specimen, X) + size_warnings(specimen, X) + slipped
    for w_ in warns + failures:
        log.warning("%s", w_)
    return AmplitudeCurve(
        X,
        f,
        zeta,
        method="qsma",
        notes=(
            f"{specimen.name}: mode {mode}, {len(r['points'])} contact points, amplitude = "
            f"transverse displacement at x = {specimen.sensor_position:.4g} m; linear "
            f"(stuck) frequency {r['omega0'] / (2 * math.pi):.4f} Hz"
            + (f"; with {' + '.join(names)} (modal form)" if names else "")
            + (
                f"; with {' + '.join(e.name for e in specimen.interface_effects)} in the joint"
                if specimen.interface_effects
                else ""
            )
        ),
        warnings=tuple(warns),
        failures=tuple(failures),
    )


def _curve(specimen, mode, amplitude):
    """``(static solution, frequency [Hz], damping ratio [-])`` of QSMA (steps 3-6, module
    docstring) with the interface effects' backbones in the static solve and their energy
    per cycle in the damping (at the secant frequency), then the modal forms of ``mode``'s
    effects on top. ``specimen``'s interface effects must have their joint values.
    """
    r = static_modal_load(specimen, amplitude, mode=mode)
    if r["warnings"]:
        raise ValueError("amplitude: QSMA stops here: " + "; ".join(r["warnings"]))
    slip = np.abs(r["slip"])
    D = np.zeros(r["amplitude"].size)
    for i, p in enumerate(r["points"].params):
        D += dissipation(slip[:, i], p)
    alpha, q = r["alpha"], r["q"]
    w = np.sqrt(alpha / q)
    if r["laws"] is not None:
        D += r["laws"].dissipation(slip, w).sum(axis=1)
    floor = specimen.floor(mode)
    zeta = floor + D / (2 * math.pi * alpha * q)
    f = w / (2 * math.pi)
    for e in specimen.effects:
        if e.mode == mode:
            f, zeta = EFFECTS[e.name].modal_form(r["amplitude"], f, zeta, floor, **e.parameters)
    return r, f, zeta


def _fit_curve(specimen, mode, X):
    """QSMA's ``(frequency, damping ratio)`` for the interface fit."""
    _, f, zeta = _curve(specimen, mode, X)
    return f, zeta


def resolve_interface_effects(specimen: SpecimenT) -> SpecimenT:
    """``specimen`` with every interface effect given by its modal fit (``fitted_on``, e.g.
    from ``VibrationDiagnosis.augment``) mapped to the contact points and fitted so that the
    physical interface's QSMA reproduces the modal form on that mode
    (:mod:`~iwan_element.models.modal.interface_fit`; each fitted effect states its
    ``fit_misfit``); ``specimen`` itself when every effect has joint values. Every analysis
    calls it; call it once to keep the joint values when carrying the joint to another
    specimen (cached).
    """
    if all(e.resolved for e in specimen.interface_effects):
        return specimen
    return _resolved(specimen)


@lru_cache(maxsize=16)
def _resolved(specimen):
    return fit_interface_effects(specimen, curve=_fit_curve)


def extrapolation_warnings(specimen: Specimen, amplitude) -> list:
    """Warnings for sensor amplitudes [m] outside the range the specimen was calibrated on
    (its documented ``amplitude_range`` when it has no ``calibrated_range``), or above the
    range an effect it carries was fitted on (below it the effects' modal forms fade or stay
    constant, and the specimen's own range governs); empty when inside.
    """
    X = np.asarray(amplitude, float)
    out = []
    if specimen.calibrated_range is None:  # not calibrated: its documented range
        lo, hi = specimen.amplitude_range
        bad = (X > hi * (1 + 1e-6)) | (X < lo * (1 - 1e-6))
        if bad.any():
            k = max(float(X.max() / hi), float(lo / X.min()))
            out.append(
                f"{int(bad.sum())} of {X.size} amplitudes ({X[bad].min():.3g} .. "
                f"{X[bad].max():.3g} m) lie outside the documented amplitude_range "
                f"{lo:.3g} .. {hi:.3g} m of {specimen.name} (up to {k:.3g} x beyond), "
                "which has no calibrated_range: extrapolated beyond what its tests covered"
            )
    for label, cr in [("the specimen", specimen.calibrated_range)] + [
        (f"its {e.name}", e.calibrated_range) for e in specimen.effects
    ]:
        own = label == "the specimen"
        if cr is None or (
            not own
            and specimen.calibrated_range is not None
            and cr[1] == specimen.calibrated_range[1]
        ):
            continue
        lo, hi = cr
        bad = X > hi * (1 + 1e-6)
        if own:  # an effect's modal form fades towards X -> 0
            bad |= X < lo * (1 - 1e-6)
        if bad.any():
            k = max(float(X.max() / hi), float(lo / X.min()) if own else 0.0)
            out.append(
                f"{int(bad.sum())} of {X.size} amplitudes ({X[bad].min():.3g} .. "
                f"{X[bad].max():.3g} m) lie outside the range {lo:.3g} .. {hi:.3g} m "
                f"that {label} ({specimen.name}) was calibrated on (up to {k:.3g} x "
                "beyond): extrapolated"
            )
    return out
