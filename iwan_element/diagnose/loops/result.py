"""Result object of the loop diagnosis, :class:`Diagnosis` (the report pieces both diagnoses
share are in :mod:`..selection.lines`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, panels, table_lines, value_stderr, wrap
from ...base.serialize import json_safe
from ..selection.lines import effect_unit, verdict_lines
from ..selection.probable import Probable

if TYPE_CHECKING:
    from matplotlib.artist import Artist

    from ...fitting.parameters import ParameterTable
    from ...identify.loops.result import FitResult
    from ..selection.averaging import AveragedBand

__all__ = ["Diagnosis"]


@dataclass(frozen=True, eq=False)
class Diagnosis(Probable, ResultShape):
    """What the four-parameter Iwan fit misses in a test record, and the augmented model.

    Attributes
    ----------
    effect : str
        The first effect named (a name of :data:`~iwan_element.EFFECTS`) or ``"none"``.
    effects : tuple of str
        All effects named, in the order they were added (innermost first).
    ambiguous_with : tuple of str
        Effects that explain the first step's misfit nearly as well as ``effect``.
    where : str
        Where the base misfit lies (part of the cycle, amplitudes, cycles, direction).
    success : bool
        The one rule of docs/guards.md: the augmented fit converged, its every reported
        parameter is identified, and no misfit beyond the noise is left unexplained (False
        for a record that is pure noise); :meth:`failure_reasons` says why not.
    offsets : dict
        Sensor offsets treated as nuisance parameters (never named as effects):
        ``force`` [N] (fitted with the model, linear) and ``displacement`` [m] (the rest
        position the record starts from, which the joint takes as its unloaded state).
    error_before, error_after : float
        NRMSE of the force [-] (RMS residual over ``max F - min F``) of the base and the
        augmented model on the whole record.
    noise_level : float
        Estimated noise standard deviation on the same scale [-].
    noise_sigma : float
        Estimated noise standard deviation [N].
    misfit : bool
        True if the base misfit is significantly more than noise.
    base_fit, fit : FitResult
        The plain Iwan fit and the augmented fit (``fit.details["effects"]`` holds the effect
        parameters with standard errors; ``fit is base_fit`` when nothing is named).
    model : joint element
        The augmented element (an ``IwanJoint`` when nothing is named), ready for
        :func:`iwan_element.exudyn.add_iwan_connector`.
    steps : tuple of dict
        Per step: every candidate's NRMSE, information-criterion difference, p-value and why
        it was or was not named.
    untestable : dict
        Effects this record cannot reveal, with the reason.
    warnings : tuple of str
    force_before, force_after : ndarray, shape (n,)
        Forces [N] of the base and the augmented model on the displacement as fitted.
    t, u, F : ndarray, shape (n,)
        The data as fitted: after the ``lowpass`` of both channels if one was given
        (read-only copies; ``t`` is the sample index if no time was given).
    details : dict
        Test statistics (JSON-safe).
    failures : tuple of str
        Why ``success`` is False, in a tester's words.
    explanations : tuple of Explanation
        Every explanation the diagnosis fitted (the plain joint, each single effect, each
        stack fitted on the way) with its evidence and posterior probability, most probable
        first (:mod:`~iwan_element.diagnose.probabilities`); the named effects are the
        first. ``probabilities`` and ``effect_probability(name)`` read them, and
        ``averaged_band`` predicts with them.
    """

    plot_panels = 2

    effect: str
    effects: tuple
    ambiguous_with: tuple
    where: str
    success: bool
    offsets: dict
    error_before: float
    error_after: float
    noise_level: float
    noise_sigma: float
    misfit: bool
    base_fit: FitResult
    fit: FitResult
    model: object
    steps: tuple
    untestable: dict
    force_before: np.ndarray
    force_after: np.ndarray
    t: np.ndarray
    u: np.ndarray
    F: np.ndarray
    details: dict = field(default_factory=dict)
    failures: tuple = ()
    explanations: tuple = ()

    @property
    def params(self) -> ParameterTable:
        """The augmented fit's parameters (``fit.params``, a ``ParameterTable``)."""
        return self.fit.params

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN/inf become None); the fits as :meth:`FitResult.to_dict`."""
        return json_safe(
            {
                "effect": self.effect,
                "effects": list(self.effects),
                "ambiguous_with": list(self.ambiguous_with),
                "where": self.where,
                "success": self.success,
                "failure_reasons": list(self.failure_reasons()),
                "params": self.params.to_dict(),
                "offsets": value_stderr(
                    {
                        "force": (
                            self.offsets["force"],
                            self.fit.details.get("force_offset_stderr"),
                        ),
                        "displacement": self.offsets["displacement"],
                    }
                ),
                "error_before": self.error_before,
                "error_after": self.error_after,
                "noise_level": self.noise_level,
                "noise_sigma": self.noise_sigma,
                "misfit": self.misfit,
                "steps": list(self.steps),
                "untestable": dict(self.untestable),
                "warnings": list(self.warnings),
                "base_fit": self.base_fit.to_dict(),
                "fit": self.fit.to_dict(),
                "model": _describe(self.model),
                "details": self.details,
                "probabilities": self.probabilities_dict(),
            }
        )

    def _step_lines(self) -> list:
        """The report's table of each selection step: the candidates, their misfit and
        verdict (the effect column as wide as the longest name, a pair's too).
        """
        lines = []
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'Iwan'}")
            width = max([20] + [len(c["name"]) for c in st["candidates"]])
            lines += table_lines(
                [
                    ("effect", f"<{width}"),
                    ("NRMSE [%]", "9.3g"),
                    ("x noise", "8.3g"),
                    ("dIC", "9.4g"),
                    ("explains [%]", "12.3g"),
                    ("  verdict", "<"),
                ],
                [
                    (
                        c["name"],
                        100 * c["nrmse"],
                        c["ratio"],
                        c["dIC"],
                        100 * c["explained"],
                        "  " + c["verdict"],
                    )
                    for c in st["candidates"]
                ],
                indent=4,
            )
        return lines

    def report(self) -> str:
        """Human-readable account: noise, misfit, where, candidates, verdict, before/after."""
        d = self.details
        p = self.base_fit.joint
        head = [
            f"{d['samples']} samples; noise {d['noise_from']}, correlation time "
            f"{d['tau']:.3g} samples ({d['n_eff']:.0f} independent samples fitted)",
            f"offsets (nuisance): force {self.offsets['force']:.4g} N, displacement "
            f"{self.offsets['displacement']:.4g} m"
            + (
                f"; low-pass {d['lowpass']:g} Hz ({d['lowpass_reason']})"
                if d.get("lowpass")
                else ""
            ),
            f"noise: sigma = {self.noise_sigma:.4g} N (NRMSE {100 * self.noise_level:.3g} %)",
            f"base Iwan fit: Fs={p.Fs:.5g} N, KT={p.KT:.5g} N/m, chi={p.chi:.4f}, "
            f"beta={p.beta:.4f}; NRMSE {100 * self.error_before:.3g} % "
            f"= {self.error_before / self.noise_level:.3g} x noise "
            f"(misfit p-value {d['misfit_p']:.2g}, level {d['alpha']:g})",
            f"selection: {d['criterion']}",
            f"where: {self.where}",
        ]
        lines = [self.verdict(), "Iwan model diagnosis"]
        for h in head:
            lines += wrap("  " + h, indent="    ")
        if self.steps:
            lines += wrap(
                "  NRMSE: RMS force residual over the force range; x noise: its "
                "ratio to the noise; dIC: information criterion above the step's "
                "best candidate (0: the best)",
                indent="    ",
            )
        lines += self._step_lines()
        for name, why in self.untestable.items():
            lines.append(f"  cannot test {name}: {why}")
        if self.effects:
            lines.append(
                f"  named: {', '.join(self.effects)}"
                + (
                    f" (nearly as good: {', '.join(self.ambiguous_with)})"
                    if self.ambiguous_with
                    else ""
                )
            )
            for e in self.fit.details.get("effects", []):
                ps = ", ".join(
                    f"{k} = {v:.4g} {effect_unit(e['name'], k)} (+- {e['stderr'][k]:.2g})"
                    for k, v in e["parameters"].items()
                )
                lines.append(f"    {e['name']}: {ps}")
            q = self.fit.joint
            lines.append(
                f"    Iwan part: Fs={q.Fs:.5g} N, KT={q.KT:.5g} N/m, chi={q.chi:.4f}, "
                f"beta={q.beta:.4f}"
            )
        else:
            lines.append("  named: none")
        lines += self.probability_lines()
        rule = tuple(d.get("rule_named", self.effects))
        if set(rule) != set(self.effects):
            lines.append(f"    (the stepwise rule alone names {' + '.join(rule) or 'nothing'})")
        return "\n".join(lines + verdict_lines("error", self))

    def _tables(self) -> list:
        """The Iwan part's parameters, the named effects' values with their standard
        errors, the candidates of every step, the probabilities, then the run.
        """
        base = super()._tables()
        named = [
            (e["name"], k, float(v), e["stderr"].get(k), effect_unit(e["name"], k))
            for e in self.fit.details.get("effects", [])
            for k, v in e["parameters"].items()
        ]
        cands = [
            (
                k + 1,
                " + ".join(st["on"]) or "Iwan",
                c["name"],
                100 * c["nrmse"],
                c["ratio"],
                c["dIC"],
                100 * c["explained"],
                c["verdict"],
            )
            for k, st in enumerate(self.steps)
            for c in st["candidates"]
        ]
        cols = ("step", "on", "candidate", "NRMSE [%]", "x noise [-]", "dIC [-]", "explains [%]")
        return (
            base[:1]
            + [("named effects", ("effect", "parameter", "value", "std. error", "unit"), named)]
            + [("candidates", cols + ("verdict",), cands)]
            + self.probability_tables()
            + base[1:]
        )

    def averaged_band(self, t=None, u=None, *, level: float = 0.95) -> AveragedBand:
        """The force predicted with the doubt about the model: every probable explanation's
        fitted model weighted by its probability, each with its parameters' posterior
        covariance (:mod:`~iwan_element.diagnose.averaging`).

        Parameters
        ----------
        t, u : array_like, shape (n,), optional
            Time [s] and displacement [m] from the joint's rest position of the drive to
            predict; default the record as fitted. The fitted starting state and force
            offset are kept.
        level : float, keyword-only
            Probability of the band, in (0, 1).

        Returns
        -------
        AveragedBand
            Channel ``"force"`` [N]: ``mean``, ``std``, ``lower``, ``upper``; the members
            and their weights.
        """
        from .evidence import loop_band

        return loop_band(self, t, u, level)

    def plot(self, ax=None) -> list[Artist]:
        """Data, base fit and augmented fit (force-displacement, mm and kN) and the residual
        before and after against time.

        Parameters
        ----------
        ax : None or a sequence of two Axes
            ``(ax_loops, ax_residual)``; ``None``: a new figure with two panels
            (:mod:`iwan_element.base.result_shape`).

        Returns
        -------
        list of matplotlib artists
        """
        a1, a2 = panels(ax, 2, figsize=(6, 8))
        step = max(1, self.u.size // 20000)
        u, F = self.u[::step] * 1e3, self.F[::step] * 1e-3
        arts = a1.plot(u, F, ".", ms=1.5, color="0.6", label="measured")
        arts += a1.plot(
            u,
            self.force_before[::step] * 1e-3,
            "-",
            lw=0.9,
            color="C0",
            label=f"Iwan fit ({100 * self.error_before:.2g} %)",
        )
        lab = " + ".join(self.effects) if self.effects else "no effect named"
        arts += a1.plot(
            u,
            self.force_after[::step] * 1e-3,
            "--",
            lw=0.9,
            color="C3",
            label=f"augmented: {lab} ({100 * self.error_after:.2g} %)",
        )
        a1.set_xlabel("displacement [mm]")
        a1.set_ylabel("force [kN]")
        a1.grid(True, alpha=0.3)
        a1.legend(fontsize=7, loc="upper left")
        tt = self.t[::step]
        arts += a2.plot(
            tt,
            (self.F - self.force_before)[::step],
            "-",
            lw=0.6,
            color="C0",
            label="residual before",
        )
        arts += a2.plot(
            tt, (self.F - self.force_after)[::step], "-", lw=0.6, color="C3", label="residual after"
        )
        arts.append(
            a2.axhspan(
                -2 * self.noise_sigma,
                2 * self.noise_sigma,
                color="0.85",
                zorder=0,
                label="+-2 noise",
            )
        )
        a2.set_xlabel("time [s]", fontsize=7)
        a2.set_ylabel("residual [N]", fontsize=7)
        a2.tick_params(labelsize=6)
        a2.legend(fontsize=6, loc="upper right")
        return arts


def _describe(model) -> str:
    return model.describe() if hasattr(model, "describe") else repr(model.params)
