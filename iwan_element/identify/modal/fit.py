"""Modal Iwan identification from frequency and damping against amplitude.

The model is one mass-normalised mode with an Iwan joint and a viscous floor (Segalman 2005,
J. Appl. Mech. 72:752-760; docs/equations.md section 7; :mod:`iwan_element.core.modal`). The
sensor sees ``X = Phi q``, with the mode-shape value ``Phi`` at the sensor unknown. The
model is therefore written in the sensor coordinate with unit modal mass: the joint's
``phi_max`` is in metres at the sensor, ``KT`` and ``K_inf`` in 1/s^2 and ``Fs`` in m/s^2.
If the modal mass seen at the sensor, ``m_X = 1 / Phi**2`` [kg], is known, the physical
joint is ``Fs * m_X`` [N] and ``KT * m_X`` [N/m] at the sensor coordinate. Every curve below
depends on ``X / phi_max`` only, so nothing else is lost by this choice.

In microslip (every amplitude well below ``phi_max``) the closed forms reduce to::

    w(X)**2 = w0**2 (1 - s delta (X/X_ref)**(chi+1))
    zeta(X) = zeta_v + w0**2 delta (X/X_ref)**(chi+1) * 2 (chi+1) / (pi (chi+3)) / w(X)**2

with ``delta = KT (X_ref/phi_max)**(chi+1) / (w0**2 (chi+2)(1+beta))`` the relative drop of
``w**2`` at the reference amplitude ``X_ref`` (secant), ``s = 1`` for the secant stiffness
and ``s = 4 n Gamma(n+1/2) / (sqrt(pi) Gamma(n+2))``, ``n = chi+2``, for the first-harmonic
one. Such data fix ``f0``, ``zeta0``, ``chi`` and ``delta`` only: ``KT``, ``phi_max``,
``beta`` and ``Fs`` enter through ``delta`` alone. The fit reports just these four then, and
says so; the full six (``f0, zeta0, chi, kappa = KT/w0**2, phi_max, beta``) are reported
only when the curve visibly leaves microslip (a significant F-test and ``phi_max`` known to
within a factor e).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize, stats

from ...base.validation import check_scalar
from ...fitting import covariance
from ..files.units import check_damping_ratio
from ..loops.identifiability import MIN_MACRO_POINTS
from .curves import DECAY_METHODS, AmplitudeCurve
from .model import model_curve
from .result import ModalIwanFit

__all__ = ["fit_modal_iwan", "ModalIwanFit"]


def _as_data(amplitude, frequency, damping_ratio):
    if isinstance(amplitude, AmplitudeCurve):
        if frequency is not None or damping_ratio is not None:
            raise ValueError("give either an AmplitudeCurve or three arrays, not both")
        c = amplitude
        return (
            c.amplitude,
            c.frequency,
            c.damping_ratio,
            c.frequency_std,
            c.damping_ratio_std,
            tuple(c.warnings),
        )
    if frequency is None or damping_ratio is None:
        raise ValueError("frequency and damping_ratio are required with an amplitude array")
    c = AmplitudeCurve(amplitude, frequency, damping_ratio)  # the shared checks and messages
    return c.amplitude, c.frequency, c.damping_ratio, c.frequency_std, c.damping_ratio_std, ()


def _weights(f, z, fstd, zstd):
    """Per-point standard deviations; unknown ones are filled later from the residuals."""
    known = (
        np.all(np.isfinite(fstd))
        and np.all(np.isfinite(zstd))
        and np.all(fstd > 0)
        and np.all(zstd > 0)
    )
    if known:
        return np.array(fstd, dtype=float), np.array(zstd, dtype=float), True
    return np.full(f.size, 1e-4 * np.median(f)), np.full(z.size, 0.02 * np.median(np.abs(z))), False


def _solve(regime, x0, lb, ub, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form):
    def resid(theta):
        try:
            fm, zm = model_curve(theta, X, regime, x_ref, stiffness, floor, damping_form)
        except ValueError:
            return np.full(2 * X.size, 1e6)
        return np.concatenate([(fm - f) / sf, (zm - z) / sz])

    x0 = np.clip(x0, lb + 1e-9 * (ub - lb), ub - 1e-9 * (ub - lb))
    return optimize.least_squares(
        resid,
        x0,
        bounds=(lb, ub),
        x_scale="jac",
        method="trf",
        xtol=1e-10,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=200,
    )


def _fit_micro(X, f, z, sf, sz, x_ref, stiffness, floor, damping_form):
    f0 = float(f[np.argmin(X)]) * (1.0 + 1e-5)
    lb = np.array([0.5 * f.min(), 0.0, -0.999, 1e-12])
    ub = np.array([2.0 * f.max(), 0.999, 1.0, 0.999])
    best = None
    for chi in (-0.7, -0.4, 0.0, 0.5):
        drop = max(1.0 - (np.median(f) / f0) ** 2, 1e-6)
        x0 = np.array([f0, 0.8 * max(float(z.min()), 1e-6), chi, drop])
        r = _solve("microslip", x0, lb, ub, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form)
        if best is None or r.cost < best.cost:
            best = r
    return best


def _fit_full(micro, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form):
    f0, z0, chi, delta = micro.x
    xmax = float(X.max())
    lb = np.array([0.5 * f.min(), 0.0, -0.999, 1e-9, math.log(1e-3 * X.min()), 0.0])
    ub = np.array([2.0 * f.max(), 0.999, 1.0, 1.0 - 1e-9, math.log(1e3 * xmax), 100.0])
    best = None
    for ratio in (0.3, 1.0, 3.0):
        for beta in (0.5,):
            phimax = ratio * xmax
            kappa = delta * (chi + 2.0) * (1.0 + beta) * (phimax / x_ref) ** (chi + 1.0)
            if not 0.0 < kappa < 1.0:
                continue
            x0 = np.array([f0, z0, chi, kappa, math.log(phimax), beta])
            r = _solve("full", x0, lb, ub, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form)
            if best is None or r.cost < best.cost:
                best = r
    return best


def _covariance(r, n_data):
    """Covariance of the fitted vector: the package's one routine
    (:func:`iwan_element.fitting.covariance`, docs/fitting.md) with ``s^2 = max(1, reduced
    chi^2)`` (the weights are the stated uncertainties; a misfit widens them). Returns the
    covariance (degenerate directions left out) and the reduced chi-square.
    """
    J = r.jac
    dof = max(n_data - J.shape[1], 1)
    chi2_red = 2.0 * r.cost / dof
    if not np.all(np.isfinite(J)):
        return np.full((J.shape[1], J.shape[1]), np.nan), chi2_red
    return covariance(J, s2=max(chi2_red, 1.0)).covariance, chi2_red


def _damping_form(damping_form, amplitude):
    """The damping form checked, ``"auto"`` resolved by where the curve came from."""
    if damping_form not in ("auto", "decay", "energy"):
        raise ValueError(f"damping_form must be 'auto', 'decay' or 'energy', got {damping_form!r}")
    if damping_form == "auto":
        decay = isinstance(amplitude, AmplitudeCurve) and amplitude.method in DECAY_METHODS
        damping_form = "decay" if decay else "energy"
    return damping_form


def _check_model(stiffness, floor):
    """The stiffness and floor options checked."""
    if stiffness not in ("harmonic", "secant"):
        raise ValueError(f"stiffness must be 'harmonic' or 'secant', got {stiffness!r}")
    if floor not in ("dashpot", "constant"):
        raise ValueError(f"floor must be 'dashpot' or 'constant', got {floor!r}")


def _scatter_weights(micro, X, f, z, sf, sz, known, x_ref, stiffness, floor, damping_form):
    """Without given errors, weights from each curve's residual scatter and the refit."""
    noise_dof = None
    if not known:  # weights from each curve's own residual scatter
        fm, zm = model_curve(micro.x, X, "microslip", x_ref, stiffness, floor, damping_form)
        dof = noise_dof = max(X.size - 2, 1)
        sf = np.full(X.size, max(math.sqrt(np.sum((fm - f) ** 2) / dof), 1e-9 * np.median(f)))
        sz = np.full(X.size, max(math.sqrt(np.sum((zm - z) ** 2) / dof), 1e-9 * np.median(z)))
        micro = _fit_micro(X, f, z, sf, sz, x_ref, stiffness, floor, damping_form)
    return micro, sf, sz, noise_dof


