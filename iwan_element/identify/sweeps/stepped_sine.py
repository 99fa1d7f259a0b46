"""Frequency and damping against amplitude from stepped-sine (FRF) levels.

Each level of a stepped-sine test is a set of frequency lines around one resonance with the
complex response per unit force ``H`` (first harmonic) measured at one excitation level:

* force-controlled: the force amplitude ``F`` is held at every line; the level's amplitude
  is the peak displacement amplitude ``|H_d(f_r)| F``;
* response-controlled: the response amplitude is held at every line (the usual way to test a
  nonlinear joint: the structure is then linear at that amplitude and its FRF is exact);
  the level's amplitude is that response, converted to displacement.

Per level a single-mode model of the receptance ``H_d = H / (i w)**k`` (k = 0, 1, 2 for
displacement, velocity, acceleration) is fitted to the lines around the peak (those where
``|H_d| >= peak_fraction * max |H_d|``, contiguous with the peak)::

    H_d(w) = A / (w_r**2 - w**2 + 2 i zeta w_r**2) + B,      A, B complex

by separable least squares: for each ``(w_r, zeta)`` the complex modal constant ``A`` and
residual ``B`` solve a linear problem, and ``scipy.optimize.least_squares`` adjusts
``(w_r, zeta)``. Standard errors come from the Jacobian of the full six-parameter problem at
the solution and the residual scatter. The damping term is the structural (hysteretic) one,
``2 zeta w_r**2`` with ``zeta = eta / 2``: the first harmonic of a joint's friction force is
frequency independent, so at a held amplitude this form is exact for the joint and equals
the viscous ``2 zeta w_r w`` at the resonance; ``zeta`` is then the equivalent viscous damping
ratio of the modal Iwan closed forms (docs/equations.md section 7).

Force control distorts each level's peak (the amplitude, hence stiffness and damping, vary
along the sweep), so a fit of one level is biased. With one mode of fixed shape the modal
constant ``A`` (real for a mass-normalised mode) does not depend on the amplitude: ``A`` is
given (``modal_constant``) or taken from the fit of the level with the
smallest peak response (assumed nearly linear: a warning says so), and each level is read
at its peak line ``w_p``, where the response is ``X = |H_d(w_p)| F``, by inverting the
single-mode model there, other modes neglected: ``A / H_d = w_r**2 - w_p**2 + 2 i zeta w_r**2``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ...base.plausibility import QUANTITY_POWER, level_failure
from ...base.validation import check_scalar
from ...fitting import covariance
from ..modal.curves import AmplitudeCurve

__all__ = ["stepped_sine_curve"]


def _level_arrays(i, level):
    try:
        f, H, amp = level
    except (TypeError, ValueError):
        raise ValueError(
            f"levels[{i}] must be a triple (frequency [Hz], complex FRF, amplitude)"
        ) from None
    f = np.array(f, dtype=float, copy=True)
    H = np.array(H, dtype=complex, copy=True)
    if f.ndim != 1 or H.shape != f.shape or f.size < 5:
        raise ValueError(
            f"levels[{i}]: frequency and FRF must be 1-D of the same length >= 5, "
            f"got shapes {f.shape} and {H.shape}"
        )
    if not (np.all(np.isfinite(f)) and np.all(np.isfinite(H))):
        raise ValueError(f"levels[{i}]: frequency and FRF must be finite (no NaN)")
    if np.any(f <= 0) or np.unique(f).size != f.size:
        raise ValueError(f"levels[{i}]: frequencies must be > 0 [Hz] and distinct")
    amp = check_scalar(f"levels[{i}] amplitude", amp, low=0.0, low_open=True)
    order = np.argsort(f)
    return f[order], H[order], amp


def _peak_lines(Hd, frac):
    """Indices of the lines contiguous with the peak whose magnitude is >= frac * peak."""
    mag = np.abs(Hd)
    k = int(np.argmax(mag))
    lo = k
    while lo > 0 and mag[lo - 1] >= frac * mag[k]:
        lo -= 1
    hi = k
    while hi < mag.size - 1 and mag[hi + 1] >= frac * mag[k]:
        hi += 1
    if hi - lo + 1 < 5:  # too few: the five lines nearest the peak
        lo = max(0, min(k - 2, mag.size - 5))
        hi = lo + 4
    return np.arange(lo, hi + 1), k


def _linear_part(w, Hd, wr, zeta):
    basis = np.column_stack([1.0 / (wr**2 - w**2 + 2j * zeta * wr * wr), np.ones_like(w)])
    coef, *_ = np.linalg.lstsq(basis, Hd, rcond=None)
    return coef, basis


def _fit_sdof(w, Hd, wr0, z0):
    """Separable least-squares SDOF fit; returns (w_r, zeta, A, B, std(w_r), std(zeta))."""
    scale = np.max(np.abs(Hd))

    def res2(x):
        coef, basis = _linear_part(w, Hd, x[0] * wr0, x[1])
        r = (basis @ coef - Hd) / scale
        return np.concatenate([r.real, r.imag])

    sol = optimize.least_squares(
        res2,
        [1.0, z0],
        bounds=([0.5, 1e-7], [2.0, 0.5]),
        x_scale=[1e-3, z0],
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
    )
    wr, zeta = sol.x[0] * wr0, sol.x[1]
    (A, B), _ = _linear_part(w, Hd, wr, zeta)

    def res6(p):
        m = (p[2] + 1j * p[3]) / (p[0] ** 2 - w**2 + 2j * p[1] * p[0] ** 2) + (p[4] + 1j * p[5])
        r = (m - Hd) / scale
        return np.concatenate([r.real, r.imag])

    p = np.array([wr, zeta, A.real, A.imag, B.real, B.imag])
    steps = np.maximum(
        np.abs(p) * 1e-7,
        [1e-9 * wr, 1e-9, 1e-9 * abs(A), 1e-9 * abs(A), 1e-12 * scale, 1e-12 * scale],
    )
    r0 = res6(p)
    J = np.empty((r0.size, 6))
    for j in range(6):
        dp = np.zeros(6)
        dp[j] = steps[j]
        J[:, j] = (res6(p + dp) - res6(p - dp)) / (2 * steps[j])
    dof = max(r0.size - 6, 1)
    cov = covariance(J, r0, dof=dof).covariance  # docs/fitting.md section 1
    return wr, zeta, A, B, math.sqrt(max(cov[0, 0], 0.0)), math.sqrt(max(cov[1, 1], 0.0))


def _invert(A, B, w, H):
    """Per-line natural frequency squared and damping ratio from the single-mode model."""
    G = A / (H - B)
    wr2 = G.real + w * w
    return wr2, G.imag / (2.0 * wr2)


def _force_levels(fits, modal_constant):
    """Force control: each level read at its peak line with one real modal constant ``A``.

    At the peak line ``w_p`` the response is ``X = |H_d| F`` and the single-mode model
    inverts exactly: ``A / (H_d - B) = w_r**2 - w_p**2 + 2 i zeta w_r**2``. ``A`` is the
    given ``modal_constant`` or else ``|A|`` of the fit of the level with the smallest peak
    response (assumed nearly linear); other modes are neglected at the peak (``B = 0``).
    """
    ref = min(range(len(fits)), key=lambda i: fits[i][5])
    A = abs(fits[ref][3]) if modal_constant is None else modal_constant
    B = 0.0
    out = []
    for wp, Hp, F, _, _, _, _, _, s_w, s_z in fits:
        wr2, zeta = _invert(A, B, wp, Hp)
        out.append((abs(Hp) * F, math.sqrt(wr2) / (2 * math.pi), zeta, s_w, s_z))
    return np.array(out)


def _fit_level(i, level, k, frac):
    """The single-mode receptance fit of one level: its curve point and its fit."""
    f, H, amp = _level_arrays(i, level)
    w = 2.0 * math.pi * f
    Hd = H / (1j * w) ** k
    idx, kp = _peak_lines(Hd, frac)
    wr0 = w[kp]
    span = (w[idx[-1]] - w[idx[0]]) / wr0
    wr, zeta, A, B, swr, sz = _fit_sdof(w[idx], Hd[idx], wr0, max(0.25 * span, 1e-5))
    if not (w[0] <= wr <= w[-1]) or zeta >= 0.5 or zeta <= 1.5e-7:
        raise ValueError(
            f"levels[{i}] holds no resonance peak within its lines "
            f"({f[0]:.4g}-{f[-1]:.4g} Hz): the single-mode fit gives "
            f"f_r = {wr / 2 / math.pi:.4g} Hz, zeta = {zeta:.3g}"
        )
    row = (amp / wr**k, wr / (2 * math.pi), zeta, swr / (2 * math.pi), sz)
    fit = (
        w[kp],
        Hd[kp],
        amp,
        A,
        B,
        abs(A / (2j * zeta * wr * wr) + B) * amp,
        wr,
        zeta,
        swr / (2 * math.pi),
        sz,
    )
    return row, fit


def stepped_sine_curve(
    levels,
    *,
    quantity: str = "displacement",
    control: str = "force",
    peak_fraction: float = 0.5,
    modal_constant: float | None = None,
) -> AmplitudeCurve:
    """Resonance frequency and damping ratio per stepped-sine level, as an amplitude curve.

    Parameters
    ----------
    levels : sequence of (frequency, frf, amplitude)
        One triple per excitation level: ``frequency`` [Hz] (>= 5 lines around one
        resonance), ``frf`` the complex first-harmonic response per unit force at those lines
        ([m/N], [m/s/N] or [m/s^2/N] after ``quantity``) and ``amplitude``: the force
        amplitude [N] held during the level (``control="force"``) or the response amplitude
        held (``control="response"``, in the units of ``quantity``).
    quantity : {"displacement", "velocity", "acceleration"}, keyword-only
        What the response is.
    control : {"force", "response"}, keyword-only
        What was held constant during each level.
    peak_fraction : float, keyword-only
        Lines with ``|H_d| >= peak_fraction * max |H_d|`` next to the peak are fitted
        (default 0.5, range [0.1, 0.95]; at least the five lines nearest the peak).
    modal_constant : float, optional
        Force control only: the real modal constant ``A = phi_in phi_out`` of the
        mass-normalised mode [1/kg] (receptance ``A / (w_r**2 - w**2 + ...)``), e.g. from a
        low-level linear test or a model. Without it ``|A|`` of the smallest level's fit is
        used. Other modes are neglected at the peak line.

    Returns
    -------
    AmplitudeCurve
        ``amplitude`` [m] (displacement at the sensor: the peak response for force control,
        the held response for response control), ``frequency`` [Hz] (``w_r / 2 pi``),
        ``damping_ratio`` [-] with standard errors, ``method="stepped-sine"``.

    Raises
    ------
    ValueError
        Malformed levels, or a level whose fitted resonance lies outside its frequency lines
        (no peak in the data).
    """
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    if control not in ("force", "response"):
        raise ValueError(f"control must be 'force' or 'response', got {control!r}")
    frac = check_scalar("peak_fraction", peak_fraction, low=0.1, high=0.95)
    A_given = (
        None
        if modal_constant is None
        else check_scalar("modal_constant", modal_constant, low=0.0, low_open=True)
    )
    if isinstance(levels, (str, bytes, dict)) or not hasattr(levels, "__iter__"):
        raise ValueError(
            f"levels must be a sequence of (frequency, frf, amplitude) triples, "
            f"got {type(levels).__name__}"
        )
    levels = list(levels)
    if not levels:
        raise ValueError("levels must hold at least one (frequency, frf, amplitude) triple")
    k = QUANTITY_POWER[quantity]
    rows, fits = [], []
    for i, level in enumerate(levels):
        row, fit = _fit_level(i, level, k, frac)
        rows.append(row)
        fits.append(fit)
    a = np.array(rows)
    warns = []
    if control == "force":
        a = _force_levels(fits, A_given)
        if A_given is None and len(levels) > 1:
            warns.append(
                "force control without modal_constant: the modal constant was taken "
                "from the smallest level, assumed linear; if that level is already "
                "nonlinear the damping ratios are biased (give modal_constant)"
            )
    notes = (
        f"{len(levels)} {control}-controlled levels ({quantity}); single-mode receptance "
        f"fit A/(w_r^2 - w^2 + 2i zeta w_r^2) + B on the lines above {frac:g} x peak"
        + (
            "; force control: each level read at its peak line with one real modal constant"
            if control == "force"
            else ""
        )
    )
    if len(levels) < 3:
        warns.append(f"only {len(levels)} level(s): too few to show an amplitude dependence")
    return AmplitudeCurve(
        a[:, 0],
        a[:, 1],
        a[:, 2],
        frequency_std=a[:, 3],
        damping_ratio_std=a[:, 4],
        method="stepped-sine",
        notes=notes,
        warnings=tuple(warns),
        failures=tuple(
            w for w in [level_failure(a[:, 0], a[:, 1], quantity=quantity, name="levels")] if w
        ),
    )
