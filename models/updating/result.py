"""The result of :func:`~iwan_element.models.updating.update.linear_update`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from iwan_element.base.result_shape import ResultShape, panels, table_lines
from iwan_element.base.serialize import json_safe
from iwan_element.fitting import ParameterTable

from ..solid.specimen import SolidSpecimen
from ..specimens.specimen import Specimen

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["LinearUpdateResult"]


@dataclass(frozen=True)
class LinearUpdateResult(ResultShape):
    """Result of :func:`linear_update`.

    Attributes
    ----------
    specimen : Specimen or SolidSpecimen
        The updated specimen (same type, frozen).
    initial : Specimen or SolidSpecimen
        The nominal one.
    params : ParameterTable
        Value, stderr, physical range (``lower``, ``upper``), unit; ``identified`` for the
        updated ones, ``fixed`` for those left at their nominal value; ``correlation``.
    groups, nominal, information : dict
        Each parameter's group, nominal value and the targets' new information about it (the
        pivot of step 3 in units of its prior; < 1: not identifiable).
    singular_values : ndarray
        Of the prior-scaled weighted sensitivity matrix (every parameter asked for).
    residuals : tuple of dict
        Per target: ``target``, ``measured``, model ``before`` and ``after``, and the weighted
        residuals.
    predictions : dict
        ``{mode: {"frequency", "stderr", "parameter_stderr", "nominal_frequency"}}`` [Hz] for
        the modes that were not targets (``stderr`` includes the model-form error).
    chi2, dof : float, int
        Sum of squared weighted residuals after, and residuals less identified parameters.
    converged : bool
    nfev : int
    model_error : dict
    """

    plot_panels = 1

    specimen: Specimen | SolidSpecimen
    initial: Specimen | SolidSpecimen
    params: ParameterTable
    groups: dict
    nominal: dict
    information: dict
    singular_values: np.ndarray
    residuals: tuple
    predictions: dict
    chi2: float
    dof: int
    converged: bool
    nfev: int = 0
    model_error: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """Converged, every asked parameter identified, none on its bound, no misfit beyond
        the stated errors.
        """
        return self.converged and not self.warnings

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False: no convergence, then every warning (empty when usable)."""
        if self.success:
            return ()
        return (() if self.converged else ("the update did not converge",)) + tuple(self.warnings)

    def predict(self, mode: int) -> tuple:
        """``(frequency, stderr)`` [Hz] of a mode that was not a target."""
        p = self.predictions[int(mode)]
        return p["frequency"], p["stderr"]

    def _target_rows(self) -> list:
        """Per target: ``(name, measured, before, after, weighted residual before, after)``."""
        keys = ("measured", "before", "after", "residual_before", "residual_after")
        return [(r["target"], *(r[k] for k in keys)) for r in self.residuals]

    def _tables(self) -> list:
        """The parameters, then the targets (measured, before and after the update, each in
        its own unit: a frequency [Hz], a unit-normalised shape entry [-], a modal constant
        [1/kg]; the residuals weighted by the targets' errors [-]), then the rest.
        """
        units = {"f": "Hz", "s": "-", "c": "1/kg"}
        rows = [(t, units.get(t[:1], "-"), *vals) for t, *vals in self._target_rows()]
        cols = (
            "target",
            "unit",
            "measured",
            "before",
            "after",
            "weighted residual before",
            "weighted residual after",
        )
        out = super()._tables()
        at = next(i for i, t in enumerate(out) if t[0] == "rows")
        out[at] = ("targets", cols, rows)
        return out

    def report(self) -> str:
        """Human-readable account: the parameters, the targets and the predictions [Hz]."""
        lines = [
            self.verdict(),
            f"Linear update of {self.initial.name!r}",
            f"  {'parameter':34s} {'nominal':>12s} {'updated':>12s} {'stderr':>10s} "
            f"{'range':>23s}  status",
        ]
        for n, p in self.params.items():
            se = f"{p.stderr:.3g}" if math.isfinite(p.stderr) else "n/a"
            lines.append(
                f"  {n + ' [' + p.unit + ']':34s} {self.nominal[n]:12.5g} {p.value:12.5g} "
                f"{se:>10s} {p.lower:11.4g}..{p.upper:<10.4g}  {p.status}"
            )
        lines.append(
            "  singular values of the weighted sensitivity: "
            + ", ".join(f"{s:.3g}" for s in self.singular_values)
        )
        lines += table_lines(
            [
                ("target", "<16"),
                ("measured", "12.6g"),
                ("before", "12.6g"),
                ("after", "12.6g"),
                ("res. before", "11.3f"),
                ("res. after", "10.3f"),
            ],
            self._target_rows(),
        )
        if self.predictions:
            lines.append(
                "  predicted modes (not targets): frequency +- stderr (parameters "
                "only) [Hz], nominal"
            )
            lines += [
                f"    mode {m}: {p['frequency']:.5g} +- {p['stderr']:.3g} "
                f"({p['parameter_stderr']:.2g}), nominal {p['nominal_frequency']:.5g}"
                for m, p in self.predictions.items()
            ]
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe: the parameters, residuals, predictions, chi2, success and warnings."""
        return json_safe(
            {
                "params": self.params.to_dict(),
                "nominal": self.nominal,
                "groups": self.groups,
                "information": self.information,
                "singular_values": list(self.singular_values),
                "rows": list(self.residuals),
                "predictions": {str(k): v for k, v in self.predictions.items()},
                "chi2": self.chi2,
                "dof": self.dof,
                "converged": self.converged,
                "success": self.success,
                "model_error": self.model_error,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Weighted residual of every target before and after (bars); returns the
        artists.
        """
        (a,) = panels(ax, 1, figsize=(7, 3.5))
        x = np.arange(len(self.residuals))
        arts = list(
            a.bar(x - 0.2, [r["residual_before"] for r in self.residuals], 0.4, label="before")
        )
        arts += list(
            a.bar(x + 0.2, [r["residual_after"] for r in self.residuals], 0.4, label="after")
        )
        a.set_xticks(x, [r["target"] for r in self.residuals], rotation=45, ha="right", fontsize=8)
        a.set(ylabel="residual / stderr [-]")
        a.axhline(0.0, color="k", lw=0.5)
        a.legend(fontsize=8)
        return arts
