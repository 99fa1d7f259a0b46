"""Fit any displacement-driven force model to a measured record, with sensor offsets.

:func:`fit_force_model` is the general least-squares engine behind the loop fits: a force
model ``model(u, theta) -> F`` (a base joint with or without an effect, driven by a
displacement history from its own initial state) is fitted together with the two sensor zero
offsets, which every loop fit carries as nuisance parameters::

    F_measured(t) = model(u_measured(t) - du0, theta)[t] + dF0

Why the record's start is left out (``burn_in``)
    A measured record rarely starts from the virgin, unloaded state the model starts from.
    For a Masing/Iwan joint, a monotone sweep over a displacement range ``2 A`` puts every
    slider that yields within ``A`` into a state fixed by the sweep alone; the stronger sliders
    keep an unknown elastic preload but do not slip later if the record stays within the
    sweep, so the unknown initial state adds only a constant force, which ``dF0`` absorbs.
    The residuals are therefore taken from the second turning point of the displacement on.

Displacement offset
    After that sweep a pure Iwan joint depends only on displacement differences, so ``du0``
    is not determined by the data; models with an absolute position (a backlash gap centred at
    zero, pinning) do determine it. A parameter whose Jacobian column is (numerically) a
    combination of the others gets ``stderr = NaN`` and ``identified = False``.

Uncertainty (documented choice: residual-based, widened by the residual's correlation)
    ``cov = tau s^2 (J^T J)^-1`` with ``s^2 = SSR/(m - p)`` and ``tau`` the integrated
    autocorrelation time of the residuals (Geyer's initial positive sequence, in fitted
    samples). ``s^2`` contains both channels' noise (the force noise and the tangent stiffness
    times the displacement error); ``tau`` is 1 for white residuals and grows when the
    residual is coloured noise or a systematic misfit, which widens the standard errors by
    ``sqrt(tau)`` instead of hiding behind many correlated samples. The displacement that
    drives the model is de-noised first (``smooth="auto"``, a Savitzky-Golay filter), so
    noise in ``u`` does not create spurious reversals (the errors-in-variables bias). The
    covariance and the verdict are the package's one routine and rule
    (:func:`iwan_element.fitting.covariance`, :func:`iwan_element.fitting.verdict`,
    docs/fitting.md).
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs, savgol_filter

from ...base.result_shape import ResultShape, value_stderr
from ...base.validation import check_int, check_magnitude, check_time, finite_array, same_length
from ...fitting import Parameter, ParameterTable, covariance, fit_success, minimize, verdict
from .cycles import find_reversals
from .noise import estimate_noise, integrated_time

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["ModelFit", "fit_force_model", "drive_displacement", "burn_in_index"]

log = logging.getLogger(__name__)
OFFSET_NAMES = ("dF0", "du0")


def burn_in_index(u: np.ndarray, *, hysteresis: float | None = None) -> int:
    """First sample after the second turning point of ``u`` (0 if there are fewer than 2)."""
    rev = find_reversals(u, hysteresis=hysteresis)
    return int(rev[1]) if rev.size >= 2 else 0


def drive_displacement(t, u, smooth="auto") -> tuple[NDArray[np.float64], dict[str, float]]:
    """The displacement that drives the model, and what was done to it.

    Parameters
    ----------
    t, u : ndarray, shape (n,)
        Time [s] and measured displacement [m].
    smooth : "auto", 0 or odd int >= 5
        ``0``: ``u`` as measured. An odd window: quintic Savitzky-Golay filter over that many
        samples. ``"auto"``: the window of :func:`~iwan_element.identify.loops.noise.estimate_noise`
        (``1/8`` of the fastest loading period) when the noise exceeds ``1e-4`` of the half
        range of ``u``, else no filter.

    Returns
    -------
    u_drive : ndarray
    info : dict
        ``smooth`` (window used, 0 for none), ``displacement_noise`` [m] and ``drive_noise``
        [m], the noise left in ``u_drive``.
    """
    n = u.size
    ne = estimate_noise(t, u) if n >= 32 else None
    sig = ne.sigma if ne is not None else 0.0
    if isinstance(smooth, str):
        if smooth != "auto":
            raise ValueError(f"smooth must be 'auto', 0 or an odd window >= 7, got {smooth!r}")
        w = 0
        if ne is not None and sig > 1e-4 * 0.5 * float(np.ptp(u)):
            dt = float(np.median(np.diff(t)))
            w = int(round(ne.window / dt)) | 1
            w = w if 7 <= w < n else 0
    else:
        w = check_int("smooth", smooth, 0)
        if w and (w < 7 or w % 2 == 0 or w >= n):
            raise ValueError(
                f"smooth must be 'auto', 0 or an odd window of at least 7 samples "
                f"below the record length {n}, got {smooth}"
            )
    u_drive = savgol_filter(u, w, 5) if w else u
    left = sig * math.sqrt(float(savgol_coeffs(w, 5)[w // 2])) if w else sig
    return u_drive, {"smooth": int(w), "displacement_noise": float(sig), "drive_noise": float(left)}


@dataclass(frozen=True, eq=False)
class ModelFit(ResultShape):
    """Result of :func:`fit_force_model`.

    Attributes
    ----------
    params : ParameterTable
        The model parameters in the order given, then the nuisances ``"dF0"`` [N] and
        ``"du0"`` [m] (when fitted): value, standard error (NaN: not determined), bounds,
        unit, ``identified`` (the package's rule, :func:`iwan_element.fitting.verdict`:
        finite stderr below half its value, not at a bound; the offsets need only a finite
        stderr) and their correlation. ``params.values``, ``params.stderr``,
        ``params.identified`` are the dict views.
    offsets : dict
        ``{"force": (dF0, stderr) [N], "displacement": (du0, stderr) [m]}``.
    t, residual : ndarray
        Times [s] and residuals [N] of the fitted samples (measured minus model).
    rms : float
        RMS residual [N].
    tau : float
        Integrated autocorrelation time of the residual [samples]; the stderr are widened by
        ``sqrt(tau)``.
    n_eff : float
        Effective number of independent residuals, ``m / tau``.
    success : bool
        Converged and every model parameter identified.
    message : str
    nfev : int
    warnings : tuple of str
    details : dict
    """

    params: ParameterTable
    offsets: dict
    t: np.ndarray
    residual: np.ndarray
    rms: float
    tau: float
    n_eff: float
    success: bool
    message: str
    nfev: int
    details: dict = field(default_factory=dict)

    @property
    def theta(self) -> np.ndarray:
        """Fitted model parameters (without the offsets), in the order given."""
        return self.params.array([k for k in self.params.names if k not in OFFSET_NAMES])

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN becomes None)."""
        from ...base.serialize import json_safe

        return json_safe(
            {
                "params": self.params.to_dict(),
                "offsets": value_stderr(self.offsets),
                "rms": self.rms,
                "tau": self.tau,
                "n_eff": self.n_eff,
                "success": self.success,
                "message": self.message,
                "nfev": self.nfev,
                "warnings": list(self.warnings),
                "details": self.details,
            }
        )

    def report(self) -> str:
        """Parameter table with standard errors and status, residual and warnings."""
        from .result import status_text

        lines = [
            self.verdict(),
            f"force-model fit ({self.message}), RMS residual {self.rms:.4g} N, "
            f"tau {self.tau:.3g} samples, n_eff {self.n_eff:.4g}",
            "  parameter        value    std. error   status",
        ]
        for p in self.params.parameters:
            lab = f"{p.name} [{p.unit or '-'}]"
            lines.append(
                f"  {lab:<14} {p.value:>11.5g} {p.stderr:>12.3g}   "
                f"{status_text(p.identified, p.nuisance)}"
            )
        lines += [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)

    def plot(self, ax=None) -> list[Artist]:
        """Residual [N] vs time [s]; returns the list of artists."""
        from ...base.result_shape import axes_or_new

        ax = axes_or_new(ax)
        lines = ax.plot(self.t, self.residual, "-", lw=0.6, label="measured - model")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("residual [N]")
        return lines


