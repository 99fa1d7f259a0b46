"""From a fit's parameters and covariance to prediction bands of the structure's response.

:class:`ParameterUncertainty` holds a Gaussian in the coordinates the fits use for their
covariance (``ln Fs, ln KT, chi, ln(1 + beta)``, see :mod:`iwan_element.identify.loops.fit`),
so that samples keep ``Fs, KT > 0`` and ``1 + beta > 0`` by construction; the remaining bounds
(``beta >= 0``, ``chi > -1``) are kept by rejection, which makes the distribution the
truncated normal (the rejected fraction is reported). A fit that did not reach macroslip
determines only ``(KT, chi, R)``: it is sampled in ``(ln KT, chi, ln R)`` and each sample is
the ``beta = 0`` member of its family, valid up to the largest amplitude tested.

:func:`propagate_uncertainty` runs the samples through :func:`~iwan_element.ensemble.run_ensemble`
and returns :class:`PredictionBands`: quantile bands of the frequency and damping ratio
against amplitude of a single-mode structure
(:func:`~iwan_element.ensemble.oscillator.modal_curve`) and of the peak transient response at
one forcing level (:func:`~iwan_element.ensemble.oscillator.peak_response`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..base.result_shape import ResultShape, column, panels
from ..base.serialize import json_safe
from ..base.validation import check_int, finite_array
from ..core.parameters import IwanParameters
from ..identify.loops.joint_verdict import PARAM_NAMES

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["ParameterUncertainty"]

_COORD = {"Fs": "ln Fs", "KT": "ln KT", "chi": "chi", "beta": "ln(1+beta)", "R": "ln R"}


def _to_theta(name, value):
    return {"Fs": math.log, "KT": math.log, "R": math.log, "chi": float, "beta": math.log1p}[name](
        value
    )


def _from_theta(name, th):
    return {"Fs": np.exp, "KT": np.exp, "R": np.exp, "chi": np.asarray, "beta": np.expm1}[name](th)


def _scale(name, value):
    """``d theta / d p`` of the coordinate map (diagonal)."""
    if name == "chi":
        return 1.0
    return 1.0 / (1.0 + value) if name == "beta" else 1.0 / value


@dataclass(frozen=True, eq=False)
class ParameterUncertainty(ResultShape):
    """A Gaussian over Iwan parameters in transformed coordinates.

    Attributes
    ----------
    nominal : IwanParameters
        The fitted (mean) joint; unsampled parameters keep its values.
    names : tuple of str
        Sampled parameters, among ``Fs, KT, chi, beta`` (or ``KT, chi, R`` for a fit without
        macroslip).
    mean, cov : ndarray
        Mean and covariance in the coordinates ``ln Fs, ln KT, chi, ln(1+beta), ln R``.
    source : str
        Where the covariance came from.
    valid_amplitude : float
        Largest displacement amplitude [m] the samples are valid for (``inf`` unless the fit
        left ``Fs, beta`` undetermined).
    warnings : tuple of str
    success : bool
        False when the source fit did not succeed (its covariance may then be meaningless).
    """

    nominal: IwanParameters
    names: tuple
    mean: np.ndarray
    cov: np.ndarray
    source: str = "generic"
    valid_amplitude: float = math.inf
    success: bool = True

    @classmethod
    def from_mean_cov(
        cls, mean: IwanParameters, cov, names=PARAM_NAMES, *, source: str = "generic"
    ) -> ParameterUncertainty:
        """From nominal parameters and a covariance in physical units.

        Parameters
        ----------
        mean : IwanParameters
            Nominal joint.
        cov : array_like, shape (k, k)
            Covariance of ``names`` in SI units (``Fs`` [N], ``KT`` [N/m], ``chi``, ``beta``),
            symmetric positive semi-definite. Mapped to the transformed coordinates with the
            delta method (as the fits do, the other way round).
        names : sequence of str
            Parameters the rows of ``cov`` refer to, distinct, among ``Fs, KT, chi, beta``.
        """
        if not isinstance(mean, IwanParameters):
            raise ValueError(f"mean must be IwanParameters, got {type(mean).__name__}")
        names = tuple(names)
        if not names or len(set(names)) != len(names) or not set(names) <= set(PARAM_NAMES):
            raise ValueError(f"names must be distinct names among {PARAM_NAMES}, got {names}")
        C = finite_array("cov", cov, ndim=2)
        if C.shape != (len(names), len(names)):
            raise ValueError(
                f"cov must have shape ({len(names)}, {len(names)}) for names {names}, got {C.shape}"
            )
        J = np.array([_scale(n, getattr(mean, n)) for n in names])
        return cls._build(mean, names, C * np.outer(J, J), source=source)

    @classmethod
    def _build(
        cls,
        nominal,
        names,
        cov_theta,
        *,
        source,
        valid=math.inf,
        warnings=(),
        values=None,
        success=True,
    ):
        C = 0.5 * (cov_theta + cov_theta.T)
        if not np.allclose(C, cov_theta, rtol=1e-8, atol=1e-300):
            raise ValueError("cov must be symmetric")
        ev = np.linalg.eigvalsh(C)
        if ev.min() < -1e-10 * max(ev.max(), 1e-300):
            raise ValueError(
                f"cov must be positive semi-definite (smallest eigenvalue {ev.min():.3g})"
            )
        values = values or {n: getattr(nominal, n) for n in names}
        mean = np.array([_to_theta(n, values[n]) for n in names])
        return cls(
            nominal=nominal,
            names=tuple(names),
            mean=mean,
            cov=C,
            source=source,
            valid_amplitude=float(valid),
            warnings=tuple(warnings),
            success=bool(success),
        )

    @classmethod
    def from_fit(cls, fit) -> ParameterUncertainty:
        """From a :class:`~iwan_element.FitResult` (loop or dissipation fit) or any result with
        ``joint`` (IwanParameters), ``stderr`` (dict), ``correlation`` (4x4 in ``Fs, KT, chi,
        beta`` order), ``identified`` and ``fixed``.

        Parameters that were given (``fixed``) or have no finite standard error are held at
        their fitted value (said in ``warnings``). A fit without macroslip is sampled in
        ``(ln KT, chi, ln R)`` (see the module docstring).
        """
        for attr in ("joint", "stderr", "correlation"):
            if not hasattr(fit, attr):
                raise ValueError(
                    f"fit must be a FitResult-like object with joint, stderr and "
                    f"correlation; it has no {attr!r}"
                )
        p = fit.joint
        warns = [f"the fit reports: {w}" for w in getattr(fit, "warnings", ())]
        if not getattr(fit, "success", True):
            warns.append("the fit did not succeed: its covariance may be meaningless")
        ident = getattr(fit, "identified", dict.fromkeys(PARAM_NAMES, True))
        details = getattr(fit, "details", {}) or {}
        src = f"fit ({getattr(fit, 'method', type(fit).__name__)})"
        if not ident.get("Fs", True) and "stderr_R" in details:
            se = np.array([fit.stderr["KT"] / p.KT, fit.stderr["chi"], details["stderr_R"] / p.R])
            corr = np.array(details["corr_KT_chi_R"], dtype=float)
            xm = float(details.get("x_max", math.inf))
            warns.append(
                "Fs and beta are not identified: each sample is the beta = 0 member of "
                f"its (KT, chi, R) family, valid for amplitudes up to {xm:.4g} m"
            )
            return cls._build(
                p,
                ("KT", "chi", "R"),
                corr * np.outer(se, se),
                source=src,
                valid=xm,
                warnings=warns,
                values={"KT": p.KT, "chi": p.chi, "R": p.R},
                success=getattr(fit, "success", True),
            )
        fixed = set(getattr(fit, "fixed", ()))
        names = [
            n
            for n in PARAM_NAMES
            if n not in fixed and ident.get(n, True) and math.isfinite(fit.stderr.get(n, math.nan))
        ]
        held = [n for n in PARAM_NAMES if n not in names]
        if not names:
            raise ValueError("the fit gives no finite standard error: nothing to sample")
        if held:
            warns.append(
                f"{', '.join(held)} held at the fitted value (given or without a standard error)"
            )
        idx = [PARAM_NAMES.index(n) for n in names]
        corr = np.asarray(fit.correlation, float)[np.ix_(idx, idx)]
        se = np.array([fit.stderr[n] * _scale(n, getattr(p, n)) for n in names])
        return cls._build(
            p,
            names,
            corr * np.outer(se, se),
            source=src,
            warnings=warns,
            success=getattr(fit, "success", True),
        )

    def _params(self, theta) -> IwanParameters:
        v = {n: float(_from_theta(n, t)) for n, t in zip(self.names, theta)}
        if "R" in v:  # beta = 0 member: R phi^(chi+1) = (chi+1) KT (eq. 10)
            KT, chi, R = v["KT"], v["chi"], v["R"]
            phi = ((chi + 1.0) * KT / R) ** (1.0 / (chi + 1.0))
            return IwanParameters(KT * phi * (chi + 1.0) / (chi + 2.0), KT, chi, 0.0)
        d = {n: getattr(self.nominal, n) for n in PARAM_NAMES}
        d.update(v)
        return IwanParameters(**d)

    def sample(self, n: int, *, rng: np.random.Generator) -> tuple[list[dict], float]:
        """``n`` parameter sets ``{"Fs", "KT", "chi", "beta"}`` and the rejected fraction.

        Draws from the Gaussian in transformed coordinates and rejects draws outside the
        model's range (``chi <= -1``, ``beta < 0``); raises ``RuntimeError`` if fewer than 1 %
        of the draws are accepted.
        """
        n = check_int("n", n, 1)
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy Generator, got {type(rng).__name__}")
        out: list[dict] = []
        drawn = 0
        while len(out) < n:
            if drawn > 100 * n:
                raise RuntimeError(
                    f"fewer than 1 % of the draws are inside the model's range "
                    f"({len(out)} of {drawn}); the covariance is too wide"
                )
            th = rng.multivariate_normal(self.mean, self.cov, size=n, method="eigh")
            for row in th:
                drawn += 1
                v = dict(zip(self.names, row))
                if v.get("chi", 0.0) <= -1.0 or v.get("beta", 0.0) < 0.0:
                    continue
                try:
                    p = self._params(row)
                except ValueError:
                    continue
                out.append({"Fs": p.Fs, "KT": p.KT, "chi": p.chi, "beta": p.beta})
                if len(out) == n:
                    break
        return out, 1.0 - n / drawn if drawn else 0.0

    def _tables(self) -> list:
        """The sampled coordinates (mean, standard deviation; a logarithm's is relative),
        then the source.
        """
        se = np.sqrt(np.diag(self.cov))
        coords = [(_COORD[n], float(m), float(s)) for n, m, s in zip(self.names, self.mean, se)]
        run = [
            ("source", self.source),
            (column("valid up to amplitude", "m"), self.valid_amplitude),
            ("nominal", str(self.nominal)),
        ]
        return [
            ("coordinates", ("coordinate", column("mean", "-"), column("std", "-")), coords),
            ("run", ("quantity", "value"), run),
        ]

    def report(self) -> str:
        """Plain-text table of the coordinates' mean and standard deviation."""
        se = np.sqrt(np.diag(self.cov))
        lines = [
            self.verdict(),
            f"Parameter uncertainty from {self.source}; nominal {self.nominal}",
            "  coordinate        mean       std",
        ]
        lines += [
            f"  {_COORD[n]:<12} {m:10.5g} {s:9.3g}" for n, m, s in zip(self.names, self.mean, se)
        ]
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def to_dict(self) -> dict:
        """The uncertainty as a JSON-safe dict (nominal, coordinates, mean, covariance)."""
        return json_safe(
            {
                "nominal": self.nominal.to_dict(),
                "names": list(self.names),
                "coordinates": [_COORD[n] for n in self.names],
                "mean": self.mean,
                "cov": self.cov,
                "source": self.source,
                "valid_amplitude": self.valid_amplitude,
                "warnings": list(self.warnings),
                "success": self.success,
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """One standard deviation of each sampled coordinate (``ln Fs``, ``ln KT``, ``chi``,
        ``ln(1 + beta)``, ``ln R``; a logarithm's is a relative error) as bars, with the
        correlation matrix written on them. Returns the artists (one Axes,
        :mod:`iwan_element.base.result_shape`).
        """
        (ax,) = panels(ax, 1, figsize=(5, 3.5))
        se = np.sqrt(np.diag(self.cov))
        x = np.arange(len(self.names))
        arts = list(ax.bar(x, se, color="C0", alpha=0.7))
        ax.set_xticks(x, [_COORD[n] for n in self.names])
        ax.set_ylabel("standard deviation (relative for a logarithm)")
        with np.errstate(invalid="ignore", divide="ignore"):
            corr = self.cov / np.outer(se, se)
        for i, s in enumerate(se):
            arts.append(
                ax.annotate(
                    " ".join(f"{c:+.2f}" for c in corr[i]),
                    (i, s),
                    ha="center",
                    va="bottom",
                    fontsize=6,
                )
            )
        ax.set_title(f"uncertainty from {self.source}", fontsize=9)
        return arts
