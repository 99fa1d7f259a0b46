"""Result objects of the two diagnoses: :class:`Diagnosis` (loops) and
:class:`VibrationDiagnosis` (amplitude-dependent frequency and damping)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.serialize import json_safe
from ..effects import EFFECTS
from ..fitting import Parameter, ParameterTable, verdict
from ..core.result_shape import ResultShape, panels, unit_label, value_stderr, wrap
from ._augment import augmented

__all__ = ["Diagnosis", "VibrationDiagnosis"]


def _unit(name: str, key: str, modal: bool = False) -> str:
    specs = EFFECTS[name].modal_specs if modal else EFFECTS[name].specs
    return "[" + unit_label(next((s.unit for s in specs if s.name == key), "")) + "]"



def _verdict_lines(word: str, result) -> list:
    """The closing lines of a diagnosis report: misfit before and after, noise, warnings."""
    lines = [f"  {word} before {100 * result.error_before:.3g} % -> after "
             f"{100 * result.error_after:.3g} % (noise {100 * result.noise_level:.3g} %)"]
    if result.warnings:
        lines.append("  warnings:")
        for w in result.warnings:
            lines += wrap(f"  - {w}", indent="    ")
    return lines


#: What a vibration diagnosis' "mismatch" is, said once in its report and its tables.
MISMATCH = ("mismatch: RMS relative difference between measured and modelled frequency and "
            "damping ratio together (log residuals, each curve over its own noise), in %; "
            "dIC: information criterion above the step's best candidate (0: the best)")

@dataclass(frozen=True, eq=False)
class Diagnosis(ResultShape):
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

    @property
    def params(self):
        """The augmented fit's parameters (``fit.params``, a ``ParameterTable``)."""
        return self.fit.params

    def to_dict(self) -> dict:
        """JSON-safe dict (NaN/inf become None); the fits as :meth:`FitResult.to_dict`."""
        return json_safe({
            "effect": self.effect, "effects": list(self.effects),
            "ambiguous_with": list(self.ambiguous_with), "where": self.where,
            "success": self.success,
            "failure_reasons": list(self.failure_reasons()), "params": self.params.to_dict(),
            "offsets": value_stderr({"force": (self.offsets["force"],
                                               self.fit.details.get("force_offset_stderr")),
                                     "displacement": self.offsets["displacement"]}),
            "error_before": self.error_before, "error_after": self.error_after,
            "noise_level": self.noise_level, "noise_sigma": self.noise_sigma,
            "misfit": self.misfit, "steps": list(self.steps), "untestable": dict(self.untestable),
            "warnings": list(self.warnings), "base_fit": self.base_fit.to_dict(),
            "fit": self.fit.to_dict(), "model": _describe(self.model), "details": self.details,
        })

    def report(self) -> str:
        """Human-readable account: noise, misfit, where, candidates, verdict, before/after."""
        d = self.details
        p = self.base_fit.joint
        head = [f"{d['samples']} samples; noise {d['noise_from']}, correlation time "
                f"{d['tau']:.3g} samples ({d['n_eff']:.0f} independent samples fitted)",
                f"offsets (nuisance): force {self.offsets['force']:.4g} N, displacement "
                f"{self.offsets['displacement']:.4g} m" + (
                    f"; low-pass {d['lowpass']:g} Hz ({d['lowpass_reason']})"
                    if d.get("lowpass") else ""),
                f"noise: sigma = {self.noise_sigma:.4g} N (NRMSE {100 * self.noise_level:.3g} %)",
                f"base Iwan fit: Fs={p.Fs:.5g} N, KT={p.KT:.5g} N/m, chi={p.chi:.4f}, "
                f"beta={p.beta:.4f}; NRMSE {100 * self.error_before:.3g} % "
                f"= {self.error_before / self.noise_level:.3g} x noise "
                f"(misfit p-value {d['misfit_p']:.2g}, level {d['alpha']:g})",
                f"selection: {d['criterion']}", f"where: {self.where}"]
        lines = [self.verdict(), "Iwan model diagnosis"]
        for h in head:
            lines += wrap("  " + h, indent="    ")
        if self.steps:
            lines += wrap("  NRMSE: RMS force residual over the force range; x noise: its "
                          "ratio to the noise; dIC: information criterion above the step's "
                          "best candidate (0: the best)", indent="    ")
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'Iwan'}")
            lines.append("    effect               NRMSE[%]  x noise       dIC  explains  verdict")
            for c in st["candidates"]:
                lines.append(f"    {c['name']:<20} {100 * c['nrmse']:8.3g} {c['ratio']:8.3g} "
                             f"{c['dIC']:9.4g} {100 * c['explained']:7.3g} %  {c['verdict']}")
        for name, why in self.untestable.items():
            lines.append(f"  cannot test {name}: {why}")
        if self.effects:
            lines.append(f"  named: {', '.join(self.effects)}"
                         + (f" (nearly as good: {', '.join(self.ambiguous_with)})"
                            if self.ambiguous_with else ""))
            for e in self.fit.details.get("effects", []):
                ps = ", ".join(f"{k} = {v:.4g} {_unit(e['name'], k)} (+- {e['stderr'][k]:.2g})"
                               for k, v in e["parameters"].items())
                lines.append(f"    {e['name']}: {ps}")
            q = self.fit.joint
            lines.append(f"    Iwan part: Fs={q.Fs:.5g} N, KT={q.KT:.5g} N/m, chi={q.chi:.4f}, "
                         f"beta={q.beta:.4f}")
        else:
            lines.append("  named: none")
        return "\n".join(lines + _verdict_lines("error", self))

    def plot(self, ax=None):
        """Data, base fit and augmented fit (force-displacement, mm and kN) and the residual
        before and after against time.

        Parameters
        ----------
        ax : None or a sequence of two Axes
            ``(ax_loops, ax_residual)``; ``None``: a new figure with two panels
            (:mod:`iwan_element.core.result_shape`).

        Returns
        -------
        list of matplotlib artists
        """
        a1, a2 = panels(ax, 2, figsize=(6, 8))
        step = max(1, self.u.size // 20000)
        u, F = self.u[::step] * 1e3, self.F[::step] * 1e-3
        arts = a1.plot(u, F, ".", ms=1.5, color="0.6", label="measured")
        arts += a1.plot(u, self.force_before[::step] * 1e-3, "-", lw=0.9, color="C0",
                        label=f"Iwan fit ({100 * self.error_before:.2g} %)")
        lab = " + ".join(self.effects) if self.effects else "no effect named"
        arts += a1.plot(u, self.force_after[::step] * 1e-3, "--", lw=0.9, color="C3",
                        label=f"augmented: {lab} ({100 * self.error_after:.2g} %)")
        a1.set_xlabel("displacement [mm]")
        a1.set_ylabel("force [kN]")
        a1.grid(True, alpha=0.3)
        a1.legend(fontsize=7, loc="upper left")
        tt = self.t[::step]
        arts += a2.plot(tt, (self.F - self.force_before)[::step], "-", lw=0.6, color="C0",
                        label="residual before")
        arts += a2.plot(tt, (self.F - self.force_after)[::step], "-", lw=0.6, color="C3",
                        label="residual after")
        arts.append(a2.axhspan(-2 * self.noise_sigma, 2 * self.noise_sigma, color="0.85",
                               zorder=0, label="+-2 noise"))
        a2.set_xlabel("time [s]", fontsize=7)
        a2.set_ylabel("residual [N]", fontsize=7)
        a2.tick_params(labelsize=6)
        a2.legend(fontsize=6, loc="upper right")
        return arts



def _describe(model) -> str:
    return model.describe() if hasattr(model, "describe") else repr(model.params)


def _apply(names, parameters, X, f, z, zeta0):
    """The named effects' modal forms on a base curve, in order."""
    for n in names:
        f, z = EFFECTS[n].modal_form(X, f, z, zeta0, **parameters[n])
    return f, z


@dataclass(frozen=True, eq=False)
class VibrationDiagnosis(ResultShape):
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

    @property
    def params(self) -> ParameterTable:
        """The fitted modal values as a :class:`~iwan_element.fitting.ParameterTable`."""
        rows = [(f"{nm}.{sp.name}", sp, self.parameters[nm][sp.name]) for nm in self.parameters
                for sp in EFFECTS[nm].modal_specs]
        se = self.details.get("stderr", {})
        at = set(self.details.get("at_bound", ()))
        out = []
        for key, sp, v in rows:
            e = se.get(key)
            e = math.nan if e is None else float(e)
            out.append(Parameter(key, v, e, unit=sp.unit,
                                 identified=verdict(key, v, e, at_bound=key in at)[0]))
        return ParameterTable(out)

    @property
    def success(self) -> bool:
        """The one rule of docs/guards.md: every named effect's reported value is identified
        and no mismatch beyond the noise remains after the effects named (the same test as
        the warning saying so: the misfit's p-value below ``alpha`` before and after)."""
        return not self.failure_reasons()

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False (empty when it is True), in a tester's words."""
        d = self.details
        out = []
        if d["misfit_p"] < d["alpha"] and d["misfit_p_after"] < d["alpha"]:
            out.append("misfit well beyond the noise remains: "
                       + (f"after {' + '.join(self.effects)}" if self.effects else
                          "no tested effect explains it")
                       + f" (misfit p-value {d['misfit_p_after']:.2g} < {d['alpha']:g})")
        bad = [k for k, p in self.params.items() if not p.identified]
        if bad:
            out.append(f"{', '.join(bad)} {'is' if len(bad) == 1 else 'are'} not identified by "
                       "these data (standard error above half the value, or at a bound)")
        return tuple(out)

    def augment(self, target, *, modal_mass: float | None = None,
                slip_per_amplitude: float = 1.0, mode: int = 1):
        """The model with the named effects added: a beam specimen or a joint element.

        Parameters
        ----------
        target : Specimen or joint element
            A :class:`~iwan_element.models.specimens.Specimen` (anything with
            ``with_effects``): returned carrying the named effects in their modal form with
            the fitted values, on ``mode``, calibrated over the diagnosed amplitudes (its QSMA
            curve is then the diagnosis's ``model_frequency``/``model_damping_ratio`` when the
            prediction was that specimen's QSMA). Or a joint element, wrapped in the effects
            converted to joint terms.
        modal_mass : float, keyword-only
            For a joint: modal mass [kg] of the mode the curves describe, ``> 0``.
        slip_per_amplitude : float, keyword-only
            For a joint: joint slip per unit modal amplitude ``r`` [-], ``> 0``: a joint
            spring ``k`` adds ``k r^2`` to the modal stiffness, a dashpot ``c`` adds ``c r^2``.
        mode : int, keyword-only
            For a specimen: the elastic mode the curves describe (1: lowest).

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
        return augmented(self, target, modal_mass=modal_mass,
                         slip_per_amplitude=slip_per_amplitude, mode=mode)

    def predict(self, amplitude, *, base=None):
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
        from ..core.validation import finite_array
        from ..identify.curves import AmplitudeCurve
        X = finite_array("amplitude", amplitude, ndim=1, min_size=1)
        if np.any(X <= 0):
            raise ValueError("amplitude must be > 0 [m]")
        warns = []
        lo, hi = float(self.amplitude.min()), float(self.amplitude.max())
        out = (X < lo * (1 - 1e-9)) | (X > hi * (1 + 1e-9))
        if base is None:
            o = np.argsort(self.amplitude)
            lx = np.log(self.amplitude[o])
            fb = np.exp(np.interp(np.log(X), lx, np.log(self.predicted_frequency[o])))
            zb = np.exp(np.interp(np.log(X), lx, np.log(self.predicted_damping_ratio[o])))
            if out.any():
                warns.append(f"{int(out.sum())} amplitudes outside the diagnosed range {lo:.3g} .. "
                             f"{hi:.3g} m: the base prediction is held at its end values there; "
                             "pass base= (the model's curve at these amplitudes)")
        else:
            if not np.allclose(np.asarray(base.amplitude), X, rtol=1e-9, atol=0.0):
                raise ValueError("base must be the model's curve at exactly these amplitudes")
            fb, zb = np.asarray(base.frequency, float), np.asarray(base.damping_ratio, float)
        if out.any():
            warns.append(f"the fitted effects ({', '.join(self.effects) or 'none'}) are "
                         f"extrapolated beyond the diagnosed amplitudes {lo:.3g} .. {hi:.3g} m "
                         f"(up to {max(X.max() / hi, lo / X.min()):.3g} x beyond)")
        z0 = float(self.details.get("predicted_zeta0", 0.0))
        f, z = _apply(self.effects, self.parameters, X, fb, zb, z0)
        sf, sz = self._bands(X, fb, zb, z0, f, z)
        return AmplitudeCurve(X, f, z, frequency_std=sf, damping_ratio_std=sz, method="diagnosis",
                              notes="prediction + " + (" + ".join(self.effects) or "nothing"),
                              warnings=tuple(warns))

    def _bands(self, X, fb, zb, z0, f, z):
        """Linearised 1-sigma bands [Hz], [-] from the covariance of the fitted values."""
        keys = [(n, k) for n in self.effects for k in self.parameters[n]]
        C = self.covariance
        if not keys or C is None or C.shape != (len(keys), len(keys)):
            return np.zeros_like(f), np.zeros_like(z)
        G = np.empty((2 * X.size, len(keys)))
        for j, (n, k) in enumerate(keys):
            v = self.parameters[n][k]
            h = max(1e-6 * abs(v), 1e-6 * math.sqrt(max(C[j, j], 0.0)), 1e-300)
            p = {a: dict(b) for a, b in self.parameters.items()}
            p[n][k] = v + h
            f1, z1 = _apply(self.effects, p, X, fb, zb, z0)
            G[:, j] = np.concatenate([np.log(f1 / f), np.log(z1 / z)]) / h
        var = np.einsum("ij,jk,ik->i", G, C, G)
        s = np.sqrt(np.maximum(var, 0.0))
        return f * s[:X.size], z * s[X.size:]

    def to_dict(self) -> dict:
        """JSON-safe dict."""
        return json_safe({"params": self.params.to_dict()} | {k: getattr(self, k) for k in (
            "effect", "effects", "ambiguous_with", "where", "error_before",
            "error_after", "noise_level", "frequency_noise", "damping_ratio_noise", "amplitude",
            "frequency", "damping_ratio", "predicted_frequency", "predicted_damping_ratio",
            "model_frequency", "model_damping_ratio", "steps", "warnings", "details", "covariance")}
                         | {"success": self.success,
                            "failure_reasons": list(self.failure_reasons())})

    def report(self) -> str:
        """Human-readable account."""
        lines = [self.verdict(),
                 "Vibration diagnosis (amplitude-dependent frequency and damping)"]
        lines += wrap(f"  {self.amplitude.size} amplitudes, {self.amplitude.min():.3g} .. "
                      f"{self.amplitude.max():.3g} m; noise: frequency "
                      f"{100 * self.frequency_noise:.2g} %, damping "
                      f"{100 * self.damping_ratio_noise:.2g} % ({self.details['noise_from']})",
                      indent="    ")
        bt = self.details.get("between_tests")
        if bt:
            lines.append(
                f"  between-test nuisances (not named): frequency offset "
                f"{100 * bt['frequency_offset']:+.3g} % (+- {100 * bt['frequency_offset_stderr']:.2g}),"
                f" damping offset {100 * bt['damping_offset']:+.3g} % "
                f"(+- {100 * bt['damping_offset_stderr']:.2g}); not testable against them: "
                f"{', '.join(bt['untested']) or 'none'}")
        lines += wrap(f"  where: {self.where}", indent="    ")
        if self.steps:
            lines += wrap("  " + MISMATCH, indent="    ")
        for k, st in enumerate(self.steps):
            lines.append(f"  step {k + 1}: candidates on {' + '.join(st['on']) or 'prediction'}")
            for c in st["candidates"]:
                lines.append(f"    {c['name']:<18} mismatch {100 * c['error']:7.3g} %  dIC "
                             f"{c['dIC']:9.4g}  explains {100 * c['explained']:5.3g} %  "
                             f"{c['verdict']}")
        if self.effects:
            lines.append("  named: " + ", ".join(
                f"{n} ({EFFECTS[n].kind})" if getattr(EFFECTS[n], "kind", "") else n
                for n in self.effects) + (
                f" (nearly as good: {', '.join(self.ambiguous_with)})"
                if self.ambiguous_with else ""))
            for name, d in self.parameters.items():
                lines.append("    " + name + ": " + ", ".join(
                    f"{k} = {v:.4g} {_unit(name, k, modal=True)}" for k, v in d.items()))
        else:
            lines.append("  named: none")
        return "\n".join(lines + _verdict_lines("mismatch", self))

    def _tables(self) -> list:
        out = [t for t in super()._tables() if t[0] == "parameters"]
        cols = ("amplitude [m]", "frequency [Hz]", "predicted frequency [Hz]",
                "model frequency [Hz]", "damping_ratio [-]", "predicted damping_ratio [-]",
                "model damping_ratio [-]")
        out.append(("points", cols, list(zip(*(map(float, a) for a in (
            self.amplitude, self.frequency, self.predicted_frequency, self.model_frequency,
            self.damping_ratio, self.predicted_damping_ratio, self.model_damping_ratio))))))
        steps = [(k + 1, " + ".join(st["on"]) or "prediction", c["name"], 100 * c["error"],
                  c["dIC"], 100 * c["explained"], c["verdict"])
                 for k, st in enumerate(self.steps) for c in st["candidates"]]
        if steps:
            out.append(("candidates (" + MISMATCH + ")",
                        ("step", "on", "candidate", "mismatch [%]", "dIC [-]", "explains [%]",
                         "verdict"), steps))
        fit = [("mismatch before [%]", 100 * self.error_before),
               ("mismatch after [%]", 100 * self.error_after),
               ("noise [%]", 100 * self.noise_level), ("named", ", ".join(self.effects)
                                                         or "none"), ("where", self.where)]
        return out + [("goodness of fit", ("quantity", "value"), fit)]

    def plot(self, ax=None):
        """Frequency and damping against amplitude: measured, predicted, augmented.

        ``ax``: ``None`` (new figure, two panels) or a sequence of two Axes (frequency,
        damping; :mod:`iwan_element.core.result_shape`). Returns the artists."""
        a1, a2 = panels(ax, 2, figsize=(6, 7))
        X = self.amplitude
        o = np.argsort(X)
        arts = a1.semilogx(X[o], self.frequency[o], "o", ms=3, mfc="none", color="k", label="measured")
        arts += a1.semilogx(X[o], self.predicted_frequency[o], "-", color="C0", label="predicted")
        arts += a1.semilogx(X[o], self.model_frequency[o], "--", color="C3",
                            label="+ " + (" + ".join(self.effects) or "nothing"))
        a1.set_xlabel("amplitude [m]")
        a1.set_ylabel("frequency [Hz]")
        arts += a2.loglog(X[o], self.damping_ratio[o], "o", ms=3, mfc="none", color="k", label="measured")
        arts += a2.loglog(X[o], self.predicted_damping_ratio[o], "-", color="C0", label="predicted")
        arts += a2.loglog(X[o], self.model_damping_ratio[o], "--", color="C3",
                          label="+ " + (" + ".join(self.effects) or "nothing"))
        a2.set_xlabel("amplitude [m]")
        a2.set_ylabel("damping ratio [-]")
        for a in (a1, a2):
            a.grid(True, which="both", alpha=0.3)
            a.legend(fontsize=7)
        return arts