def _identified(names, x, se, at_bound, degenerate, warns) -> dict:
    """Which fitted values the data identify, by the package's one rule
    (:func:`iwan_element.fitting.verdict`; the offsets are nuisances), appending to ``warns``
    why not.
    """
    ident = {}
    for k, name in enumerate(names):
        why = (
            " (a joint with no absolute position reference depends on displacement "
            "differences only)"
            if name == "du0"
            else ""
        )
        ident[name], warn = verdict(
            name,
            float(x[k]),
            float(se[k]),
            at_bound=bool(at_bound[k]),
            degenerate=bool(degenerate[k]),
            nuisance=name in OFFSET_NAMES,
            why_degenerate=why,
        )
        if warn:
            warns.append(warn)
    return ident


def _check_parameters(model, theta0, lower, upper, names):
    """The model, the start vector, its bounds and the parameter names, checked."""
    if not callable(model):
        raise ValueError(f"model must be callable model(u, theta), got {type(model).__name__}")
    th0 = finite_array("theta0", theta0, ndim=1)
    p = th0.size
    lo = np.full(p, -np.inf) if lower is None else finite_array("lower", lower, ndim=1)
    hi = np.full(p, np.inf) if upper is None else np.array(upper, float)
    if lo.size != p or hi.size != p or np.any(lo >= hi):
        raise ValueError(f"lower and upper must have {p} entries with lower < upper")
    names = tuple(names) if names is not None else tuple(f"p{k}" for k in range(p))
    if len(names) != p:
        raise ValueError(f"names must have {p} entries, got {len(names)}")
    return th0, p, lo, hi, names


