"""Prediction bands: a fit's parameter uncertainty run through the structure's response."""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from ..base.result_shape import ResultShape, column, panels, table_lines
from ..base.serialize import json_safe
from ..base.validation import check_int, check_magnitude, check_scalar, finite_array
from ..core.parameters import IwanParameters
from .oscillator import SingleModeSystem, modal_curve, peak_response
from .runner import EnsembleResult, run_ensemble
from .uncertainty import ParameterUncertainty

if TYPE_CHECKING:
    from matplotlib.artist import Artist

    from ..identify.modal.result import ModalIwanFit

__all__ = ["PredictionBands", "propagate_uncertainty", "response_task", "modal_fit_task"]


def response_task(
    params: dict,
    rng,
    *,
    system: SingleModeSystem,
    amplitude,
    force=None,
    cycles: int = 30,
    steps_per_period: int = 64,
) -> dict:
    """One ensemble task: ``frequency`` [Hz] and ``damping_ratio`` [-] at ``amplitude`` and, with
    ``force`` [N], the ``peak`` transient displacement [m] (see :mod:`.oscillator`).
    ``params`` holds ``Fs, KT, chi, beta``; ``rng`` is unused (the model is deterministic).
    """
    p = IwanParameters(params["Fs"], params["KT"], params["chi"], params["beta"])
    f, z = modal_curve(p, system, amplitude)
    out: dict[str, Any] = {"frequency": f, "damping_ratio": z}
    if force is not None:
        out["peak"] = peak_response(
            p, system, force=force, cycles=cycles, steps_per_period=steps_per_period
        )
    return out


def modal_fit_task(
    params: dict,
    rng,
    *,
    names,
    regime: str,
    conventions: dict,
    amplitude,
    force=None,
    cycles: int = 30,
    steps_per_period: int = 64,
) -> dict:
    """One ensemble task for a modal Iwan fit (:func:`iwan_element.fit_modal_iwan`): its model
    curve at ``amplitude`` for one sampled fit vector and, in the macroslip regime with
    ``force`` [N per unit modal mass], the peak transient displacement [m] of the fitted
    single-mode oscillator (fixed dashpot ``2 zeta0 w0``).
    """
    from ..identify.modal.model import full_parameters, model_curve

    theta = np.array([params[n] for n in names], dtype=float)
    f, z = model_curve(
        theta,
        np.asarray(amplitude, float),
        regime,
        conventions["x_ref"],
        conventions["stiffness"],
        conventions["floor"],
        conventions.get("damping_form", "energy"),
    )
    out: dict[str, Any] = {"frequency": np.asarray(f, float), "damping_ratio": np.asarray(z, float)}
    if force is not None:
        p, k_inf = full_parameters(theta)
        system = SingleModeSystem(mass=1.0, stiffness=max(k_inf, 0.0), zeta0=theta[1])
        out["peak"] = peak_response(
            p, system, force=force, cycles=cycles, steps_per_period=steps_per_period
        )
    return out


