"""Mode coupling through the interface, made visible: each mode's damping against its own
amplitude with and without the other modes ringing through the same joint, and with and
without each effect the joint carries.

:func:`mode_coupling` runs the multi-mode ring-down (:func:`~iwan_element.models.ringdown`
with ``amplitude={mode: X, ...}``) and one single-mode ring-down per mode from the same
amplitude, for the same duration (each at ``steps_per_period`` of its own period), and
compares each mode's decay curves at the same amplitudes (:func:`compare_curves`). A modal
Iwan model (one uncoupled single-degree-of-freedom system per mode) would give ratio 1; the
transient of the whole specimen shows how much one mode's slip raises another's damping
(``docs/multi_mode.md``). With ``effects=True`` the multi-mode ring-down is run again once
per named effect of the specimen (``interface_effects``, the effects in the joint, and
``effects``, the modal ones) with that effect taken out, and each mode's curve with every
effect is compared with the curve without it: what each effect adds to each mode.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from iwan_element import AmplitudeCurve
from iwan_element.base.result_shape import ResultShape, column, panels, table_lines
from iwan_element.base.serialize import json_safe

from ..modal.qsma import resolve_interface_effects
from ..reduced.dispatch import linear_system
from ..specimens.specimen import Specimen
from .ringdown_result import RingdownResult
from .solver import MAX_STEPS, check_steps
from .transient import preflight, ringdown

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["compare_curves", "ModeCouplingResult", "mode_coupling", "plot_curve_pairs"]


def compare_curves(curve: AmplitudeCurve, reference: AmplitudeCurve) -> dict:
    """``curve`` against ``reference`` at the amplitudes of ``curve`` that lie inside
    ``reference``'s range (``reference``'s frequency and damping interpolated linearly in
    log amplitude): a mode with the other modes against alone, a prediction against a
    measurement.

    Returns
    -------
    dict of ndarray
        ``amplitude`` [m], ``frequency``, ``frequency_reference`` [Hz], ``damping``,
        ``damping_reference`` [-], ``damping_ratio`` (curve over reference [-]) and
        ``frequency_shift`` (curve over reference minus 1 [-]); empty arrays when the
        ranges do not overlap.
    """
    for name, c in (("curve", curve), ("reference", reference)):
        if not isinstance(c, AmplitudeCurve):
            raise ValueError(f"{name} must be an AmplitudeCurve, got {type(c).__name__}")
    order = np.argsort(reference.amplitude)
    la = np.log(reference.amplitude[order])
    X = curve.amplitude
    inside = (
        (len(reference) >= 2) & (X >= reference.amplitude.min()) & (X <= reference.amplitude.max())
    )
    x = np.log(X[inside])
    fr = np.interp(x, la, reference.frequency[order])
    zr = np.interp(x, la, reference.damping_ratio[order])
    f, z = curve.frequency[inside], curve.damping_ratio[inside]
    return {
        "amplitude": X[inside],
        "frequency": f,
        "frequency_reference": fr,
        "damping": z,
        "damping_reference": zr,
        "damping_ratio": z / zr,
        "frequency_shift": f / fr - 1.0,
    }


@dataclass(frozen=True)
class ModeCouplingResult(ResultShape):
    """Result of :func:`mode_coupling`, with the package's result shape.

    Attributes
    ----------
    modes : tuple of int
    together : RingdownResult
        The multi-mode ring-down.
    alone : tuple of RingdownResult
        One single-mode ring-down per mode of ``modes``, same amplitude and duration.
    figures : dict
        ``{mode: compare_curves(with the other modes, alone)}``.
    without : dict
        ``{effect name: RingdownResult}``: the multi-mode ring-down with that effect taken
        out (``mode_coupling(..., effects=True)``; empty otherwise).
    effect_figures : dict
        ``{(mode, effect name): compare_curves(with every effect, without that one)}``.
    warnings : tuple of str
    """

    plot_panels = 2

    modes: tuple
    together: RingdownResult
    alone: tuple
    figures: dict
    without: dict = field(default_factory=dict)
    effect_figures: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """True when every run succeeded and every mode's curves overlap in amplitude."""
        return bool(
            self.together.success
            and all(r.success for r in self.alone)
            and all(r.success for r in self.without.values())
            and all(len(f["amplitude"]) for f in self.figures.values())
            and all(len(f["amplitude"]) for f in self.effect_figures.values())
        )

    def effect_summary(self) -> dict:
        """``{(mode, effect): {"points", "max_damping_ratio", "at_amplitude",
        "frequency_shift"}}``: per mode, how much each effect raises its damping (the largest
        ratio with the effect over without it) and shifts its frequency there.
        """
        return {key: _largest(f) for key, f in self.effect_figures.items()}

    def summary(self) -> dict:
        """Per mode: the largest damping raise and frequency shift from the other modes."""
        return {r: _largest(f) for r, f in self.figures.items()}

    def _tables(self) -> list:
        """Per mode and amplitude, the damping together and alone and the frequency shift
        (the main table), then the run.
        """
        rows = [(int(r), *vals) for r, vals in _figure_rows(self.figures)]
        cols = (
            "mode",
            column("amplitude", "m"),
            column("damping together", "-"),
            column("damping alone", "-"),
            column("damping ratio together/alone", "-"),
            column("frequency shift df/f", "-"),
        )
        run = [
            ("modes", ", ".join(map(str, self.modes))),
            (column("wall time", "s"), float(self.together.wall_time)),
        ]
        out: list[tuple[str, tuple, list]] = [("modes", cols, rows)]
        if self.effect_figures:
            eff = [(int(r), name, *vals) for (r, name), vals in _figure_rows(self.effect_figures)]
            ecols = (
                "mode",
                "effect",
                column("amplitude", "m"),
                column("damping with every effect", "-"),
                column("damping without the effect", "-"),
                column("damping ratio with/without", "-"),
                column("frequency shift df/f", "-"),
            )
            out.append(("effects", ecols, eff))
        return out + [("run", ("quantity", "value"), run)]

    def report(self) -> str:
        """Human-readable account: per mode, its damping with and without the others."""
        lines = [
            self.verdict(),
            f"mode coupling through the interface: modes {', '.join(map(str, self.modes))}"
            f" released together ({self.together.wall_time:.3g} s wall) and alone",
        ]
        for r, f in self.figures.items():
            n = len(f["amplitude"])
            k = np.unique(np.linspace(0, n - 1, min(n, 12)).round().astype(int))
            rows = zip(
                1e6 * f["amplitude"][k],
                100 * f["damping"][k],
                100 * f["damping_reference"][k],
                f["damping_ratio"][k],
                1e6 * f["frequency_shift"][k],
            )
            lines.append(f"  mode {r} ({n} points, {len(k)} shown):")
            lines += table_lines(
                (
                    ("X [um]", "10.4g"),
                    ("zeta together [%]", "18.4f"),
                    ("zeta alone [%]", "15.4f"),
                    ("ratio", "7.3f"),
                    ("df/f [ppm]", "11.1f"),
                ),
                rows,
                indent=4,
            )
        for (r, name), e in self.effect_summary().items():
            q = e["max_damping_ratio"]
            lines.append(
                f"  mode {r}, {name}: "
                + (
                    "no common amplitudes with and without it"
                    if q is None
                    else f"damping x{q:.3f} with it at {1e6 * e['at_amplitude']:.4g} um "
                    f"(df/f {1e6 * e['frequency_shift']:+.1f} ppm)"
                )
            )
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe: the figures, the summaries, success and warnings."""
        return json_safe(
            {
                "modes": list(self.modes),
                "figures": {str(k): v for k, v in self.figures.items()},
                "summary": {str(k): v for k, v in self.summary().items()},
                "effect_figures": {f"{r}:{n}": v for (r, n), v in self.effect_figures.items()},
                "effect_summary": {f"{r}:{n}": v for (r, n), v in self.effect_summary().items()},
                "wall_time": self.together.wall_time,
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Each mode's damping ratio [%] and frequency [Hz] against its amplitude, together
        (filled) and alone (open), on ``ax = (ax_z, ax_f)``; returns the artists.
        """
        ax_z, ax_f = panels(ax, 2, figsize=(6, 6))
        pairs = [
            (f"mode {r}", self.together.mode_curve(r), "with the other modes", rd.curve, "alone")
            for r, rd in zip(self.modes, self.alone)
        ]
        return plot_curve_pairs(ax_z, ax_f, pairs, ("o-", "s--"))