def _fitted_samples(tt, uu, n, smooth, burn_in, max_samples):
    """The driving displacement, the burn-in index and the fitted samples after it."""
    u_drive, dinfo = drive_displacement(tt, uu, smooth)
    b = burn_in_index(u_drive) if burn_in == "auto" else check_int("burn_in", burn_in, 0)
    if b >= n - 20:
        raise ValueError(f"burn_in leaves {n - b} samples; at least 20 are needed")
    m_all = n - b
    ms = m_all if max_samples is None else min(m_all, check_int("max_samples", max_samples, 100))
    keep = b + np.unique(np.round(np.linspace(0, m_all - 1, ms)).astype(np.intp))
    return u_drive, dinfo, b, keep


def _start(model, u_drive, keep, y, th0, lo, hi, names, amp, fit_offsets):
    """Start vector, bounds and names of the fit, with the offsets when they are fitted."""
    p = th0.size
    if fit_offsets:
        x0 = np.r_[np.clip(th0, lo, hi), 0.0, 0.0]
        x0[p] = float(np.median(y - np.asarray(model(u_drive, x0[:p]), float)[keep]))
        lo_x, hi_x = np.r_[lo, -np.inf, -0.5 * amp], np.r_[hi, np.inf, 0.5 * amp]
        all_names = names + OFFSET_NAMES
    else:
        x0, lo_x, hi_x, all_names = np.clip(th0, lo, hi), lo, hi, names
    return x0, lo_x, hi_x, all_names


def _parameter_table(all_names, res, c, se, degenerate, lo_x, hi_x, units, warns):
    """The fitted parameters' table (values, errors, bounds, units, verdicts)."""
    at_bound = np.isclose(res.x, lo_x, rtol=1e-6, atol=1e-12) | np.isclose(
        res.x, hi_x, rtol=1e-6, atol=1e-12
    )
    ident = _identified(all_names, res.x, se, at_bound, degenerate, warns)
    unit_of = {"dF0": "N", "du0": "m", **dict(units or {})}
    table = ParameterTable(
        tuple(
            Parameter(
                k,
                float(v),
                float(e),
                float(a),
                float(b),
                unit_of.get(k, ""),
                ident[k],
                nuisance=k in OFFSET_NAMES,
            )
            for k, v, e, a, b in zip(all_names, res.x, se, lo_x, hi_x)
        ),
        correlation=c.correlation,
    )
    return table, ident


def _correlation_warning(tau, warns):
    """A warning when the residuals are correlated over more than 3 samples."""
    if tau > 3.0:
        warns.append(
            f"the residuals are correlated over {tau:.3g} samples (a systematic misfit "
            f"or coloured noise): the std. errors are widened by sqrt(tau) = "
            f"{math.sqrt(tau):.3g}"
        )


