"""The result of an Iwan identification: :class:`FitResult`, its report, dict and plot."""

from __future__ import annotations

import math
import time
import warnings
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, value_stderr
from ...base.serialize import json_safe
from ...core.parameters import IwanParameters
from ...fitting import ParameterTable, fit_success
from .joint_verdict import (
    PARAM_NAMES,
    failure_list,
    joint_table,
    required_parameters,
    settle_verdict,
)

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["FitResult", "IdentifiabilityWarning"]

#: Order of the parameters in ``FitResult.correlation``.


def status_text(identified: bool, nuisance: bool = False) -> str:
    """The report's status column; it follows ``identified`` and nothing else."""
    if nuisance:
        return "nuisance (fitted)" if identified else "nuisance, not determined"
    return "identified" if identified else "NOT identified"


class IdentifiabilityWarning(UserWarning):
    """A parameter is not, or only poorly, determined by the data (see ``FitResult.warnings``)."""


@dataclass(frozen=True, eq=False)
class FitResult(ResultShape):
    """Identified Iwan parameters with uncertainties and diagnostics.

    Attributes
    ----------
    params : ParameterTable
        ``Fs`` [N], ``KT`` [N/m], ``chi``, ``beta``: value, standard error (NaN where the
        parameter is not identified or was given), verdict, whether it was given
        (``fixed``), and their correlation matrix (``params.correlation``, in the order of
        :data:`PARAM_NAMES`; NaN rows/columns for parameters without a standard error).
        When ``Fs`` and ``beta`` are not identified (no macroslip in the data) the values
        are the ``beta = 0`` member of the family that fits the data equally well;
        ``ranges`` gives the family.
    joint : IwanParameters
        (property) The fitted joint, built from ``params``.
    stderr, identified : dict
        (properties) ``params.stderr`` and ``params.identified``.
    correlation : ndarray, shape (4, 4)
        (property) ``params.correlation``.
    fixed : tuple of str
        (property) Parameters that were given, not fitted (``("Fs",)`` for
        ``method="seed"``).
    ranges : dict
        For parameters that are not identified: ``(low, high)`` range that fits the data
        equally well.
    residual_norm : float
        Euclidean norm of the residual vector that was minimised (loop fit: force residuals
        [N], divided by ``sigma`` if given; dissipation fits: log residuals [-]).
    nrmse : float
        Normalised RMS error [-]: for loop fits the RMS force error over the force range
        ``max F - min F``; for dissipation fits the RMS relative error of the fitted quantities.
    success : bool
        The one rule of docs/guards.md: the fit converged, every reported parameter is
        identified and the joint explains the data beyond the noise.
    message : str
        The optimiser's stop message (kept apart from the verdict: a normal stop is no
        reason for failure).
    nfev : int
        Model evaluations (all starts, the Jacobian and the identifiability check included).
    method : str
        ``"loops"``, ``"seed"`` or ``"least_squares"``.
    n_data : int
        Number of residuals fitted.
    warnings : tuple of str
        Everything a user should know before trusting the numbers.
    wall_time : float
        Time taken [s].
    details : dict
        JSON-safe extras (largest backbone argument, macroslip test statistics, starts, ...).
    offsets : dict
        Loop fits: the sensor zero offsets fitted as nuisance parameters, ``{"force": (dF0,
        stderr) [N], "displacement": (du0, stderr) [m]}`` (stderr NaN: not determined by the
        data). ``measured = model(u - du0) + dF0``. Empty for dissipation fits.
    noise : dict
        Loop fits: ``{"force": sigma [N], "displacement": sigma [m]}`` from
        :func:`~iwan_element.identify.loops.noise.estimate_noise`, and ``"tau"``, the residuals'
        integrated autocorrelation time [samples] by which the variances were multiplied.
    failures : tuple of str
        Why ``success`` is False, in a tester's words (:meth:`failure_reasons`).
    """

    params: ParameterTable
    ranges: dict
    residual_norm: float
    nrmse: float
    success: bool
    message: str
    nfev: int
    method: str
    n_data: int
    wall_time: float
    details: dict = field(default_factory=dict)
    offsets: dict = field(default_factory=dict)
    noise: dict = field(default_factory=dict)
    _curves: dict = field(default_factory=dict, repr=False)
    failures: tuple = ()

    @property
    def joint(self) -> IwanParameters:
        """The fitted joint (``Fs``, ``KT``, ``chi``, ``beta`` of :attr:`params`)."""
        return IwanParameters(*(self.params[k].value for k in PARAM_NAMES))

    @property
    def stderr(self) -> dict:
        """Standard error of each parameter (NaN: not identified or given)."""
        return self.params.stderr

    @property
    def identified(self) -> dict:
        """``True`` for each parameter the data determine."""
        return self.params.identified

    @property
    def correlation(self) -> np.ndarray | None:
        """Correlation matrix in the order of :data:`PARAM_NAMES` (read-only; None when the
        parameter table holds none, which the package's fits never build).
        """
        return self.params.correlation

    @property
    def fixed(self) -> tuple:
        """Parameters that were given, not fitted."""
        return tuple(p.name for p in self.params.parameters if p.fixed)

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN and inf become ``None``): ``params`` is the parameter table's
        dict; ``IwanParameters.from_dict(d["joint"])`` rebuilds the joint.
        """
        return json_safe(
            {
                "method": self.method,
                "params": self.params.to_dict(),
                "joint": self.joint.to_dict(),
                "correlation": {"order": list(PARAM_NAMES), "matrix": self.correlation},
                "ranges": {k: list(v) for k, v in self.ranges.items()},
                "residual_norm": self.residual_norm,
                "nrmse": self.nrmse,
                "success": self.success,
                "failure_reasons": list(self.failure_reasons()),
                "message": self.message,
                "nfev": self.nfev,
                "n_data": self.n_data,
                "warnings": list(self.warnings),
                "wall_time": self.wall_time,
                "details": self.details,
                "offsets": value_stderr(self.offsets),
                "noise": dict(self.noise),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Loop fits: measured and fitted force [kN] vs displacement [mm]; dissipation fits:
        measured and fitted ``D`` [J] vs ``F0`` [N] (log-log). Returns the list of artists.
        """
        from ...base.result_shape import axes_or_new

        ax = axes_or_new(ax)
        c = self._curves
        if not c:
            raise ValueError("this result carries no data to plot (rebuilt from a dict?)")
        if self.method == "loops":
            step = max(1, c["u"].size // 20000)
            arts = ax.plot(
                c["u"][::step] * 1e3,
                c["F"][::step] * 1e-3,
                ".",
                ms=1.5,
                color="0.55",
                label="measured",
            )
            arts += ax.plot(
                c["u"][::step] * 1e3,
                c["F_fit"][::step] * 1e-3,
                "-",
                lw=1.0,
                color="C3",
                label="fit (offsets removed from the data)",
            )
            ax.set_xlabel("u [mm]")
            ax.set_ylabel("F [kN]")
        else:
            arts = ax.loglog(c["F0"], c["D"], "o", label="measured")
            arts += ax.loglog(c["F0_fit"], c["D_fit"], "-", label="fit")
            ax.set_xlabel("F0 [N]")
            ax.set_ylabel("D [J]")
        ax.legend()
        return arts

    def _parameter_lines(self, p) -> list:
        """The report's rows of the four parameters and the fitted offsets."""
        lines = []
        fmt = {
            "Fs": ("Fs   [N]  ", "{:.6g}"),
            "KT": ("KT   [N/m]", "{:.6g}"),
            "chi": ("chi  [-]  ", "{:.4f}"),
            "beta": ("beta [-]  ", "{:.4f}"),
        }
        for k in PARAM_NAMES:
            label, f = fmt[k]
            v = getattr(p, k)
            se = self.stderr.get(k, math.nan)
            se_txt = f.format(se) if math.isfinite(se) else "n/a"
            if k in self.fixed:
                status, se_txt = "given (not fitted)", ""
            elif not self.identified.get(k, False):
                lo, hi = self.ranges.get(k, (math.nan, math.nan))
                status = status_text(False) + (
                    f" (data fit equally for {f.format(lo)} .. {f.format(hi)})"
                    if k in self.ranges
                    else ""
                )
            else:
                rel = f" {100 * se / abs(v):.2g} %" if v != 0 and k in ("Fs", "KT") else ""
                status = status_text(True) + rel
            lines.append(f"  {label}  {f.format(v):>12}  {se_txt:>12}   {status}")
        for name, (key, _unit, scale) in {
            "dF0 [N]  ": ("force", "N", 1.0),
            "du0 [m]  ": ("displacement", "m", 1.0),
        }.items():
            if key in self.offsets:
                v, se = self.offsets[key]
                se_txt = f"{se * scale:.4g}" if math.isfinite(se) else "n/a"
                lines.append(
                    f"  {name}   {v * scale:>12.5g}  {se_txt:>12}   "
                    f"{status_text(math.isfinite(se), nuisance=True)}"
                )
        return lines

    def report(self) -> str:
        """Human-readable summary: parameters with standard errors, correlations, fit quality
        and warnings.
        """
        p = self.joint
        title = {
            "loops": "loop fit (exact IwanJoint on the measured displacement)",
            "seed": "dissipation fit, seed-paper procedure (Nelder-Mead + Newton on KT)",
            "least_squares": "dissipation fit, least squares on the exact F0(u0), D(u0)",
        }
        lines = [
            self.verdict(),
            f"Iwan joint identification: {title.get(self.method, self.method)}",
            f"  {self.n_data} residuals, {self.nfev} model evaluations, {self.wall_time:.2f} s, "
            f"optimiser stop: {self.message}",
            "",
            "  parameter        value        std. error   status",
        ]
        lines += self._parameter_lines(p)
        lines.append(
            f"  derived: phi_max = {p.phi_max:.5g} m, R = {p.R:.5g} N m^(-chi-2), S = {p.S:.5g} N/m"
        )
        have = [k for k in PARAM_NAMES if math.isfinite(self.stderr.get(k, math.nan))]
        if len(have) > 1 and (corr := self.correlation) is not None:
            lines += ["", "  correlation     " + "".join(f"{k:>8}" for k in have)]
            for i, k in enumerate(PARAM_NAMES):
                if k in have:
                    row = "".join(f"{corr[i, PARAM_NAMES.index(j)]:8.3f}" for j in have)
                    lines.append(f"  {k:<15} {row}")
        unit = (
            "[-]"
            if self.method != "loops"
            else "[N]"
            if not self.details.get("weighted")
            else "[-]"
        )
        lines += [
            "",
            f"  residual norm {self.residual_norm:.4g} {unit}, NRMSE {100 * self.nrmse:.3g} %",
        ]
        if self.noise:
            lines.append(
                f"  noise: force {self.noise.get('force', math.nan):.3g} N, displacement "
                f"{self.noise.get('displacement', math.nan):.3g} m; residual correlation "
                f"time {self.noise.get('tau', math.nan):.3g} samples (variances x tau)"
            )
        if self.warnings:
            lines += ["", "  warnings:"] + [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


def _finish(
    method,
    out,
    *,
    converged,
    message,
    nfev,
    nrmse,
    t0,
    extra_warnings=(),
    fixed=(),
    stacklevel=3,
    offsets=None,
    noise=None,
    curves=None,
) -> FitResult:
    """Build the FitResult from the dict of :func:`_identify` (or its seed-method twin) and
    issue one IdentifiabilityWarning carrying every warning.

    ``success`` is the package's one rule (docs/guards.md): the optimiser converged, the data
    are more than noise (``out["explains"]``, default True) and every reported parameter (all
    four, but those given and a ``beta`` compatible with 0, :func:`required_parameters`)
    is identified by the rule of :func:`settle_verdict`; so
    ``success``, the report's status column and the warnings say the same. A fit in
    microslip reports ``Fs`` and ``beta`` as not identified: it is not a usable joint.
    """
    ident, settle_warns = settle_verdict(out, fixed)
    warns = list(extra_warnings) + out["warnings"] + settle_warns
    if not converged:
        warns.append(f"the optimiser did not converge: {message}")
    explains = out.get("explains", True)
    if not explains:
        ident = dict.fromkeys(ident, False)
    success = fit_success(converged and explains, ident, required_parameters(out["ranges"], fixed))
    table = joint_table(
        out["params"], out["stderr"], ident, fixed=fixed, correlation=out["correlation"]
    )
    failures = (
        failure_list(
            converged=converged,
            message=str(message),
            explains=explains,
            noise_text=next(
                (w for w in warns if "indistinguishable from noise" in w),
                f"misfit well beyond the noise remains: the joint does not follow the "
                f"data (NRMSE {float(nrmse):.3g})",
            ),
            ident=ident,
            required=required_parameters(out["ranges"], fixed),
            microslip=out["details"].get("macroslip_reached") is False,
            fixed=fixed,
        )
        if not success
        else ()
    )
    result = FitResult(
        params=table,
        ranges=out["ranges"],
        residual_norm=float(np.sqrt(out["r"] @ out["r"])),
        nrmse=float(nrmse),
        success=success,
        message=str(message),
        nfev=int(nfev),
        method=method,
        n_data=int(out["r"].size),
        warnings=tuple(warns),
        wall_time=time.perf_counter() - t0,
        details=json_safe(out["details"]),
        offsets=dict(offsets or {}),
        noise=dict(noise or {}),
        _curves=dict(curves or {}),
        failures=failures,
    )
    if _EMIT.get():
        for w in warns:  # one warning each: one line each on stderr, filtered one by one
            warnings.warn(
                "Iwan identification: " + " ".join(w.split()),
                IdentifiabilityWarning,
                stacklevel=stacklevel,
            )
    return result


# Whether fits issue their IdentifiabilityWarning (the warnings stay in FitResult.warnings).
# Library callers that report the warnings themselves switch it off for their own context
# only, instead of changing the process-wide warning filters.
_EMIT: ContextVar[bool] = ContextVar("iwan_fit_emit_warnings", default=True)


@contextmanager
def quiet_fits():
    """Within this context (thread / task), fits do not call ``warnings.warn``."""
    token = _EMIT.set(False)
    try:
        yield
    finally:
        _EMIT.reset(token)