def _figure_rows(figures: dict) -> list:
    """``[(key, (amplitude, damping, reference damping, ratio, df/f)), ...]``: every
    amplitude of every :func:`compare_curves` figure of ``figures`` (``{key: figure}``).
    """
    names = ("amplitude", "damping", "damping_reference", "damping_ratio", "frequency_shift")
    return [
        (key, tuple(float(v) for v in row))
        for key, f in figures.items()
        for row in zip(*(f[n] for n in names))
    ]


def _largest(f: dict) -> dict:
    """The largest damping ratio of a :func:`compare_curves` figure, its amplitude and the
    frequency shift there (None where the curves do not overlap).
    """
    k = int(np.argmax(f["damping_ratio"])) if len(f["amplitude"]) else None
    return {
        "points": len(f["amplitude"]),
        "max_damping_ratio": None if k is None else float(f["damping_ratio"][k]),
        "at_amplitude": None if k is None else float(f["amplitude"][k]),
        "frequency_shift": None if k is None else float(f["frequency_shift"][k]),
    }


def named_effects(specimen) -> tuple:
    """The names of the effects a specimen carries, in the joint (``interface_effects``)
    and in modal form (``effects``), each once, in order.
    """
    names = [e.name for e in getattr(specimen, "interface_effects", ())]
    names += [e.name for e in getattr(specimen, "effects", ())]
    return tuple(dict.fromkeys(names))