def fit_force_model(
    t,
    u,
    F,
    model: Callable,
    theta0,
    *,
    lower=None,
    upper=None,
    names: Sequence[str] | None = None,
    units: dict | None = None,
    fit_offsets: bool = True,
    smooth="auto",
    burn_in: int | str = "auto",
    max_samples: int | None = 5000,
    max_nfev: int = 200,
) -> ModelFit:
    """Least-squares fit of ``model`` plus force and displacement offsets (module docstring).

    Parameters
    ----------
    t, u, F : array_like, shape (n,)
        Time [s] (strictly increasing), displacement [m], force [N]. Not modified.
    model : callable
        ``model(u, theta) -> ndarray (n,)``: the force [N] of the model driven by the
        displacement history ``u`` [m] (all samples, from the model's initial state).
    theta0 : array_like, shape (p,)
        Start values of the model parameters.
    lower, upper : array_like, shape (p,), optional, keyword-only
        Bounds (default unbounded).
    names : sequence of str, optional, keyword-only
        Parameter names (default ``p0, p1, ...``).
    units : dict, optional, keyword-only
        Unit of each name, for the report.
    fit_offsets : bool, keyword-only
        Fit ``dF0`` and ``du0`` (default True).
    smooth : "auto", 0 or odd int, keyword-only
        De-noising of the driving displacement (:func:`drive_displacement`).
    burn_in : int or "auto", keyword-only
        Samples left out at the start (``"auto"``: up to the second turning point).
    max_samples : int or None, keyword-only
        Most residuals fitted (evenly spaced), ``>= 100``; None: all.
    max_nfev : int, keyword-only
        Model evaluations allowed to the optimiser.

    Returns
    -------
    ModelFit
    """
    t_start = time.perf_counter()
    uu = check_magnitude("u", finite_array("u", u, ndim=1, min_size=32), unit="m")
    FF = check_magnitude("F", finite_array("F", F, ndim=1, min_size=32), unit="N")
    n = same_length(u=uu, F=FF)
    tt = check_time(t, n)
    th0, p, lo, hi, names = _check_parameters(model, theta0, lower, upper, names)
    u_drive, dinfo, b, keep = _fitted_samples(tt, uu, n, smooth, burn_in, max_samples)
    y = FF[keep]
    nfev = [0]
    amp = max(float(np.ptp(uu)), 1e-300)

    def resid(x):
        nfev[0] += 1
        du0 = x[p + 1] if fit_offsets else 0.0
        dF0 = x[p] if fit_offsets else 0.0
        Fm = np.asarray(model(u_drive - du0, x[:p]), float)
        return Fm[keep] + dF0 - y

    x0, lo_x, hi_x, all_names = _start(
        model, u_drive, keep, y, th0, lo, hi, names, amp, fit_offsets
    )
    res = minimize(resid, x0, lo_x, hi_x, method="trf", max_nfev=max_nfev, x_scale="jac")
    r = res.fun
    assert r is not None  # method "trf" returns the residuals
    tau = integrated_time(r)
    c = covariance(res.jac, r, tau=tau)
    se, cov, degenerate = c.stderr, c.covariance, c.degenerate
    warns: list[str] = []
    table, ident = _parameter_table(all_names, res, c, se, degenerate, lo_x, hi_x, units, warns)
    values, stderr = table.values, table.stderr
    _correlation_warning(tau, warns)
    success = fit_success(res.success, ident, names)
    offs = {
        "force": (values.get("dF0", 0.0), stderr.get("dF0", math.nan)),
        "displacement": (values.get("du0", 0.0), stderr.get("du0", math.nan)),
    }
    return ModelFit(
        params=table,
        offsets=offs,
        t=tt[keep],
        residual=-r,
        rms=float(np.sqrt(np.mean(r * r))),
        tau=float(tau),
        n_eff=float(r.size / tau),
        success=success,
        message=str(res.message),
        nfev=int(nfev[0]),
        warnings=tuple(warns),
        details={
            "burn_in": int(b),
            "fitted_samples": int(keep.size),
            "units": dict(units or {}),
            "covariance": cov.tolist(),
            "wall_time": time.perf_counter() - t_start,
            **dinfo,
        },
    )
