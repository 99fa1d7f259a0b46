"""Result object of the vibration diagnosis: :class:`VibrationDiagnosis` (measured against
predicted amplitude-dependent frequency and damping, and what is missing).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...base.result_shape import ResultShape, panels, wrap
from ...base.serialize import json_safe
from ...effects import EFFECTS
from ...fitting import Parameter, ParameterTable, verdict
from ..selection.lines import effect_unit, verdict_lines
from ..selection.probable import Probable
from ._prediction import predicted_curve
from .augment import augmented

if TYPE_CHECKING:
    from matplotlib.artist import Artist

    from ...identify.modal.curves import AmplitudeCurve
    from ..selection.averaging import AveragedBand

__all__ = ["VibrationDiagnosis"]


#: What a vibration diagnosis' "mismatch" is, said once in its report and its tables.
MISMATCH = (
    "mismatch: RMS relative difference between measured and modelled frequency and "
    "damping ratio together (log residuals, each curve over its own noise), in %; "
    "dIC: information criterion above the step's best candidate (0: the best)"
)


@dataclass(frozen=True, eq=False)
class VibrationDiagnosis(Probable, ResultShape):
    """Measured against predicted amplitude-dependent frequency and damping: what is missing.

    Attributes
    ----------
    effect : str
        The first effect named (a name of :data:`~iwan_element.EFFECTS` with a modal form:
        ``"hardening"``, ``"macroslip_onset"``, ``"pinning_stiffness"``,
        ``"viscous_damping"``, ...) or ``"none"``.
    effects : tuple of str
        All effects named, in order.
    ambiguous_with : tuple of str
        Effects explaining the first step nearly as well.
    where : str
        Where measured and predicted curves disagree beyond the noise.
    parameters : dict
        Fitted modal values of each named effect (its ``modal_specs``: names, units,
        meaning), e.g. ``viscous_damping: {"zeta_v"}`` (added modal viscous damping
        ratio [-]); ``pinning_stiffness: {"k_p_per_mass" [1/s^2], "delta" [m]}``;
        ``hardening: {"k3_per_mass" [1/(m^2 s^2)]}``; ``macroslip_onset: {"kappa_2"
        [1/s^2], "X_s" [m], "shape" [-]}`` (amplitudes in the curve's units).
    error_before, error_after : float
        RMS relative mismatch of frequency and damping together [-] (log residuals).
    noise_level : float
        RMS relative noise of the two curves [-].
    frequency_noise, damping_ratio_noise : float
        Relative noise of each curve [-] (estimated or given).
    amplitude, frequency, damping_ratio : ndarray, shape (n,)
        The measured curve (read-only copies).
    predicted_frequency, predicted_damping_ratio : ndarray, shape (n,)
        The prediction it was compared with (read-only copies).
    model_frequency, model_damping_ratio : ndarray, shape (n,)
        The prediction with the named effects added.
    steps : tuple of dict
    warnings : tuple of str
        What the data cannot support (few amplitudes for a noise estimate, a mismatch left
        beyond the noise, and where).
    details : dict
    covariance : ndarray or None
        Covariance of the fitted modal values (in the order of ``parameters``), from the
        noise-normalised Jacobian, scaled by the reduced chi-square when above 1.
    params : ParameterTable
        (property) The fitted modal values ``"effect.name"`` with their standard errors
        (``details["stderr"]``: from :func:`iwan_element.fitting.covariance`, NaN for a value
        the data do not determine), units and verdicts (:func:`iwan_element.fitting.verdict`;
        a value at the upper end of its fit range, ``details["at_bound"]``, is not
        identified); empty when nothing was named.
    explanations : tuple of Explanation
        Every explanation fitted (the prediction alone, each single effect, each stack
        fitted on the way) with its evidence and posterior probability, most probable
        first (:mod:`~iwan_element.diagnose.probabilities`); ``probabilities`` and
        ``effect_probability(name)`` read them, ``averaged_band`` predicts with them.
    """

    plot_panels = 2

    effect: str
    effects: tuple
    ambiguous_with: tuple
    where: str
    parameters: dict
    error_before: float
    error_after: float
    noise_level: float
    frequency_noise: float
    damping_ratio_noise: float
    amplitude: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    predicted_frequency: np.ndarray
    predicted_damping_ratio: np.ndarray
    model_frequency: np.ndarray
    model_damping_ratio: np.ndarray
    steps: tuple
    details: dict = field(default_factory=dict)
    covariance: np.ndarray | None = None
    explanations: tuple = ()

    @property
    def params(self) -> ParameterTable:
        """The fitted modal values as a :class:`~iwan_element.fitting.ParameterTable`."""
        rows = [
            (f"{nm}.{sp.name}", sp, self.parameters[nm][sp.name])
            for nm in self.parameters
            for sp in EFFECTS[nm].modal_specs
        ]
        se = self.details.get("stderr", {})
        at = set(self.details.get("at_bound", ()))
        out = []
        for key, sp, v in rows:
            e = se.get(key)
            e = math.nan if e is None else float(e)
            out.append(
                Parameter(
                    key, v, e, unit=sp.unit, identified=verdict(key, v, e, at_bound=key in at)[0]
                )
            )
        return ParameterTable(tuple(out))

    @property
    def success(self) -> bool:
        """The one rule of docs/guards.md: every named effect's reported value is identified
        and no mismatch beyond the noise remains after the effects named (the same test as
        the warning saying so: the misfit's p-value below ``alpha`` before and after).
        """
        return not self.failure_reasons()

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False (empty when it is True), in a tester's words."""
        d = self.details
        out = []
        if d["misfit_p"] < d["alpha"] and d["misfit_p_after"] < d["alpha"]:
            out.append(
                "misfit well beyond the noise remains: "
                + (
                    f"after {' + '.join(self.effects)}"
                    if self.effects
                    else "no tested effect explains it"
                )
                + f" (misfit p-value {d['misfit_p_after']:.2g} < {d['alpha']:g})"
            )
        bad = [k for k, p in self.params.items() if not p.identified]
        if bad:
            out.append(
                f"{', '.join(bad)} {'is' if len(bad) == 1 else 'are'} not identified by "
                "these data (standard error above half the value, or at a bound)"
            )
        return tuple(out)

    def augment(
        self,
        target,
        *,
        modal_mass: float | None = None,
        slip_per_amplitude: float = 1.0,
        mode: int = 1,
        form: str = "physical",
    ) -> Any:
        """The model with the named effects added: a beam specimen or a joint element.

        Parameters
        ----------
        target : Specimen or joint element
            A :class:`~iwan_element.models.specimens.Specimen` (anything with
            ``with_effects``): returned carrying the named effects fitted on ``mode``,
            calibrated over the diagnosed amplitudes, in the joint (``form="physical"``:
            ``InterfaceEffect`` entries, a law at the contact points that every analysis
            runs in every mode; the model maps the fitted values to the points through the
            slip per sensor amplitude of ``mode`` and fits them so that the joint's QSMA on
            ``mode`` reproduces the fitted curve,
            :func:`~iwan_element.models.resolve_interface_effects`,
            docs/vibration_effects.md) or in their modal form
            (``form="modal"``: ``SpecimenEffect`` entries acting on ``mode`` alone; its QSMA
            curve is then the diagnosis's ``model_frequency``/``model_damping_ratio`` when
            the prediction was that specimen's QSMA). Or a joint element, wrapped in the
            effects converted to joint terms.
        modal_mass : float, keyword-only
            For a joint: modal mass [kg] of the mode the curves describe, ``> 0``.
        slip_per_amplitude : float, keyword-only
            For a joint: joint slip per unit modal amplitude ``r`` [-], ``> 0``: a joint
            spring ``k`` adds ``k r^2`` to the modal stiffness, a dashpot ``c`` adds ``c r^2``.
        mode : int, keyword-only
            For a specimen: the elastic mode the curves describe (1: lowest).
        form : {"physical", "modal"}, keyword-only
            For a specimen: the effects in the joint (default) or on ``mode`` alone (where a
            user has one mode and wants the fitted curve exactly).

        Returns
        -------
        Specimen or joint element
            For a joint: e.g. ``PinningStiffness(k_p = kappa m / r^2, delta = delta r)``
            and/or ``ViscousDamping(c = 2 zeta_v omega_0 m / r^2)`` around ``joint``, with
            ``omega_0`` the measured angular frequency at the smallest amplitude (each effect's
            ``modal_to_joint``).

        Raises
        ------
        ValueError
            A specimen whose documented and calibrated amplitudes the diagnosed ones miss by
            more than a factor 30 (amplitudes given in mm or um, docs/guards.md); a target that
            is neither a specimen nor a joint element; a missing or bad ``modal_mass``.
        """
        return augmented(
            self,
            target,
            modal_mass=modal_mass,
            slip_per_amplitude=slip_per_amplitude,
            mode=mode,
            form=form,
        )

    def predict(self, amplitude, *, base=None) -> AmplitudeCurve:
        """The augmented model's frequency and damping at new amplitudes, with 1-sigma bands.

        Parameters
        ----------
        amplitude : array_like, shape (m,)
            Amplitudes [m], ``> 0``.
        base : AmplitudeCurve, optional, keyword-only
            The model without the named effects at exactly these amplitudes (e.g. the
            specimen's QSMA curve). Default: the prediction the diagnosis was given,
            interpolated in log amplitude; outside the diagnosed amplitudes it is held at
            its end values and a warning says so (pass ``base`` there).

        Returns
        -------
        AmplitudeCurve
            ``method="diagnosis"``; ``frequency_std`` and ``damping_ratio_std`` are the bands
            (1 sigma) from the fitted parameters' covariance (linearised), ``warnings`` states
            extrapolation beyond the diagnosed amplitudes.
        """
        return predicted_curve(self, amplitude, base)

    def averaged_band(self, amplitude, *, base=None, level: float = 0.95) -> AveragedBand:
        """Frequency and damping predicted with the doubt about the model: every probable
        explanation's modal forms weighted by its probability, each with its parameters'
        posterior covariance (:mod:`~iwan_element.diagnose.averaging`); ``base`` as in
        :meth:`predict`. Returns an ``AveragedBand`` (channels ``"frequency"`` [Hz] and
        ``"damping_ratio"`` [-]).
        """
        from .evidence import vibration_band

        return vibration_band(self, amplitude, base, level)

    def to_dict(self) -> dict:
        """JSON-safe dict."""
        return json_safe(
            {"params": self.params.to_dict()}
            | {
                k: getattr(self, k)
                for k in (
                    "effect",
                    "effects",
                    "ambiguous_with",
                    "where",
                    "error_before",
                    "error_after",
                    "noise_level",
                    "frequency_noise",
                    "damping_ratio_noise",
                    "amplitude",
                    "frequency",
                    "damping_ratio",
                    "predicted_frequency",
                    "predicted_damping_ratio",
                    "model_frequency",
                    "model_damping_ratio",
                    "steps",
                    "warnings",
                    "details",
                    "covariance",
                )
            }
            | {
                "success": self.success,
                "failure_reasons": list(self.failure_reasons()),
                "probabilities": self.probabilities_dict(),
            }
        )

    def report(self) -> str:
        """Human-readable account."""
        lines = [self.verdict(), "Vibration diagnosis (amplitude-dependent frequency and damping)"]
        lines += wrap(
            f"  {self.amplitude.size} amplitudes, {self.amplitude.min():.3g} .. "
            f"{self.amplitude.max():.3g} m; noise: frequency "
            f"{100 * self.frequency_noise:.2g} %, damping "
            f"{100 * self.damping_ratio_noise:.2g} % ({self.details['noise_from']})",
            indent="    ",
        )
        bt = self.details.get("between_tests")
        if bt:
            lines.append(
                f"  between-test nuisances (not named): frequency offset "
                f"{100 * bt['frequency_offset']:+.3g} % "
                f"(+- {100 * bt['frequency_offset_stderr']:.2g}),"
                f" damping offset {100 * bt['damping_offset']:+.3g} % "
                f"(+- {100 * bt['damping_offset_stderr']:.2g}); not testable against them: "
                f"{', '.join(bt['untested']) or 'none'}"
            )
        lines += wrap(f"  where: {self.where}", indent="    ")
        if self.steps:
            lines += wrap("  " + MISMATCH, indent="    ")
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'prediction'}")
            width = max([18] + [len(c["name"]) for c in st["candidates"]])
            for c in st["candidates"]:
                lines.append(
                    f"    {c['name']:<{width}} mismatch {100 * c['error']:7.3g} %  dIC "
                    f"{c['dIC']:9.4g}  explains {100 * c['explained']:5.3g} %  "
                    f"{c['verdict']}"
                )
        if self.effects:
            lines.append(
                "  named: "
                + ", ".join(
                    f"{n} ({EFFECTS[n].kind})" if getattr(EFFECTS[n], "kind", "") else n
                    for n in self.effects
                )
                + (
                    f" (nearly as good: {', '.join(self.ambiguous_with)})"
                    if self.ambiguous_with
                    else ""
                )
            )
            for name, d in self.parameters.items():
                lines.append(
                    "    "
                    + name
                    + ": "
                    + ", ".join(
                        f"{k} = {v:.4g} {effect_unit(name, k, modal=True)}" for k, v in d.items()
                    )
                )
        else:
            lines.append("  named: none")
        lines += self.probability_lines()
        rule = tuple(self.details.get("rule_named", self.effects))
        if set(rule) != set(self.effects):
            lines.append(f"    (the stepwise rule alone names {' + '.join(rule) or 'nothing'})")
        return "\n".join(lines + verdict_lines("mismatch", self))

    def _tables(self) -> list:
        out = [t for t in super()._tables() if t[0] == "parameters"]
        cols = (
            "amplitude [m]",
            "frequency [Hz]",
            "predicted frequency [Hz]",
            "model frequency [Hz]",
            "damping_ratio [-]",
            "predicted damping_ratio [-]",
            "model damping_ratio [-]",
        )
        out.append(
            (
                "points",
                cols,
                list(
                    zip(
                        *(
                            map(float, a)
                            for a in (
                                self.amplitude,
                                self.frequency,
                                self.predicted_frequency,
                                self.model_frequency,
                                self.damping_ratio,
                                self.predicted_damping_ratio,
                                self.model_damping_ratio,
                            )
                        )
                    )
                ),
            )
        )
        steps = [
            (
                k + 1,
                " + ".join(st["on"]) or "prediction",
                c["name"],
                100 * c["error"],
                c["dIC"],
                100 * c["explained"],
                c["verdict"],
            )
            for k, st in enumerate(self.steps)
            for c in st["candidates"]
        ]
        if steps:
            out.append(
                (
                    "candidates (" + MISMATCH + ")",
                    (
                        "step",
                        "on",
                        "candidate",
                        "mismatch [%]",
                        "dIC [-]",
                        "explains [%]",
                        "verdict",
                    ),
                    steps,
                )
            )
        fit = [
            ("mismatch before [%]", 100 * self.error_before),
            ("mismatch after [%]", 100 * self.error_after),
            ("noise [%]", 100 * self.noise_level),
            ("named", ", ".join(self.effects) or "none"),
            ("where", self.where),
        ]
        return (
            out[:1]
            + self.probability_tables()
            + out[1:]
            + [("goodness of fit", ("quantity", "value"), fit)]
        )

    def plot(self, ax=None) -> list[Artist]:
        """Frequency and damping against amplitude: measured, predicted, augmented.

        ``ax``: ``None`` (new figure, two panels) or a sequence of two Axes (frequency,
        damping; :mod:`iwan_element.base.result_shape`). Returns the artists.
        """
        a1, a2 = panels(ax, 2, figsize=(6, 7))
        X = self.amplitude
        o = np.argsort(X)
        arts = a1.semilogx(
            X[o], self.frequency[o], "o", ms=3, mfc="none", color="k", label="measured"
        )
        arts += a1.semilogx(X[o], self.predicted_frequency[o], "-", color="C0", label="predicted")
        arts += a1.semilogx(
            X[o],
            self.model_frequency[o],
            "--",
            color="C3",
            label="+ " + (" + ".join(self.effects) or "nothing"),
        )
        a1.set_xlabel("amplitude [m]")
        a1.set_ylabel("frequency [Hz]")
        arts += a2.loglog(
            X[o], self.damping_ratio[o], "o", ms=3, mfc="none", color="k", label="measured"
        )
        arts += a2.loglog(X[o], self.predicted_damping_ratio[o], "-", color="C0", label="predicted")
        arts += a2.loglog(
            X[o],
            self.model_damping_ratio[o],
            "--",
            color="C3",
            label="+ " + (" + ".join(self.effects) or "nothing"),
        )
        a2.set_xlabel("amplitude [m]")
        a2.set_ylabel("damping ratio [-]")
        for a in (a1, a2):
            a.grid(True, which="both", alpha=0.3)
            a.legend(fontsize=7)
        return arts