def without_effect(specimen, name: str) -> Any:
    """A copy of ``specimen`` with the effect ``name`` taken out of its joint and modal
    effects (the rest kept).
    """
    changes = {
        k: tuple(e for e in getattr(specimen, k) if e.name != name)
        for k in ("interface_effects", "effects")
        if hasattr(specimen, k)
    }
    return specimen.replace(**changes)


def plot_curve_pairs(ax_z, ax_f, pairs, formats) -> list:
    """Damping ratio [%] (on ``ax_z``) and frequency [Hz] (on ``ax_f``) against amplitude of
    ``pairs = [(name, curve, label, other curve, other label), ...]``, one colour per pair,
    the second curve of each drawn in ``formats[1]`` with open markers; returns the artists.
    """
    arts = []
    for i, (name, c1, l1, c2, l2) in enumerate(pairs):
        for c, fmt, lab, fill in ((c1, formats[0], l1, True), (c2, formats[1], l2, False)):
            kw = {"color": f"C{i}", "ms": 3, "label": f"{name} {lab}"}
            if not fill:
                kw["mfc"] = "none"
            arts += ax_z.semilogx(c.amplitude, 100 * c.damping_ratio, fmt, **kw)
            arts += ax_f.semilogx(c.amplitude, c.frequency, fmt, **kw)
    ax_z.set(xlabel="amplitude at the sensor [m]", ylabel="damping ratio [%]")
    ax_f.set(xlabel="amplitude at the sensor [m]", ylabel="frequency [Hz]")
    ax_z.legend(fontsize=7)
    return arts