def _regime(micro, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form, alpha, warns):
    """The full model, taken when an F-test rejects microslip and ``phi_max`` is fixed."""
    chosen, regime = micro, "microslip"
    n_data = 2 * X.size
    full = (
        _fit_full(micro, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form)
        if n_data > 7
        else None
    )
    if full is not None:
        cov_f, chi2_f = _covariance(full, n_data)
        F_stat = (micro.cost - full.cost) / max(chi2_f, 1e-300)  # (dchi2 / 2) / chi2_red
        p_val = float(stats.f.sf(F_stat, 2, max(n_data - 6, 1)))
        phi_known = math.sqrt(max(cov_f[4, 4], 0.0)) < 1.0
        beyond = int(np.count_nonzero(X > math.exp(full.x[4])))
        if p_val < alpha and phi_known and beyond >= MIN_MACRO_POINTS:
            chosen, regime = full, "macroslip"
        else:
            few = (
                ""
                if beyond >= MIN_MACRO_POINTS
                else f", {beyond} amplitude(s) beyond it where {MIN_MACRO_POINTS} are needed"
            )
            warns.append(
                f"the data never leave microslip (F-test p = {p_val:.2g}, phi_max "
                f"{'not ' if not phi_known else ''}bounded{few}): KT, phi_max, beta and Fs are "
                "not identified; reported f0, zeta0, chi and the microslip coefficient delta"
            )
    return chosen, regime, n_data


