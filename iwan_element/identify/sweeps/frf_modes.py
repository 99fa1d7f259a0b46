"""Linear modal targets from low-level FRFs or stepped-sine sweep points.

One mode per fit, drive point or transfer (``docs/modal_targets.md`` section 6): the
receptance near an isolated resonance,

    H(W) = X e^{i phi} / F = c / (w_r**2 - W**2 + 2 i zeta w_r W) + B,

with ``c = phi_drive phi_response`` [1/kg] the real modal constant of the mass-normalised mode
and ``B`` [m/N] a real residual of the other modes (constant over a narrow band; REFERENCE
relations as in ``docs/sweeps.md`` section 1, viscous damping term). Weighted least squares
of the complex receptance with relative residuals ``(H_model - H) / |H|``
(``scipy.optimize.least_squares``), standard errors from the package's covariance
(:func:`iwan_element.fitting.covariance`, ``s**2 (J^T J)^-1``). The points must come from a
level where the structure is linear: a sweep's response range is reported with the result,
and a fit whose relative misfit exceeds 5 % is flagged.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import optimize

from ...base.plausibility import QUANTITY_POWER, level_failure
from ...base.validation import check_magnitude, finite_array
from ...fitting import covariance
from ..modal.mode_target import ModeTarget
from ..modal.targets import ModalTargets
from .sweep import _convention, _inputs

__all__ = ["frf_modes", "sweep_modes", "sweep_receptance"]

#: Relative rms misfit above which a single linear mode does not describe the points.
_MISFIT = 0.05


def _model(p, W):
    wr, zeta, c, B = p
    return c / (wr * wr - W * W + 2j * zeta * wr * W) + B


def _fit(W, H, residual):
    """(params, stderr, rms, success) of the single-mode fit; params (w_r, zeta, c, B)."""
    mag = np.abs(H)
    k = int(np.argmax(mag))
    wr0 = W[k]
    half = W[mag >= mag[k] / math.sqrt(2.0)]
    zeta0 = min(max(0.5 * (half.max() - half.min()) / wr0, 1e-5), 0.2)
    c0 = float((H[k] * 2j * zeta0 * wr0 * wr0).real) or mag[k] * 2 * zeta0 * wr0 * wr0
    x0 = np.array([1.0, zeta0, c0 / (wr0 * wr0), 0.0])

    def unpack(x):
        return np.array([x[0] * wr0, x[1], x[2] * wr0 * wr0, x[3] if residual else 0.0])

    def res(x):
        r = (_model(unpack(x), W) - H) / mag
        return np.concatenate([r.real, r.imag])

    n_p = 4 if residual else 3
    sol = optimize.least_squares(
        lambda x: res(np.append(x, 0.0) if n_p == 3 else x),
        x0[:n_p],
        method="lm",
        x_scale="jac",
        xtol=1e-14,
        ftol=1e-14,
        max_nfev=4000,
    )
    x = sol.x if n_p == 4 else np.append(sol.x, 0.0)
    r = res(x)
    dof = max(r.size - n_p, 1)
    jac = np.diag([wr0, 1.0, wr0 * wr0, 1.0][:n_p])
    cov = covariance(sol.jac, r, dof=dof, Jp=jac)
    se = np.append(cov.stderr, 0.0) if n_p == 3 else cov.stderr
    return unpack(x), se, math.sqrt(float(r @ r) / dof), bool(sol.success)


def _targets(W, H, X, label, residual, source, notes):
    if W.size < 6:
        raise ValueError(f"f must hold at least 6 points around the resonance, got {W.size}")
    p, se, rms, ok = _fit(W, H, residual)
    warns = []
    if not ok:
        warns.append("the single-mode fit did not converge")
    if not (W.min() <= p[0] <= W.max()):
        raise ValueError(
            f"the points hold no resonance: the fitted natural frequency "
            f"{p[0] / 2 / math.pi:.5g} Hz lies outside f "
            f"({W.min() / 2 / math.pi:.5g}-{W.max() / 2 / math.pi:.5g} Hz)"
        )
    if not 0 < p[1] < 0.5:
        raise ValueError(
            f"the single-mode fit gives a damping ratio of {p[1]:.3g}: not a "
            "lightly damped resonance (check the phase convention)"
        )
    if rms > _MISFIT:
        warns.append(
            f"one linear mode fits the points to only {100 * rms:.2g} % rms: the "
            "level is not linear, another mode is near, or the phase is not that of "
            "the response relative to the force"
        )
    mode = ModeTarget(
        index=1,
        label=label,
        frequency=p[0] / (2 * math.pi),
        frequency_std=se[0] / (2 * math.pi),
        damping_ratio=p[1],
        damping_ratio_std=se[1],
        modal_constant=p[2],
        modal_constant_std=se[2],
        window=(float(W.min() / 2 / math.pi), float(W.max() / 2 / math.pi)),
        amplitude_range=(float(X.min()), float(X.max())),
        method="single-mode receptance least squares",
    )
    notes = (
        f"{notes}; {W.size} points, residual B = {p[3]:.4g} m/N (+-{se[3]:.2g}); "
        f"rms relative misfit {rms:.2g}"
    )
    return ModalTargets(modes=(mode,), source=source, notes=notes, warnings=tuple(warns))


def _complex_array(name, v) -> np.ndarray:
    """``v`` as a new complex array, or a ValueError naming ``name``."""
    try:
        return np.array(v, dtype=complex, copy=True)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be an array of complex numbers, got {type(v).__name__}"
        ) from None


def frf_modes(
    f, H, *, quantity: str = "displacement", residual: bool = True, label: str = "frf"
) -> ModalTargets:
    """Natural frequency, damping ratio and modal constant from a low-level complex FRF.

    Parameters
    ----------
    f : array_like, shape (n,)
        Frequency lines [Hz] around one resonance (n >= 6), > 0, distinct.
    H : array_like of complex, shape (n,)
        FRF at those lines, response over force, ``exp(+i W t)`` convention: receptance
        [m/N], mobility [m/s/N] or accelerance [m/s^2/N] after ``quantity``.
    quantity : {"displacement", "velocity", "acceleration"}, keyword-only
        What the response is (``H / (i W)**k`` is the receptance).
    residual : bool, keyword-only
        Fit the real residual ``B`` of the other modes (default True).
    label : str, keyword-only
        Label of the mode in the result.

    Returns
    -------
    ModalTargets
        One mode, ``source="frf"``, with ``modal_constant`` [1/kg]; ``window`` holds the
        lines' frequency range [Hz], ``amplitude_range`` the receptance magnitude range [m/N].

    Raises
    ------
    ValueError
        Malformed input (naming the argument), or points that hold no resonance.
    """
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    ff = check_magnitude("f", finite_array("f", f, min_size=6), unit="Hz")
    if np.any(ff <= 0) or np.unique(ff).size != ff.size:
        raise ValueError("f must be > 0 [Hz] and distinct")
    Hc = _complex_array("H", H)
    if Hc.shape != ff.shape or not np.all(np.isfinite(Hc)) or np.any(Hc == 0):
        raise ValueError(
            f"H must be finite, non-zero and of the shape of f {ff.shape}, got {Hc.shape}"
        )
    order = np.argsort(ff)
    W = 2 * math.pi * ff[order]
    Hd = Hc[order] / (1j * W) ** QUANTITY_POWER[quantity]
    return _targets(W, Hd, np.abs(Hd), str(label), residual, "frf", f"complex FRF ({quantity})")


def sweep_modes(
    f,
    F,
    response,
    phase,
    *,
    level=None,
    quantity: str = "acceleration",
    residual: bool = True,
    label: str = "sweep",
) -> ModalTargets:
    """Natural frequency, damping ratio and modal constant from low-level sweep points.

    Every point (drive frequency, fundamental force and response amplitudes, response phase
    relative to the force) is one line of a linear receptance: give only the points of the
    lowest level(s), where the structure is linear. The phase convention is read from the
    data by the rule of :func:`~iwan_element.sweep_curve` (``docs/sweeps.md`` section 3).

    Parameters
    ----------
    f, F, response, phase : array_like, shape (n,)
        Drive frequency [Hz], fundamental force amplitude [N] (> 0), fundamental response
        amplitude in SI units of ``quantity`` (> 0) and its phase relative to the force [rad].
    level : array_like, optional, keyword-only
        Sweep label per point (default: a new sweep where ``f`` turns round).
    quantity : {"acceleration", "velocity", "displacement"}, keyword-only
        What ``response`` is.
    residual : bool, keyword-only
        Fit the real residual ``B`` of the other modes (default True).
    label : str, keyword-only
        Label of the mode in the result.

    Returns
    -------
    ModalTargets
        One mode, ``source="sweep"``, with ``modal_constant`` [1/kg]; ``amplitude_range``
        the smallest and largest displacement amplitude of the points [m].

    Raises
    ------
    ValueError
        Malformed input, a phase convention that cannot be told, or points without a
        resonance.
    """
    pts = sweep_receptance(f, F, response, phase, level=level, quantity=quantity)
    W, X, H = 2.0 * math.pi * pts["f"], pts["X"], pts["H"]
    sweeps, conv_note = pts["sweeps"], pts["note"]
    out = _targets(W, H, X, str(label), residual, "sweep", f"{len(sweeps)} sweep(s), {conv_note}")
    wide = (
        (
            f"the points span displacement amplitudes {X.min():.3g}-{X.max():.3g} m (more "
            "than a factor of 3): a nonlinear structure is not linear over all of them",
        )
        if np.ptp(np.log(X)) > math.log(3.0)
        else ()
    )
    bad = level_failure(X, pts["f"], quantity=quantity, name="response")
    if wide or bad:
        out = ModalTargets(
            modes=out.modes,
            source=out.source,
            notes=out.notes,
            warnings=out.warnings + wide,
            failures=out.failures + ((bad,) if bad else ()),
        )
    return out


def sweep_receptance(f, F, response, phase, *, level=None, quantity: str = "acceleration") -> dict:
    """Stepped-sine points as a displacement receptance, the phase convention read from the
    data by the rule of :func:`~iwan_element.sweep_curve` (``docs/sweeps.md`` section 3).

    Parameters
    ----------
    f, F, response, phase, level, quantity
        As :func:`sweep_modes`.

    Returns
    -------
    dict
        ``f`` [Hz], ``F`` [N], ``X`` (the response's displacement amplitude [m]) and ``H``
        (complex receptance ``X e^{i phi} / F`` [m/N], ``exp(+i W t)``, positive modal
        constant), in the order given; ``sweeps`` (index arrays of each sweep, by
        frequency) and ``note`` (the convention read).

    Raises
    ------
    ValueError
        Malformed input or a phase convention that cannot be told (naming the argument).
    """
    if quantity not in QUANTITY_POWER:
        raise ValueError(f"quantity must be one of {sorted(QUANTITY_POWER)}, got {quantity!r}")
    arrs, sweeps = _inputs(f, F, response, phase, level)
    W = 2.0 * math.pi * arrs["f"]
    X = arrs["response"] / W ** QUANTITY_POWER[quantity]
    phd, note, _ = _convention(W, X, arrs["F"], arrs["phase"], sweeps, quantity)
    return {
        "f": arrs["f"],
        "F": arrs["F"],
        "X": X,
        "H": X * np.exp(1j * phd) / arrs["F"],
        "sweeps": sweeps,
        "note": note,
    }