def mode_coupling(
    specimen: Specimen,
    *,
    amplitude: dict,
    duration: float,
    steps_per_period: int = 64,
    n_periods: float = 3.0,
    effects: bool = False,
    max_steps: int = MAX_STEPS,
) -> ModeCouplingResult:
    """Each mode's damping with and without the other modes through the same interface, and
    with and without each effect the specimen carries.

    Every run's release, length and cost are checked before the first one starts (the
    errors of :func:`~iwan_element.models.ringdown`).

    Parameters
    ----------
    specimen : Specimen
    amplitude : dict, keyword-only
        ``{mode: amplitude at the sensor [m]}``, at least two modes.
    duration : float, keyword-only
        Duration of every run [s]: at least ``max(6, n_periods + 3)`` periods of the
        lowest mode (:func:`~iwan_element.models.ringdown`'s minimum).
    steps_per_period : int, keyword-only
        Steps per period of the highest mode in the multi-mode run, of its own mode in each
        single-mode run (>= 16).
    n_periods : float, keyword-only
        Periods per window of the decay curves (range [3, 1000]).
    effects : bool, keyword-only
        Also run the multi-mode ring-down once per named effect of the specimen with that
        effect taken out (module docstring); the specimen must carry at least one. Effects
        in the joint given by their modal fit are resolved first
        (:func:`~iwan_element.models.modal.resolve_interface_effects`), so that the others
        keep their joint values when one is taken out.
    max_steps : int, keyword-only
        Most time steps of all the runs together (default
        :data:`~iwan_element.models.simulation.solver.MAX_STEPS`, as ``ringdown``'s).

    Returns
    -------
    ModeCouplingResult
    """
    if not isinstance(amplitude, dict) or len(amplitude) < 2:
        raise ValueError(
            f"amplitude must be a dict of at least two modes {{mode: X [m]}}, got {amplitude!r}"
        )
    run: dict[str, Any] = {
        "duration": duration,
        "steps_per_period": steps_per_period,
        "n_periods": n_periods,
    }
    if not isinstance(effects, (bool, np.bool_)):
        raise ValueError(f"effects must be True or False, got {effects!r}")
    names = named_effects(specimen) if effects else ()
    if effects and not names:
        raise ValueError(
            "effects=True compares runs with and without each named effect, and the "
            "specimen carries none (no interface_effects, no effects): augment it first "
            "(VibrationDiagnosis.augment) or pass effects=False"
        )
    if names:  # the joint values fitted once, so that taking one out keeps the others'
        specimen = resolve_interface_effects(specimen)
    multi = preflight(specimen, amplitude, max_steps=max_steps, **run)
    steps = multi * (1 + len(names)) + sum(
        preflight(specimen, {r: X}, max_steps=max_steps, **run) for r, X in amplitude.items()
    )
    check_steps(
        steps,
        n_coordinates=linear_system(specimen).M.shape[0],
        max_steps=max_steps,
        what=f"mode_coupling's {len(amplitude) + 1 + len(names)} ring-downs",
        shorten="shorten duration or lower steps_per_period",
    )
    together = ringdown(specimen, amplitude=amplitude, max_steps=max_steps, **run)
    modes = together.modes
    alone = tuple(
        ringdown(specimen, mode=r, amplitude=amplitude[r], max_steps=max_steps, **run)
        for r in modes
    )
    figures = {r: compare_curves(together.mode_curve(r), a.curve) for r, a in zip(modes, alone)}
    without = {
        n: ringdown(without_effect(specimen, n), amplitude=amplitude, max_steps=max_steps, **run)
        for n in names
    }
    effect_figures = {
        (r, n): compare_curves(together.mode_curve(r), w.mode_curve(r))
        for n, w in without.items()
        for r in modes
    }
    warns = [
        f"mode {r}: its curves with and without the other modes do not overlap in amplitude"
        for r, f in figures.items()
        if not len(f["amplitude"])
    ]
    warns += [f"together: {x}" for x in together.warnings]
    warns += [f"mode {r} alone: {x}" for r, a in zip(modes, alone) for x in a.warnings]
    warns += [f"without {n}: {x}" for n, w in without.items() for x in w.warnings]
    warns += [
        f"mode {r}: its curves with and without {n} do not overlap in amplitude"
        for (r, n), f in effect_figures.items()
        if not len(f["amplitude"])
    ]
    return ModeCouplingResult(
        modes=modes,
        together=together,
        alone=alone,
        figures=figures,
        without=without,
        effect_figures=effect_figures,
        warnings=tuple(warns),
    )
