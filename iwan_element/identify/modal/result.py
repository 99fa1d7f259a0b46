"""The result object of :func:`fit_modal_iwan` (the model itself: :mod:`.model`)."""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, overload

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from ...base.result_shape import ResultShape, panels, wrap
from ...core.parameters import IwanParameters
from ...fitting import (
    Parameter,
    ParameterTable,
    covariance,
    fit_success,
    noise_dof_warning,
    verdict,
)
from ..loops.result import IdentifiabilityWarning
from .model import FULL, MICRO, _derived, full_parameters, model_curve

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["ModalIwanFit"]

_BOUNDS = {
    "f0": (0.0, math.inf),
    "zeta0": (0.0, 1.0),
    "chi": (-1.0, math.inf),
    "delta": (0.0, 1.0),
    "kappa": (0.0, 1.0),
    "log_phi_max": (-math.inf, math.inf),
    "beta": (0.0, math.inf),
}
_UNITS = {
    "f0": "Hz",
    "zeta0": "-",
    "chi": "-",
    "delta": "-",
    "kappa": "-",
    "beta": "-",
    "phi_max": "m",
    "KT": "1/s^2",
    "K_inf": "1/s^2",
    "Fs": "m/s^2",
}


@dataclass(frozen=True)
class ModalIwanFit(ResultShape):
    """Result of :func:`fit_modal_iwan`.

    Attributes
    ----------
    regime : {"macroslip", "microslip", "linear"}
        What the data fixed: all six parameters, the four microslip ones, or only a mean
        frequency and damping ratio.
    names : tuple of str
        Names of the fitted vector ``values`` (``f0, zeta0, chi, delta`` in microslip;
        ``f0, zeta0, chi, kappa, log_phi_max, beta`` beyond).
    values, covariance : ndarray
        Fitted vector and its covariance (sample it with :meth:`sample_parameters`).
    params : ParameterTable
        Reported parameters with their standard errors (delta method) and verdicts:
        ``f0`` [Hz], ``zeta0``, ``chi``, and ``delta`` (microslip) or ``beta, kappa,
        phi_max`` [m at the sensor], ``KT``, ``K_inf`` [1/s^2], ``Fs`` [m/s^2] (unit modal
        mass, sensor coordinate).
    parameters, stderr : dict
        (properties) ``params.values`` and ``params.stderr``.
    joint : IwanParameters or None
        (property) The joint (unit modal mass, sensor coordinate) when the data fix it.
    chi2_red : float
        Reduced chi-square of the weighted fit; the covariance is scaled by it when above 1.
    success : bool
        The one rule of docs/guards.md: the optimiser converged, every reported parameter is
        identified and no misfit beyond the stated uncertainty remains (reduced chi-square
        at most 4).
    warnings : tuple of str
    failures : tuple of str
        Why ``success`` is False, in a tester's words (:meth:`failure_reasons`).
    """

    plot_panels = 2

    regime: str
    names: tuple
    values: np.ndarray
    covariance: np.ndarray
    data: dict
    conventions: dict
    chi2_red: float = float("nan")
    weights: tuple = ()
    success: bool = False
    params: ParameterTable = field(default_factory=lambda: ParameterTable(()))
    failures: tuple = ()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_solution(
        cls,
        theta,
        cov,
        regime,
        data,
        conv,
        *,
        chi2_red,
        weights,
        warnings,
        optimizer_ok,
        jac=None,
        noise_dof=None,
        noise_source=None,
    ):
        """The result of a weighted least-squares solution ``theta`` with covariance ``cov``;
        with the solution's Jacobian ``jac`` the reported parameters' standard errors come
        from :func:`iwan_element.fitting.covariance` with the delta method (NaN along a
        degenerate direction), else from ``cov``. ``noise_dof``: degrees of freedom of a
        noise level taken from the residuals (None: stated), the verdict's rule 4;
        ``noise_source``: where that noise level came from, for the warning.
        """
        names = MICRO if regime == "microslip" else FULL
        theta = np.asarray(theta, dtype=float)
        params = _derived(theta, regime)
        grad = _gradient(lambda th: np.array(list(_derived(th, regime).values())), theta)
        if jac is not None and np.all(np.isfinite(jac)) and np.all(np.isfinite(grad)):
            se = covariance(jac, s2=max(chi2_red, 1.0), Jp=grad).stderr
        else:
            se = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", grad, cov, grad), 0.0))
        stderr = dict(zip(params, map(float, se)))
        warns = list(warnings)
        if chi2_red > 4.0:
            warns.append(
                f"systematic misfit: reduced chi-square {chi2_red:.3g}; the model does "
                "not follow the data within their stated uncertainty and the standard "
                f"errors were widened by {math.sqrt(chi2_red):.3g}"
            )
        if not optimizer_ok:
            warns.append("the optimiser did not report convergence")
        bad = _unidentified(params, stderr, theta, names, noise_dof)
        few = None
        if noise_dof is not None:
            few = noise_dof_warning(
                noise_dof,
                noise_source
                if noise_source is not None
                else (
                    f" (weights from the residuals of {len(data['amplitude'])} amplitudes; state "
                    "the per-point uncertainties or measure more amplitudes)"
                ),
            )
        if few:
            warns.append(few)
        else:
            warns += [
                f"{n} is not identified by these data (value {params[n]:.4g}, stderr "
                f"{stderr[n]:.3g})"
                for n in bad
            ]
        if params["zeta0"] < 1e-9:
            warns.append("zeta0 is at its bound 0: no viscous floor is visible in the data")
        table = _table(params, stderr, bad)
        success = fit_success(optimizer_ok, table.identified, explained=chi2_red <= 4.0)
        failures = () if success else _failures(optimizer_ok, chi2_red, few, bad, regime)
        return cls(
            regime,
            names,
            theta,
            np.asarray(cov, dtype=float),
            data,
            conv,
            chi2_red,
            weights,
            success,
            table,
            warnings=tuple(warns),
            failures=failures,
        )

    @classmethod
    def linear(cls, data, conv, *, warnings):
        """Linear fit (mean ``f0`` [Hz], ``zeta0`` [-]): no amplitude dependence identified."""
        f, z = data["frequency"], data["damping_ratio"]
        n = f.size
        theta = np.array([f.mean(), z.mean()])
        sd = (
            np.array([f.std(ddof=1), z.std(ddof=1)]) / math.sqrt(n) if n > 1 else np.full(2, np.nan)
        )
        cov = np.diag(sd**2)
        params, stderr = _derived(theta, "linear"), {"f0": sd[0], "zeta0": sd[1]}
        return cls(
            "linear",
            ("f0", "zeta0"),
            theta,
            cov,
            data,
            conv,
            float("nan"),
            (),
            False,
            _table(params, stderr, _unidentified(params, stderr, theta, ())),
            warnings=tuple(warnings),
            failures=(
                f"the amplitude dependence is not identified: only {n} point(s) at too "
                "few distinct amplitudes (at least 3 are needed)",
            ),
        )

    # ------------------------------------------------------------------ model access
    @property
    def identified(self) -> tuple:
        """Names of the reported parameters the data pin down."""
        return tuple(k for k, p in self.params.items() if p.identified)

    @property
    def parameters(self) -> dict:
        """Reported parameters, ``params.values``."""
        return self.params.values

    @property
    def stderr(self) -> dict:
        """Their standard errors, ``params.stderr``."""
        return self.params.stderr

    @property
    def joint(self) -> IwanParameters | None:
        """The joint (unit modal mass, sensor coordinate) when the data fix it, else None."""
        return full_parameters(self.values)[0] if self.regime == "macroslip" else None

    def _curve(self, theta, X):
        if self.regime == "linear":
            return np.full(X.shape, theta[0]), np.full(X.shape, theta[1])
        c = self.conventions
        return model_curve(
            theta,
            X,
            self.regime,
            c["x_ref"],
            c["stiffness"],
            c["floor"],
            c.get("damping_form", "energy"),
        )

    @property
    def fitted_range(self) -> tuple:
        """``(lowest, highest)`` amplitude [m] the fit rests on (the curve's points, and the
        fitted span of a direct decay fit); :meth:`predict` warns beyond it.
        """
        X = np.asarray(self.data["amplitude"], dtype=float)
        span = list(self.conventions.get("amplitude_range", ())) + [X.min(), X.max()]
        return float(min(span)), float(max(span))

    @overload
    def predict(
        self, amplitude, band: None = None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...
    @overload
    def predict(
        self, amplitude, band: float
    ) -> tuple[
        NDArray[np.float64],
        NDArray[np.float64],
        tuple[NDArray[np.float64], NDArray[np.float64]],
        tuple[NDArray[np.float64], NDArray[np.float64]],
    ]: ...
    def predict(
        self, amplitude, band: float | None = None
    ) -> (
        tuple[NDArray[np.float64], NDArray[np.float64]]
        | tuple[
            NDArray[np.float64],
            NDArray[np.float64],
            tuple[NDArray[np.float64], NDArray[np.float64]],
            tuple[NDArray[np.float64], NDArray[np.float64]],
        ]
    ):
        """Frequency [Hz] and damping ratio [-] of the fitted model at ``amplitude`` [m].

        With ``band`` (a probability in (0, 1), e.g. 0.95) also returns the two-sided band
        of the fitted curve from the parameter covariance (delta method, normal quantile):
        ``(frequency, damping_ratio, (f_lo, f_hi), (zeta_lo, zeta_hi))``. Amplitudes beyond
        :attr:`fitted_range` issue an :class:`~iwan_element.IdentifiabilityWarning`
        (extrapolation).
        """
        X = np.atleast_1d(np.asarray(amplitude, dtype=float))
        if X.ndim != 1 or np.any(~np.isfinite(X)) or np.any(X <= 0):
            raise ValueError("amplitude must be finite and > 0 [m]")
        lo, hi = self.fitted_range
        if np.any(X < lo * (1 - 1e-9)) or np.any(X > hi * (1 + 1e-9)):
            warnings.warn(
                f"ModalIwanFit.predict: amplitudes {X.min():.3g} .. {X.max():.3g} m "
                f"reach beyond the fitted ones ({lo:.3g} .. {hi:.3g} m, up to "
                f"{max(X.max() / hi, lo / X.min()):.3g} x): the {self.regime} model "
                "is extrapolated there",
                IdentifiabilityWarning,
                stacklevel=2,
            )
        f, z = (np.asarray(v, dtype=float) for v in self._curve(self.values, X))
        if band is None:
            return f, z
        if not 0.0 < float(band) < 1.0:
            raise ValueError(f"band must be a probability in (0, 1), got {band!r}")
        q = stats.norm.ppf(0.5 + 0.5 * float(band))
        J = _gradient(lambda th: np.concatenate(self._curve(th, X)), self.values)
        sd = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", J, self.covariance, J), 0.0))
        sf, sz = sd[: X.size], sd[X.size :]
        return f, z, (f - q * sf, f + q * sf), (z - q * sz, z + q * sz)

    def sample_parameters(self, n: int, *, rng: np.random.Generator) -> list[dict]:
        """``n`` draws of the fitted vector from N(values, covariance) inside the bounds."""
        if not isinstance(rng, np.random.Generator):
            raise ValueError("rng must be a numpy.random.Generator")
        out = []
        lo = np.array([_BOUNDS[k][0] for k in self.names])
        hi = np.array([_BOUNDS[k][1] for k in self.names])
        for _ in range(100):
            d = rng.multivariate_normal(
                self.values, self.covariance, size=max(int(n), 1), method="eigh"
            )
            d = d[np.all((d > lo) & (d < hi), axis=1)]
            out += [dict(zip(self.names, row)) for row in d]
            if len(out) >= n:
                return out[:n]
        raise ValueError(
            "could not draw parameter sets inside the bounds; the covariance is too wide"
        )

    # ------------------------------------------------------------------ reporting
    def rms_errors(self) -> dict:
        """RMS relative errors of the fit against the data: frequency and damping ratio."""
        f, z = self._curve(self.values, self.data["amplitude"])
        rf = (f - self.data["frequency"]) / self.data["frequency"]
        rz = (z - self.data["damping_ratio"]) / self.data["damping_ratio"]
        return {
            "frequency": float(np.sqrt(np.mean(rf**2))),
            "damping_ratio": float(np.sqrt(np.mean(rz**2))),
        }

    def to_dict(self) -> dict:
        """The fit as a JSON-safe dict (parameters in SI units, None for non-finite values)."""

        def num(x):
            return None if not np.isfinite(x) else float(x)

        return {
            "regime": self.regime,
            "success": self.success,
            "failure_reasons": list(self.failure_reasons()),
            "params": self.params.to_dict(),
            "names": list(self.names),
            "covariance": [[float(x) for x in row] for row in self.covariance],
            "chi2_red": num(self.chi2_red),
            "rms_errors": self.rms_errors(),
            "conventions": dict(self.conventions),
            "warnings": list(self.warnings),
        }

    def to_json(self) -> str:
        """The fit as a JSON string (:meth:`to_dict`, indented)."""
        return json.dumps(self.to_dict(), indent=2)

    def report(self) -> str:
        """Plain-text report: the verdict, the parameters with their units and standard errors."""
        c = self.conventions
        lines = [
            self.verdict(),
            f"Modal Iwan fit ({self.regime}; {c['stiffness']} stiffness, {c['floor']} floor)",
        ]
        lines += self.params.report().splitlines()
        if self.regime == "microslip":
            lines.append(f"  delta = relative drop of w^2 at X_ref = {c['x_ref']:.4g} m")
        lines.append(
            f"  goodness of fit: {len(self.data['amplitude'])} amplitudes, reduced "
            f"chi-square {self.chi2_red:.3g}, RMS error f "
            f"{100 * self.rms_errors()['frequency']:.4f} %, zeta "
            f"{100 * self.rms_errors()['damping_ratio']:.2f} %"
        )
        for w in self.warnings:
            lines += wrap(f"  warning: {w}", indent="    ")
        return "\n".join(lines)

    def plot(self, ax=None, *, band: float = 0.95, label: str = "fit") -> list[Artist]:
        """Data (with error bars), fitted curves and their band against amplitude.

        ``ax`` is a sequence of two Axes ``(ax_frequency, ax_damping)``; a new figure if
        omitted (:mod:`iwan_element.base.result_shape`). Returns the list of artists drawn.
        """
        ax = panels(ax, 2, sharex=True, figsize=(6, 6))
        from matplotlib.ticker import NullFormatter

        d = self.data
        X = np.geomspace(d["amplitude"].min(), d["amplitude"].max(), 200)
        f, z, fb, zb = self.predict(X, band=band)
        artists = []
        for a, y, s, m, b in (
            (ax[0], d["frequency"], d["frequency_std"], f, fb),
            (ax[1], d["damping_ratio"], d["damping_ratio_std"], z, zb),
        ):
            eb = a.errorbar(
                d["amplitude"], y, yerr=np.nan_to_num(s), fmt="o", ms=3, color="k", label="data"
            )
            artists += [eb.lines[0], *eb.lines[2]]
            artists += a.plot(X, m, "r-", label=label)
            artists.append(
                a.fill_between(
                    X, b[0], b[1], color="r", alpha=0.25, label=f"{100 * band:.0f} % band"
                )
            )
            a.set_xscale("log")
            a.xaxis.set_minor_formatter(NullFormatter())
        ax[0].set_ylabel("frequency [Hz]")
        ax[1].set_ylabel("damping ratio [-]")
        ax[1].set_xlabel("amplitude at the sensor [m]")
        ax[0].legend(loc="best", fontsize="small")
        return artists


def _failures(optimizer_ok, chi2_red, few, bad, regime) -> tuple:
    """The reasons a modal fit is not usable, in a tester's words."""
    out = []
    if not optimizer_ok:
        out.append("the optimiser did not converge")
    if chi2_red > 4.0:
        out.append(
            f"misfit well beyond the noise remains: reduced chi-square {chi2_red:.3g} "
            "(the model does not follow the data within their uncertainty)"
        )
    if few:
        out.append(few)
    elif bad:
        why = (
            "the curve shows too little amplitude dependence to fix them (standard "
            "errors above half their values)"
            if regime == "microslip"
            else "their standard errors exceed half their values"
        )
        out.append(
            f"{', '.join(bad)} {'is' if len(bad) == 1 else 'are'} not identified by "
            f"these data: {why}"
        )
    return tuple(out)


def _gradient(fun, theta):
    """Central-difference Jacobian of ``fun`` at ``theta``."""
    theta = np.asarray(theta, dtype=float)
    f0 = np.atleast_1d(fun(theta))
    J = np.empty((f0.size, theta.size))
    for j in range(theta.size):
        h = 1e-6 * max(abs(theta[j]), 1e-3)
        tp, tm = theta.copy(), theta.copy()
        tp[j] += h
        tm[j] -= h
        J[:, j] = (np.atleast_1d(fun(tp)) - np.atleast_1d(fun(tm))) / (2 * h)
    return J


def _table(params, stderr, bad) -> ParameterTable:
    """The reported parameters as a :class:`~iwan_element.fitting.ParameterTable`."""
    return ParameterTable(
        tuple(
            Parameter(
                k, float(v), float(stderr.get(k, math.nan)), unit=_UNITS[k], identified=k not in bad
            )
            for k, v in params.items()
        )
    )


def _unidentified(params, stderr, theta, names, noise_dof=None):
    """Reported parameters the data do not pin down: the package's one rule
    (:func:`iwan_element.fitting.verdict`), ``chi`` against ``chi + 1``, ``beta`` against
    ``max(beta, 0.2)`` (a joint with little macroslip softening is as good as one without);
    the viscous floor ``zeta0`` may be zero, so only a finite error is asked of it.
    """
    bad = []
    for k, v in params.items():
        ref, text = {"chi": (v + 1.0, "chi + 1"), "beta": (max(v, 0.2), "max(beta, 0.2)")}.get(
            k, (None, "its value")
        )
        ok, _ = verdict(
            k,
            float(v),
            float(stderr.get(k, math.nan)),
            reference=ref,
            reference_text=text,
            nuisance=k == "zeta0",
            noise_dof=noise_dof,
        )
        if not ok:
            bad.append(k)
    return bad