def fit_modal_iwan(
    amplitude,
    frequency=None,
    damping_ratio=None,
    *,
    stiffness: str = "harmonic",
    floor: str = "dashpot",
    x_ref: float | None = None,
    significance: float = 1e-3,
    damping_form: str = "auto",
) -> ModalIwanFit:
    """Identify a single-mode modal Iwan model with a viscous floor from f(X) and zeta(X).

    Model (Segalman 2005, J. Appl. Mech. 72:752-760; docs/equations.md section 7):
    ``w(X)**2 = K_inf + K(X)`` and ``zeta(X) = zeta_v + D(X) / (2 pi w(X)**2 X**2)`` with the
    Iwan joint's dissipation ``D`` and stiffness ``K`` (secant or first harmonic), in the
    sensor coordinate with unit modal mass (see the module docstring for units and for what
    microslip data can and cannot fix). Weighted least squares (``scipy.optimize.least_squares``)
    on both curves; per-point uncertainties are the weights when known, otherwise the
    weights come from the residual scatter of each curve (two passes).

    Parameters
    ----------
    amplitude : array_like or AmplitudeCurve
        Displacement amplitude at the sensor [m], or an :class:`AmplitudeCurve` (then
        ``frequency`` and ``damping_ratio`` are omitted and its uncertainties are used).
    frequency : array_like
        Natural frequency [Hz].
    damping_ratio : array_like
        Damping ratio [-] (a ratio, not percent): a value of 1 or more, or a curve never
        below 0.05, is refused as percent.
    stiffness : {"harmonic", "secant"}, keyword-only
        Stiffness the measurement sees: ``"harmonic"`` (default; ring-down and stepped-sine
        tests measure the first-harmonic stiffness) or ``"secant"`` (quasi-static modal
        analysis, QSMA).
    floor : {"dashpot", "constant"}, keyword-only
        Viscous floor: a fixed dashpot (default) or a constant ratio (docs/equations.md section 7).
    x_ref : float, optional
        Reference amplitude [m] of ``delta``; default the geometric mean of the amplitudes.
    significance : float, keyword-only
        Level of the F-test that must reject the microslip model before ``phi_max`` and
        ``beta`` are reported (default 1e-3, range (0, 0.5)). Under microslip ``phi_max`` is
        not identified, so the statistic's null distribution is heavier than the F
        distribution it is compared with (Davies 1987, Biometrika 74:33-43): at 0.01, exact
        microslip curves with 1 % damping noise came out as macroslip joints in 2 of 60
        seeds. As in :func:`~iwan_element.fit_decay`, the small default allows for that; and
        at least four amplitudes must lie beyond the fitted ``phi_max``.
    damping_form : {"auto", "decay", "energy"}, keyword-only
        What the measured damping ratio is: ``"decay"``, the decay rate of a free decay over
        ``w`` (``zeta = D / (2 pi (K_inf + K_t) X**2)``, the energy drained from a turning
        point, :func:`~iwan_element.modal_iwan_curve`); ``"energy"``,
        ``D / (2 pi w**2 X**2)`` (steady forced response, sweeps, QSMA). ``"auto"``
        (default): ``"decay"`` for a curve from :func:`~iwan_element.amplitude_curve`
        (method ``"hilbert"`` or ``"pff"``), else ``"energy"``.

    Returns
    -------
    ModalIwanFit
    """
    damping_form = _damping_form(damping_form, amplitude)
    X, f, z, fstd, zstd, in_warn = _as_data(amplitude, frequency, damping_ratio)
    check_damping_ratio("damping_ratio", z)
    _check_model(stiffness, floor)
    alpha = check_scalar(
        "significance", significance, low=0.0, high=0.5, low_open=True, high_open=True
    )
    if np.any(z < 0):
        raise ValueError("damping_ratio must be >= 0 for a modal Iwan fit")
    x_ref = (
        float(np.exp(np.mean(np.log(X))))
        if x_ref is None
        else check_scalar("x_ref", x_ref, low=0.0, low_open=True)
    )
    conv = dict(stiffness=stiffness, floor=floor, x_ref=x_ref, damping_form=damping_form)
    data = dict(
        amplitude=X, frequency=f, damping_ratio=z, frequency_std=fstd, damping_ratio_std=zstd
    )
    n_amp = np.unique(np.round(np.log(X), 9)).size
    if n_amp < 3:
        return ModalIwanFit.linear(
            data,
            conv,
            warnings=in_warn
            + (
                f"only {n_amp} distinct amplitude(s): the amplitude dependence cannot be "
                "identified; reported the mean frequency and damping ratio only",
            ),
        )
    sf, sz, known = _weights(f, z, fstd, zstd)
    micro = _fit_micro(X, f, z, sf, sz, x_ref, stiffness, floor, damping_form)
    micro, sf, sz, noise_dof = _scatter_weights(
        micro, X, f, z, sf, sz, known, x_ref, stiffness, floor, damping_form
    )
    warns = list(in_warn)
    chosen, regime, n_data = _regime(
        micro, X, f, z, sf, sz, x_ref, stiffness, floor, damping_form, alpha, warns
    )
    cov, chi2_red = _covariance(chosen, n_data)
    return ModalIwanFit.from_solution(
        chosen.x,
        cov,
        regime,
        data,
        conv,
        chi2_red=chi2_red,
        weights=(sf, sz),
        warnings=tuple(warns),
        optimizer_ok=bool(chosen.success),
        jac=chosen.jac,
        noise_dof=noise_dof,
    )
