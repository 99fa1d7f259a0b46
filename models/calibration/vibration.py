"""Calibration of a specimen's interface from vibration data.

* From vibration data: :func:`calibrate` fits interface parameters (by default the
  tangential stiffness per area, the friction coefficient, chi and the modal damping floor)
  so that the QSMA curve (:func:`~iwan_element.models.modal.modal_amplitude_curve`) matches a
  measured :class:`~iwan_element.AmplitudeCurve` (frequency and damping against amplitude at
  the specimen's sensor point). Nonlinear least squares (``scipy.optimize.least_squares`` through
  :func:`iwan_element.fitting.minimize`,
  log-parameters, bounded), residuals ``(f/f_meas - 1)/f_tol`` and ``(zeta/zeta_meas - 1)/z_tol``;
  standard errors from the Jacobian at the optimum. The joint's parameters come from the
  calibration ``mode`` only; the other modes' measured curves (``floors``) set only their
  own linear floors, each from its lowest-amplitude points (:func:`modal_floor`): the
  floor is linear damping, not the joint.
* From a joint or modal Iwan fit: :mod:`~iwan_element.models.calibration.joint`.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from iwan_element import AmplitudeCurve, amplitude_curve
from iwan_element.base.progress import complete, finish, progress_bar, tick
from iwan_element.base.result_shape import ResultShape, panels, unit_label
from iwan_element.base.validation import check_scalar
from iwan_element.fitting import (
    Parameter,
    ParameterTable,
    covariance,
    fit_success,
    minimize,
    verdict,
)

from ..modal.qsma import modal_amplitude_curve
from ..specimens.specimen import Specimen

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["measured_amplitude_curve", "CalibrationResult", "calibrate", "modal_floor"]

_FIT = ("stiffness_per_area", "friction", "chi", "damping_floor", "beta")
_BOUNDS = {
    "stiffness_per_area": (1e9, 1e15),
    "friction": (1e-3, 3.0),
    "chi": (-0.95, 0.0),
    "damping_floor": (1e-6, 0.05),
    "beta": (1e-4, 10.0),
}
_UNITS = {
    "stiffness_per_area": "N/m^3",
    "friction": "1",
    "chi": "1",
    "damping_floor": "1",
    "beta": "1",
}


def measured_amplitude_curve(
    path, *, band=(60.0, 120.0), window: float = 0.25, start: float = 0.0
) -> AmplitudeCurve:
    """f(X), zeta(X) of one mode from a ring-down acceleration record (CSV: t [s], a [m/s^2]).

    Reads the file and calls :func:`iwan_element.amplitude_curve` (band-pass, Hilbert,
    windowed fits; it trims the filter's end effects itself) on the record from ``start``
    seconds after its largest sample (the impact).
    """
    data = np.loadtxt(Path(path), delimiter=",", skiprows=1)
    if data.ndim != 2 or data.shape[1] < 2 or data.shape[0] < 1000:
        raise ValueError(f"{path}: expected a CSV of t [s], a [m/s^2] with >= 1000 rows")
    t, a = data[:, 0], data[:, 1]
    keep = t >= t[np.argmax(np.abs(a))] + start
    return amplitude_curve(t[keep], a[keep], quantity="acceleration", band=band, window=window)


@dataclass(frozen=True)
class CalibrationResult(ResultShape):
    """Result of :func:`calibrate`.

    Attributes
    ----------
    specimen : Specimen
        The calibrated specimen.
    params : ParameterTable
        The fitted interface parameters with standard errors, search ranges, units and
        verdicts (:func:`iwan_element.fitting.verdict`); ``params.values``,
        ``params.stderr`` are the dict views.
    measured, model : AmplitudeCurve
    max_frequency_error, max_damping_error : float
    success : bool
        Converged, no warning, every fitted parameter identified.
    converged : bool
        The optimiser converged (``success`` also asks for identified parameters).
    start : dict
        Each fitted parameter's starting value (the given specimen's: after a linear
        update, the report states how far the calibration moved a parameter the two share).
    warnings : tuple of str
        Everything the data could not support, one line per parameter that is not
        identified included.
    """

    COLUMNS = {
        "max_frequency_error": ("max |f/f_meas - 1|", "-"),
        "max_damping_error": ("max |zeta/zeta_meas - 1|", "-"),
    }

    plot_panels = 2

    specimen: Specimen
    params: ParameterTable
    measured: AmplitudeCurve
    model: AmplitudeCurve
    max_frequency_error: float
    max_damping_error: float
    success: bool
    converged: bool = True
    start: dict = field(default_factory=dict)

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False in a tester's words: the optimiser's stop, then every
        warning (a parameter the curve does not identify, a floor leaning on the joint).
        """
        if self.success:
            return ()
        own = () if self.converged else ("the fit did not converge",)
        return own + tuple(self.warnings) or super().failure_reasons()

    def report(self) -> str:
        """Human-readable account: the fitted parameters [their units] and the misfits."""
        lines = [self.verdict(), f"Interface calibration of {self.specimen.name!r}"]
        for k, p in self.params.items():
            moved = (
                f"  (from {self.start[k]:.6g}: {100 * (p.value / self.start[k] - 1):+.2f} %)"
                if self.start.get(k)
                else ""
            )
            lines.append(
                f"  {k:20s} = {p.value:.6g} +- {p.stderr:.2g} [{unit_label(p.unit)}]  "
                f"{p.status}{moved}"
            )
        lines.append(f"  max |f/f_meas - 1|      = {self.max_frequency_error:.2e}")
        lines.append(f"  max |zeta/zeta_meas - 1| = {self.max_damping_error:.3f}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """As a dict: the parameters, start values, success, misfits, warnings and curves."""
        return {
            "params": self.params.to_dict(),
            "start": dict(self.start),
            "success": self.success,
            "converged": self.converged,
            "max_frequency_error": self.max_frequency_error,
            "max_damping_error": self.max_damping_error,
            "warnings": list(self.warnings),
            "model": self.model.to_dict(),
            "measured": self.measured.to_dict(),
        }

    def plot(self, ax=None) -> list[Artist]:
        """Measured and model f(X), zeta(X) on ``ax = (ax_f, ax_z)`` (a new figure if
        ``None``; :mod:`iwan_element.base.result_shape`); returns the artists.
        """
        ax = panels(ax, 2, sharex=True, figsize=(6, 6))
        arts = self.measured.plot(ax, label="measured", ls="none")
        arts += self.model.plot(ax, label="model (QSMA)", marker="", ls="-")
        return arts


def _with(specimen: Specimen, names, values, mode: int = 1) -> Specimen:
    """``specimen`` with the named parameters set; ``damping_floor`` is the calibration
    mode's floor, so it also sets that mode's entry of ``modal_damping`` when there is one.
    """
    ch: dict[str, Any] = {n: float(v) for n, v in zip(names, values)}  # Specimen fields
    md = list(specimen.modal_damping)
    if "damping_floor" in ch and mode <= len(md):
        md[mode - 1] = ch["damping_floor"]
        ch["modal_damping"] = tuple(md)
    return specimen.replace(**ch)


def modal_floor(
    specimen: Specimen, measured: AmplitudeCurve, *, mode: int, decades: float = 1.0
) -> tuple[float, float, list]:
    """A mode's linear damping floor from its own lowest-amplitude points.

    The points of ``measured`` (amplitude at ``specimen.sensor_position``) within
    ``decades`` of its lowest amplitude, each with the joint's share at its amplitude
    removed (QSMA of ``specimen``'s interface on ``mode`` with no floor), averaged with
    weights ``1 / damping_ratio_std**2`` (equal weights when the curve has no spread).

    Parameters
    ----------
    specimen : Specimen
        The interface (calibrated on another mode) whose joint share is removed.
    measured : AmplitudeCurve
        The mode's measured curve.
    mode : int, keyword-only
        Elastic mode number of ``measured`` (1: lowest).
    decades : float, keyword-only
        Amplitude span of the points used [decades], in (0, 3].

    Returns
    -------
    (floor, stderr, warnings) : (float, float, list of str)
        Floor [-] and its standard error [-] (the weighted scatter of the points, at least
        the weights' own error); warnings when fewer than 3 points are used or the joint's
        share there exceeds 10 % of the measured damping (the floor then leans on the joint
        model).
    """
    if not isinstance(measured, AmplitudeCurve) or len(measured) == 0:
        raise ValueError("measured must be a non-empty AmplitudeCurve")
    decades = check_scalar("decades", decades, low=0.0, high=3.0, low_open=True)
    X = measured.amplitude
    m = X <= X.min() * 10.0**decades * (1 + 1e-12)
    bare = specimen.replace(damping_floor=0.0, modal_damping=(), calibrated_range=None, effects=())
    joint = modal_amplitude_curve(bare, mode=mode, amplitude=X[m]).damping_ratio
    z = measured.damping_ratio[m] - joint
    sd = measured.damping_ratio_std[m] if measured.damping_ratio_std is not None else None
    ok = sd is not None and np.all(np.isfinite(sd)) and np.all(sd > 0)
    w = 1.0 / sd**2 if ok and sd is not None else np.ones(z.size)
    floor = float(np.sum(w * z) / np.sum(w))
    scatter = math.sqrt(float(np.sum(w * (z - floor) ** 2) / np.sum(w)) / max(z.size - 1, 1))
    se = max(scatter, math.sqrt(1.0 / float(np.sum(w)))) if ok else scatter
    warns = []
    if z.size < 3:
        warns.append(f"mode {mode}'s floor rests on {z.size} point(s) (fewer than 3)")
    share = float(np.max(joint / measured.damping_ratio[m]))
    if share > 0.1:
        warns.append(
            f"the joint's share of mode {mode}'s damping at its lowest measured "
            f"amplitudes is up to {100 * share:.0f} %: its floor leans on the joint model"
        )
    return floor, se, warns


def calibrate(
    specimen: Specimen,
    measured: AmplitudeCurve,
    *,
    fit=("stiffness_per_area", "friction", "chi", "damping_floor"),
    mode: int = 1,
    f_tol: float = 2e-4,
    z_tol: float = 0.05,
    floors: dict | None = None,
    progress: bool = False,
) -> CalibrationResult:
    """Fit interface parameters so the QSMA curve matches a measured amplitude curve.

    Parameters
    ----------
    specimen : Specimen
        Geometry and the starting values of the fitted parameters.
    measured : AmplitudeCurve
        Measured curve (amplitude at ``specimen.sensor_position``); points outside
        ``specimen.amplitude_range`` are ignored.
    fit : sequence of str, keyword-only
        Parameters to fit, from ``stiffness_per_area``, ``friction``, ``chi``,
        ``damping_floor``, ``beta``.
    mode : int, keyword-only
        The calibration mode of ``measured`` (1: lowest); the joint comes from it alone.
    f_tol, z_tol : float, keyword-only
        Residual scales of the relative frequency and damping errors.
    floors : dict, optional, keyword-only
        ``{mode: AmplitudeCurve}``: other modes' measured curves (amplitudes at the same
        sensor), each setting only that mode's linear floor from its lowest-amplitude points
        (:func:`modal_floor`, with the calibrated joint's share removed). The calibrated
        specimen's ``modal_damping`` then lists the calibration mode's fitted floor and
        these; its parameter table adds a row ``floor_mode_<r>`` per mode.
    progress : bool, keyword-only
        Show a tqdm bar over the QSMA evaluations (total: the fit's budget, lowered to the
        count reached at the end); needs tqdm.
    """
    floors, fit, X, fm, zm = _fit_points(specimen, measured, floors, fit, mode)
    sol, lb, ub = _solve(specimen, fit, mode, X, fm, zm, f_tol, z_tol, progress)
    vals = [_transform(n, v, True) for n, v in zip(fit, sol.x)]
    fitted = _with(specimen, fit, vals, mode).replace(
        calibrated_range=(float(X.min()), float(X.max()))
    )
    curve = modal_amplitude_curve(fitted, mode=mode, amplitude=X)
    warns = []
    # the package's one covariance routine (docs/fitting.md): s^2 (J^T J)^-1, s^2 = SSR/dof,
    # with the delta method from the fitted logarithms
    dlog = np.diag([1.0 if n == "chi" else v for n, v in zip(fit, vals)])
    se = (
        covariance(sol.jac, sol.fun, Jp=dlog).stderr
        if np.all(np.isfinite(sol.jac))
        else np.full(len(fit), np.nan)
    )
    if not np.all(np.isfinite(se)):
        warns.append("the Jacobian is singular: some parameters are not identifiable")
    ferr = float(np.max(np.abs(curve.frequency / fm - 1)))
    zerr = float(np.max(np.abs(curve.damping_ratio / zm - 1)))
    rows = _rows(fit, sol.x, vals, se, lb, ub, warns)
    fitted, floor_rows = _floors(fitted, mode, floors, warns)
    table = ParameterTable(rows + floor_rows)
    return CalibrationResult(
        specimen=fitted,
        params=table,
        measured=measured,
        model=curve,
        start={n: float(_get(specimen, n)) for n in fit},
        max_frequency_error=ferr,
        max_damping_error=zerr,
        success=fit_success(bool(sol.success) and not warns, table.identified),
        converged=bool(sol.success),
        warnings=tuple(warns),
    )


def _fit_points(specimen, measured, floors, fit, mode):
    """:func:`calibrate`'s checked ``floors`` and ``fit`` and the measured points inside the
    specimen's amplitude range: ``(floors, fit, X, f, zeta)``.
    """
    floors = {} if floors is None else dict(floors)
    if any(
        isinstance(r, bool) or not isinstance(r, numbers.Integral) or r < 1 or r == mode
        for r in floors
    ) or not all(isinstance(c, AmplitudeCurve) for c in floors.values()):
        raise ValueError(
            f"floors must map modes >= 1 other than the calibration mode {mode} to "
            f"AmplitudeCurves, got {floors!r}"
        )
    floors = {int(r): c for r, c in floors.items()}
    fit = tuple(fit)
    bad = [n for n in fit if n not in _FIT]
    if bad or not fit:
        raise ValueError(f"fit must name parameters from {_FIT}, got {fit!r}")
    lo, hi = specimen.amplitude_range
    m = (measured.amplitude >= lo * (1 - 1e-9)) & (measured.amplitude <= hi * (1 + 1e-9))
    if m.sum() < len(fit) + 2:
        raise ValueError(
            f"the measured curve has {m.sum()} points in the specimen's amplitude "
            f"range; need at least {len(fit) + 2}"
        )
    return floors, fit, measured.amplitude[m], measured.frequency[m], measured.damping_ratio[m]


def _get(s, n):
    """A fitted parameter's value on ``s``."""
    return getattr(s, n) if n == "friction" else getattr(s.interface, n)


def _transform(n, v, inverse=False):
    """The fit's coordinate of parameter ``n`` (its logarithm; chi itself), or back."""
    if n == "chi":
        return v
    return math.exp(v) if inverse else math.log(v)


def _solve(specimen, fit, mode, X, fm, zm, f_tol, z_tol, progress):
    """The bounded least squares of :func:`calibrate` over the QSMA curve at the measured
    amplitudes ``X``: ``(solution, lower, upper)`` in the fit's coordinates.
    """
    x0 = np.array(
        [
            _transform(n, min(max(_get(specimen, n), _BOUNDS[n][0] * 1.01), _BOUNDS[n][1]))
            for n in fit
        ]
    )
    lb = np.array([_transform(n, _BOUNDS[n][0]) for n in fit])
    ub = np.array([_transform(n, _BOUNDS[n][1]) for n in fit])

    def model(x):
        s = _with(specimen, fit, [_transform(n, v, True) for n, v in zip(fit, x)], mode)
        return modal_amplitude_curve(s, mode=mode, amplitude=X)

    def resid(x):
        tick(bar)
        c = model(x)
        return np.concatenate([(c.frequency / fm - 1) / f_tol, (c.damping_ratio / zm - 1) / z_tol])

    # each iteration costs one evaluation and one per fitted parameter (its Jacobian)
    bar = progress_bar(progress, total=200 * (len(fit) + 1), desc="calibrate", unit="QSMA")
    try:
        sol = minimize(resid, x0, lb, ub, method="trf", max_nfev=200, x_scale=1.0, diff_step=1e-4)
        complete(bar, "converged")  # the budget's evaluations not needed
    finally:
        finish(bar)
    return sol, lb, ub


def _rows(fit, x, vals, se, lb, ub, warns):
    """The parameter table's rows of the fitted parameters, each with its verdict
    (:func:`iwan_element.fitting.verdict`); what a row cannot support goes to ``warns``.
    """
    rows = []
    for k, (n, v) in enumerate(zip(fit, x)):
        at_bound = min(v - lb[k], ub[k] - v) < 1e-3
        if at_bound:
            warns.append(f"{n} ended on its bound")
        lo, hi = _BOUNDS[n]
        val = min(max(vals[k], lo), hi)  # exp(ln b) may round past the bound b
        ok, why = verdict(
            n,
            val,
            float(se[k]),
            at_bound=at_bound,
            reference=val + 1.0 if n == "chi" else None,
            reference_text="chi + 1" if n == "chi" else "its value",
        )
        if why and not at_bound:  # (at a bound: said above)
            warns.append(why)
        rows.append(Parameter(n, val, float(se[k]), lo, hi, _UNITS[n], ok))
    return rows


def _floors(fitted: Specimen, mode: int, floors: dict, warns: list):
    """The calibrated specimen with each mode's floor of ``floors`` (:func:`modal_floor`)
    and the calibration mode's own in ``modal_damping``; the table rows of those floors
    (their warnings appended to ``warns``).
    """
    if not floors:
        return fitted, []
    md = [fitted.floor(r) for r in range(1, max(max(floors), mode) + 1)]
    rows = []
    for r, curve in sorted(floors.items()):
        z, se, w = modal_floor(fitted, curve, mode=r)
        warns += w
        lo, hi = _BOUNDS["damping_floor"]
        ok, why = verdict(f"floor_mode_{r}", z, se, at_bound=not lo <= z <= hi)
        if why:
            warns.append(why)
        if not lo <= z <= hi:
            warns.append(f"mode {r}'s floor {z:.3g} lies outside [{lo:g}, {hi:g}]: clipped")
            z = min(max(z, lo), hi)
        md[r - 1] = z
        rows.append(Parameter(f"floor_mode_{r}", z, se, lo, hi, "1", ok))
    return fitted.replace(modal_damping=tuple(md)), rows