@dataclass(frozen=True, eq=False)
class PredictionBands(ResultShape):
    """Quantile bands of the predicted response over the sampled parameter sets.

    Attributes
    ----------
    amplitude : ndarray, shape (m,)
        Displacement amplitudes [m].
    frequency, damping_ratio : ndarray, shape (n_ok, m)
        Per successful sample: frequency [Hz] and damping ratio [-] against amplitude.
    peak : ndarray, shape (n_ok,) or None
        Peak transient displacement [m] at ``force``.
    nominal : dict
        The same outputs for the nominal (fitted) parameters.
    level : float
        Central probability of the bands (0.9: 5 % .. 95 % quantiles).
    force : float or None
        Forcing amplitude of the transient run [N].
    system : SingleModeSystem or None
        ``None`` for a modal fit (the fit carries its own single-mode structure).
    uncertainty : ParameterUncertainty or ModalIwanFit
        The sampled distribution.
    ensemble : EnsembleResult
        The runs, with the sampled parameters (``to_csv`` writes them).
    warnings : tuple of str
    """

    amplitude: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    peak: np.ndarray | None
    nominal: dict
    level: float
    force: float | None
    system: SingleModeSystem | None
    uncertainty: ParameterUncertainty | ModalIwanFit
    ensemble: EnsembleResult

    @property
    def _source(self) -> str:
        return (
            getattr(self.uncertainty, "source", None)
            or f"modal fit ({getattr(self.uncertainty, 'regime', '?')})"
        )

    def band(
        self, name: str
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(low, median, high)`` quantiles of ``"frequency"``, ``"damping_ratio"``, ``"peak"``."""
        if name not in ("frequency", "damping_ratio", "peak"):
            raise ValueError(f"name must be 'frequency', 'damping_ratio' or 'peak', got {name!r}")
        data = getattr(self, name)
        if data is None:
            raise ValueError("no peak response: propagate_uncertainty was called without force")
        q = [(1 - self.level) / 2, 0.5, (1 + self.level) / 2]
        return tuple(np.quantile(data, q, axis=0))

    @property
    def plot_panels(self) -> int:  # type: ignore[override]  # read-only: set by ``peak``
        """Frequency and damping, and the peak response when there is one."""
        return 3 if self.peak is not None else 2

    @property
    def success(self) -> bool:
        """True when at least two thirds of the sampled parameter sets ran (the bands are
        quantiles of the successful ones; failures are listed in the ensemble).
        """
        n = len(self.ensemble)
        return bool(n > 0 and len(self.ensemble.errors) <= n / 3)

    def _tables(self) -> list:
        """The bands per amplitude (nominal, low, median, high of the frequency and the
        damping ratio, and of the peak when computed), then the run.
        """
        cols, data = [column("amplitude", "m")], [self.amplitude]
        names = ("frequency", "damping_ratio") + (("peak",) if self.peak is not None else ())
        units = {"frequency": "Hz", "damping_ratio": "-", "peak": "m"}
        for name in names:
            lo, med, hi = self.band(name)
            for k, v in (
                ("nominal", self.nominal[name]),
                ("low", lo),
                ("median", med),
                ("high", hi),
            ):
                if np.ndim(v) == 0:
                    v = np.full(len(self.amplitude), float(v))
                cols.append(column(f"{name} {k}", units[name]))
                data.append(v)
        rows = [tuple(map(float, r)) for r in zip(*data)]
        run = [
            (column("level", "-"), float(self.level)),
            (column("force", "N"), self.force),
            ("samples", int(self.frequency.shape[0])),
            ("failed", len(self.ensemble.errors)),
            ("source", self._source),
        ]
        return [("bands", tuple(cols), rows), ("run", ("quantity", "value"), run)]

    def report(self) -> str:
        """Plain-text table of the bands: frequency [Hz], damping ratio [-], peak, per amplitude."""
        lines = [
            self.verdict(),
            f"Prediction bands ({100 * self.level:.0f} % central) from {self._source}: "
            f"{self.frequency.shape[0]} samples on {self.ensemble.executor}, "
            f"{len(self.ensemble.errors)} failed",
        ]
        fl, _, fh = self.band("frequency")
        zl, _, zh = self.band("damping_ratio")
        lines += table_lines(
            [
                ("X [m]", "10.3e"),
                ("f nominal", "11.6g"),
                ("f low", "11.6g"),
                ("f high", "11.6g"),
                ("zeta nom.", "10.4e"),
                ("zeta low", "10.4e"),
                ("zeta high", "10.4e"),
            ],
            zip(
                self.amplitude,
                self.nominal["frequency"],
                fl,
                fh,
                self.nominal["damping_ratio"],
                zl,
                zh,
            ),
        )
        if self.peak is not None:
            pl, pm, ph = self.band("peak")
            lines.append(
                f"  peak displacement at F0 = {self.force:g} N: nominal "
                f"{self.nominal['peak']:.5g} m, band {pl:.5g} .. {ph:.5g} m"
            )
        return "\n".join(lines + [f"  warning: {w}" for w in self.warnings])

    def to_dict(self) -> dict:
        """The bands as a JSON-safe dict (low, median, high, nominal per quantity)."""
        q = {}
        for name in ("frequency", "damping_ratio") + (("peak",) if self.peak is not None else ()):
            lo, med, hi = self.band(name)
            q[name] = {"low": lo, "median": med, "high": hi, "nominal": self.nominal[name]}
        return json_safe(
            {
                "amplitude": self.amplitude,
                "level": self.level,
                "force": self.force,
                "samples": int(self.frequency.shape[0]),
                "failed": len(self.ensemble.errors),
                "bands": q,
                "system": None
                if self.system is None
                else {
                    "mass": self.system.mass,
                    "stiffness": self.system.stiffness,
                    "zeta0": self.system.zeta0,
                },
                "source": self._source,
                "uncertainty": self.uncertainty.to_dict(),
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None, *, color="C0", label=None, relative: bool = False) -> list[Artist]:
        """Bands (shaded) with the median (dashed) and the nominal curve (solid).

        Parameters
        ----------
        ax : sequence of matplotlib Axes, optional
            ``plot_panels`` Axes: ``(ax_frequency, ax_damping)`` or, with a peak response,
            ``(ax_frequency, ax_damping, ax_peak)``; new axes if omitted
            (:mod:`iwan_element.base.result_shape`).
        color, label : keyword-only
            Colour and legend label of the bands.
        relative : bool, keyword-only
            Plot the deviation from the nominal curve in per cent (narrow bands become
            visible); the peak panel is unchanged.

        Returns
        -------
        list
            The artists drawn.
        """
        ax = panels(ax, self.plot_panels, figsize=(6, 3.2 * self.plot_panels))
        X = self.amplitude
        pct = f"{100 * self.level:.0f} % band"
        artists = []
        for a, name, ylabel in (
            (ax[0], "frequency", "frequency"),
            (ax[1], "damping_ratio", "damping ratio"),
        ):
            nom = np.asarray(self.nominal[name], float)
            lo, med, hi = self.band(name)
            if relative:
                lo, med, hi, nom = (100.0 * (v / nom - 1.0) for v in (lo, med, hi, nom))
            artists.append(
                a.fill_between(
                    X, lo, hi, color=color, alpha=0.3, label=f"{label + ': ' if label else ''}{pct}"
                )
            )
            artists += a.plot(X, med, "--", color=color, lw=1, label="median")
            artists += a.plot(X, nom, "-", color=color, lw=1.5, label="nominal fit")
            a.set_xscale("log")
            a.set_xlabel("displacement amplitude X [m]")
            unit = "[Hz]" if name == "frequency" else "[-]"
            a.set_ylabel(
                f"{ylabel}: deviation from nominal [%]" if relative else f"{ylabel} {unit}"
            )
        ax[0].legend(fontsize=8)
        if self.peak is not None:
            lo, _, hi = self.band("peak")
            artists.append(
                ax[2].hist(
                    self.peak, bins=min(30, max(5, self.peak.size // 5)), color=color, alpha=0.6
                )[2]
            )
            for v, ls in ((lo, ":"), (hi, ":"), (self.nominal["peak"], "-")):
                artists.append(ax[2].axvline(v, color="k", ls=ls, lw=1))
            ax[2].set_xlabel(f"peak displacement at F0 = {self.force:g} N [m]")
            ax[2].set_ylabel("samples")
        return artists


#: Most parameter sets propagate_uncertainty draws (each is one simulation).
_MAX_SAMPLES = 10**7


def propagate_uncertainty(
    source,
    *,
    system: SingleModeSystem | None = None,
    amplitude,
    n_samples: int = 200,
    force: float | None = None,
    cycles: int = 30,
    steps_per_period: int = 64,
    level: float = 0.9,
    seed=None,
    executor=None,
    progress: bool = False,
) -> PredictionBands:
    """Sample the parameters of a fit and return prediction bands of the response.

    Parameters
    ----------
    source : FitResult, ModalIwanFit or ParameterUncertainty
        A loop or dissipation fit (see :meth:`ParameterUncertainty.from_fit`), a modal Iwan
        fit (:func:`iwan_element.fit_modal_iwan`, sampled with its own
        ``sample_parameters`` in its fit coordinates), or a prepared distribution (for
        instance :meth:`ParameterUncertainty.from_mean_cov`).
    system : SingleModeSystem, keyword-only
        The structure the joint sits in (not used with a modal fit, which carries its own
        single-mode structure: unit modal mass, sensor coordinate).
    amplitude : array_like, keyword-only
        Displacement amplitudes [m] of the f(X), zeta(X) bands, ``> 0``.
    n_samples : int, keyword-only
        Parameter sets drawn, ``>= 2``.
    force : float, optional, keyword-only
        Forcing amplitude [N] of the transient run (harmonic at the nominal linear frequency
        for ``cycles`` periods from rest); its peak displacement gets a band. ``None`` skips it.
    cycles, steps_per_period : int, keyword-only
        Length and resolution of the transient run.
    level : float, keyword-only
        Central probability of the bands, in ``(0, 1)``.
    seed : int or None, keyword-only
        Seeds the parameter draws and the ensemble.
    executor, progress : keyword-only
        As in :func:`~iwan_element.ensemble.run_ensemble`.

    Returns
    -------
    PredictionBands
    """
    X = check_magnitude("amplitude", finite_array("amplitude", amplitude), unit="m")
    if np.any(X <= 0):
        raise ValueError("amplitude must be > 0 [m]")
    n_samples = check_int("n_samples", n_samples, 2)
    if n_samples > _MAX_SAMPLES:
        raise ValueError(f"n_samples must be in [2, {_MAX_SAMPLES:.0e}], got {n_samples}")
    level = check_scalar("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
    if force is not None:
        force = check_scalar("force", force, low=0.0, low_open=True)
    if seed is None:
        seed = int(cast(int, np.random.SeedSequence().entropy))  # drawn: always an int
    rng = np.random.default_rng(seed)
    if hasattr(source, "sample_parameters") and hasattr(source, "regime"):
        task, nominal_set, sets, unc, warns = _modal_fit_setup(
            source, X, force, cycles, steps_per_period, n_samples, rng
        )
        system = None
    else:
        task, nominal_set, sets, unc, warns = _fit_setup(
            source, system, X, force, cycles, steps_per_period, n_samples, rng
        )
    nominal = task(nominal_set, None)
    ens = run_ensemble(task, sets, executor=executor, seed=seed, progress=progress)
    warns += list(ens.warnings)
    ok = ens.ok
    if ok.sum() < 2:
        raise RuntimeError(
            f"only {int(ok.sum())} of {n_samples} runs succeeded; first error: "
            f"{ens.errors[0].message if ens.errors else '?'}"
        )
    peak = ens.column("peak")[ok] if force is not None else None
    return PredictionBands(
        amplitude=X,
        frequency=ens.column("frequency")[ok],
        damping_ratio=ens.column("damping_ratio")[ok],
        peak=peak,
        nominal=nominal,
        level=level,
        force=force,
        system=system,
        uncertainty=unc,
        ensemble=ens,
        warnings=tuple(warns),
    )


def _fit_setup(source, system, X, force, cycles, steps_per_period, n_samples, rng):
    """Task, nominal set, samples, distribution and warnings for a loop or dissipation fit
    or a prepared :class:`ParameterUncertainty`.
    """
    if not isinstance(source, ParameterUncertainty) and not hasattr(source, "joint"):
        raise ValueError(
            "source must be a FitResult, a ModalIwanFit or a "
            f"ParameterUncertainty, got {type(source).__name__}"
        )
    unc = (
        source
        if isinstance(source, ParameterUncertainty)
        else ParameterUncertainty.from_fit(source)
    )
    if not isinstance(system, SingleModeSystem):
        raise ValueError(f"system must be a SingleModeSystem, got {type(system).__name__}")
    sets, rejected = unc.sample(n_samples, rng=rng)
    warns = list(unc.warnings)
    if rejected > 0.01:
        warns.append(
            f"{100 * rejected:.1f} % of the draws fell outside the model's range "
            "(beta < 0 or chi <= -1) and were rejected: the bands are those of the "
            "truncated distribution"
        )
    if X.max() > unc.valid_amplitude:
        warns.append(
            f"amplitudes above {unc.valid_amplitude:.4g} m are beyond the tested "
            "range: the fit cannot constrain the joint there (Fs, beta not "
            "identified)"
        )
    task = functools.partial(
        response_task,
        system=system,
        amplitude=X,
        force=force,
        cycles=cycles,
        steps_per_period=steps_per_period,
    )
    nominal_set = {k: getattr(unc.nominal, k) for k in ("Fs", "KT", "chi", "beta")}
    return task, nominal_set, sets, unc, warns


def _modal_fit_setup(fit, X, force, cycles, steps_per_period, n_samples, rng):
    """Task, nominal set, samples and warnings for a modal Iwan fit."""
    warns = [f"the fit reports: {w}" for w in fit.warnings]
    if force is not None and fit.regime != "macroslip":
        raise ValueError(
            f"a peak response needs the whole joint, which a {fit.regime} modal fit "
            "does not determine; call without force"
        )
    task = functools.partial(
        modal_fit_task,
        names=tuple(fit.names),
        regime=fit.regime,
        conventions=dict(fit.conventions),
        amplitude=X,
        force=force,
        cycles=cycles,
        steps_per_period=steps_per_period,
    )
    span = fit.data["amplitude"]
    if X.max() > 1.001 * np.max(span) or X.min() < 0.999 * np.min(span):
        warns.append(
            f"amplitudes outside the fitted data ({np.min(span):.3g} .. "
            f"{np.max(span):.3g} m) are an extrapolation of the modal model"
        )
    sets = fit.sample_parameters(n_samples, rng=rng)
    sets = [{k: float(v) for k, v in s.items()} for s in sets]
    return task, dict(zip(fit.names, map(float, fit.values))), sets, fit, warns
