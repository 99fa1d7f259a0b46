"""The result of the discrepancy workflow across modes (:class:`ModesDiagnosis`, returned by
:func:`~iwan_element.models.calibration.diagnose_modes`) and its candidates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from iwan_element.base.result_shape import ResultShape, panels, table_lines, wrap
from iwan_element.base.serialize import json_safe

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["Candidate", "ModesDiagnosis"]


@dataclass(frozen=True)
class Candidate:
    """One explanation tried in the joint: the effects one mode's diagnosis named, at one
    placement, read on every mode.

    Attributes
    ----------
    effects : tuple of str
        The effects (empty: the plain joint).
    mode : int
        The mode they were found on (0: the plain joint).
    where : str
        The placement asked for; ``placed`` where the mapping put each effect (a bolt that
        the mode barely moves sends it to every contact point).
    scores : dict or None
        ``{mode: {"chi2", "rms", "frequency_error", "damping_error"}}``: chi-square, RMS of
        the noise-normalised log residuals, largest relative errors [-]; ``None`` when it
        could not be read (``reason``).
    n_values : int
        Modal values fitted on ``mode`` (the information criterion's ``k``).
    specimen : Specimen or None
        The specimen carrying the effects in its joint.
    read : dict
        ``{mode: (frequency [Hz], damping ratio [-])}``: its QSMA at the measured amplitudes.
    predicted : dict
        ``{(mode, sensor): AmplitudeCurve}``: its ring-down read like the record (a
        candidate checked by :func:`~iwan_element.models.calibration.diagnose_hammer_test`;
        empty otherwise).
    values : dict
        ``{effect: {name: value}}``: the joint values (SI units).
    capped : tuple of str
        Its effects whose patch holds as much stiffness as its points have
        (:func:`~iwan_element.models.modal.stiffness_cap`): the mode asked for more.
    ic, probability : float
        Information criterion and probability among the candidates and the plain joint
        (set by :meth:`ModesDiagnosis.build`).
    spoils : tuple of int
        Modes it makes worse by more than the workflow's tolerance.
    """

    effects: tuple
    mode: int
    where: str
    placed: tuple = ()
    scores: dict | None = None
    n_values: int = 0
    specimen: Any = field(default=None, repr=False)
    read: dict = field(default_factory=dict, repr=False)
    predicted: dict = field(default_factory=dict, repr=False)
    values: dict = field(default_factory=dict)
    reason: str = ""
    capped: tuple = ()
    ic: float = math.nan
    probability: float = 0.0
    spoils: tuple = ()

    @property
    def label(self) -> str:
        """``"macroslip_onset (mode 2) at bolt2"``, or ``"plain joint"``."""
        if not self.effects:
            return "plain joint"
        at = ",".join(dict.fromkeys(self.placed)) or self.where
        return f"{'+'.join(self.effects)} (mode {self.mode}) at {at}"

    def line(self) -> str:
        """One line of the candidate's figures."""
        if self.scores is None:
            return f"{self.label}: {self.reason}"
        per = "; ".join(
            f"mode {m} rms {s['rms']:.3g}, max df/f {100 * s['frequency_error']:.3g} %, "
            f"dz/z {100 * s['damping_error']:.3g} %"
            for m, s in self.scores.items()
        )
        return f"{self.label}: {per}"

    def row(self, ic_min: float) -> dict:
        """A row of the candidates' table (JSON-safe values)."""
        r: dict[str, Any] = {
            "candidate": self.label,
            "found_on": self.mode or None,
            "where": ",".join(dict.fromkeys(self.placed)) or self.where or None,
            "dIC": self.ic - ic_min if math.isfinite(self.ic) else None,
            "probability": self.probability,
        }
        for m, s in (self.scores or {}).items():
            r[f"mode {m} rms [-]"] = s["rms"]
            r[f"mode {m} max |df/f| [-]"] = s["frequency_error"]
            r[f"mode {m} max |dzeta/zeta| [-]"] = s["damping_error"]
        r["note"] = self.reason or _spoil_note(self)
        return r


def _scored(plain, cands, n_total, spoil) -> tuple:
    """Every candidate with its information criterion, probability and spoiled modes."""
    ln_n = math.log(n_total)

    def ic(c):
        if c.scores is None:
            return math.inf
        return sum(s["chi2"] for s in c.scores.values()) + c.n_values * ln_n

    allc = [replace(plain, ic=ic(plain))] + [replace(c, ic=ic(c)) for c in cands]
    finite = [c.ic for c in allc if math.isfinite(c.ic)]
    lo = min(finite)
    w = np.array([math.exp(-0.5 * (c.ic - lo)) if math.isfinite(c.ic) else 0.0 for c in allc])
    w /= w.sum()
    out = []
    for c, p in zip(allc, w):
        bad = ()
        if c.scores is not None and c.effects:
            bad = tuple(
                m
                for m, s in c.scores.items()
                if m != c.mode
                and s["rms"] > plain.scores[m]["rms"] + spoil * max(1.0, plain.scores[m]["rms"])
            )
        out.append(replace(c, probability=float(p), spoils=bad))
    return out[0], tuple(out[1:])


@dataclass(frozen=True)
class ModesDiagnosis(ResultShape):
    """Result of :func:`~iwan_element.models.calibration.diagnose_modes`.

    Attributes
    ----------
    plain : Candidate
        The specimen as given, read on every mode.
    candidates : tuple of Candidate
        Each named effect at each placement, read on every mode.
    named : Candidate or None
        The candidate of least information criterion that lowers the plain joint's and
        spoils no other mode (read by the ring-down when ``checked``); ``None`` when none
        does (or no mode had a gap).
    diagnoses : dict
        ``{mode: VibrationDiagnosis}`` of each mode against the plain joint.
    curves : dict
        ``{mode: (amplitude [m], frequency [Hz], damping ratio [-])}`` measured.
    checked : tuple of Candidate
        The plain joint and the best candidates by QSMA read again by the multi-mode
        ring-down of the test (:func:`~iwan_element.models.calibration.
        diagnose_hammer_test`), which then names; empty when not run.
    success : bool
        A candidate was named, or no mode's diagnosis named an effect.
    warnings : tuple of str
    """

    plot_panels = 2
    COLUMNS = {
        "dIC": ("dIC", "-"),
        "probability": ("probability", "-"),
    }

    plain: Candidate
    candidates: tuple
    named: Candidate | None
    diagnoses: dict
    curves: dict
    success: bool
    checked: tuple = ()

    @classmethod
    def build(
        cls, plain, cands, diagnoses, curves, *, spoil: float, checked=(), checked_points=0
    ) -> ModesDiagnosis:
        """Score the candidates (:mod:`.mode_diagnosis` docstring) and name one: among
        ``checked`` (the plain joint first, then candidates read by the multi-mode
        ring-down on ``checked_points`` amplitudes in all) when given, else among all.
        """
        n_total = sum(2 * c[0].size for c in curves.values())
        plain, cands = _scored(plain, cands, n_total, spoil)
        base, final = plain, cands
        if checked:
            base, final = _scored(checked[0], tuple(checked[1:]), checked_points, spoil)
        ok = [c for c in final if c.scores is not None and not c.spoils and c.ic < base.ic]
        named = min(ok, key=lambda c: c.ic) if ok else None
        gaps = [m for m, d in diagnoses.items() if d.effects]
        warns = _warnings(gaps, base, named)
        if checked:
            best_q = min(
                (c for c in cands if c.scores is not None and not c.spoils),
                key=lambda c: c.ic,
                default=None,
            )
            warns.append(
                f"named by the multi-mode ring-down among the {len(checked) - 1} best by QSMA"
                + (
                    f" (QSMA alone: {best_q.label})"
                    if best_q is not None and (named is None or best_q.label != named.label)
                    else ""
                )
            )
        return cls(
            plain=plain,
            candidates=cands,
            named=named,
            diagnoses=dict(diagnoses),
            curves=dict(curves),
            checked=(base,) + tuple(final) if checked else (),
            success=named is not None or not gaps,
            warnings=tuple(warns),
        )

    @property
    def specimen(self) -> Any:
        """The specimen with the named effect in its joint (the given one when none)."""
        return (self.named or self.plain).specimen

    def gaps(self) -> dict:
        """``{mode: {"before": scores, "after": scores}}`` of the plain joint and the named
        candidate (``after`` is ``before`` when none was named), by the ring-down when
        ``checked``.
        """
        base = self.checked[0] if self.checked else self.plain
        before = base.scores or {}
        after = (self.named or base).scores or before
        return {m: {"before": s, "after": after[m]} for m, s in before.items()}

    def report(self) -> str:
        """The verdict, each mode's diagnosis, the candidates, the gaps before and after."""
        lines = [self.verdict(), "Discrepancy workflow across modes (effects in the joint)"]
        for m, d in self.diagnoses.items():
            named = ", ".join(d.effects) or "nothing"
            lines += wrap(f"  mode {m}: diagnosis names {named} ({d.verdict()})", indent="    ")
        lines.append("  read by QSMA, each mode on its own:")
        lines += _table((self.plain,) + self.candidates)
        if self.checked:
            lines.append("  read by the multi-mode ring-down of the test (names):")
            lines += _table(self.checked)
        lines.append(
            "  gap per mode, plain -> named (max |df/f| [%], max |dz/z| [%], rms [noise "
            "units], after each curve's constant offsets [%] in f and zeta, given last):"
        )
        for m, g in self.gaps().items():
            b, a = g["before"], g["after"]
            lines.append(f"    mode {m}: {_gap(b)} -> {_gap(a)}")
        if self.named is not None:
            lines.append(f"  named: {self.named.label}; joint values {self.named.values}")
        lines += [f"  warning: {w}" for w in self.warnings]
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-safe: the candidates' rows, the named one, the gaps, verdict."""
        ic0 = min(c.ic for c in (self.plain,) + self.candidates)
        ic1 = min((c.ic for c in self.checked), default=0.0)
        return json_safe(
            {
                "rows": [c.row(ic0) for c in (self.plain,) + self.candidates],
                "checked_rows": [c.row(ic1) for c in self.checked],
                "named": None if self.named is None else self.named.label,
                "named_values": None if self.named is None else self.named.values,
                "gaps": {str(m): g for m, g in self.gaps().items()},
                "success": self.success,
                "warnings": list(self.warnings),
            }
        )

    def plot(self, ax=None) -> list[Artist]:
        """Each mode's measured curve (points), the plain joint (dashed) and the named
        candidate (solid): damping ratio [%] and frequency shift from the curve's
        lowest-amplitude frequency [%] against amplitude, on ``ax = (ax_z, ax_f)``.
        """
        ax_z, ax_f = panels(ax, 2, figsize=(6, 6))
        arts: list = []
        for i, (m, (X, f, z)) in enumerate(self.curves.items()):
            col = f"C{i}"
            f0 = float(f[np.argmin(X)])
            arts += ax_z.plot(X, 100 * z, "o", ms=3, color=col, label=f"mode {m} measured")
            arts += ax_f.plot(X, 100 * (f / f0 - 1), "o", ms=3, color=col)
            for c, ls in ((self.plain, "--"), (self.named, "-")):
                if c is None or m not in c.read:
                    continue
                fq, zq = c.read[m]
                lab = f"mode {m} {c.label}"
                arts += ax_z.plot(X, 100 * zq, ls, color=col, label=lab)
                arts += ax_f.plot(X, 100 * (fq / f0 - 1), ls, color=col)
        for a in (ax_z, ax_f):
            a.set_xscale("log")
            a.set_xlabel("amplitude [m]")
        ax_z.set_ylabel("damping ratio [%]")
        ax_f.set_ylabel("frequency shift [%]")
        ax_z.legend(fontsize=7)
        return arts


def _gap(s: dict) -> str:
    """One mode's gap: largest errors [%], RMS [noise units], offsets [%]."""
    return (
        f"{100 * s['frequency_error']:.3g}, {100 * s['damping_error']:.3g}, {s['rms']:.3g} "
        f"(offsets {100 * s['frequency_offset']:+.3g}, {100 * s['damping_offset']:+.3g})"
    )


def _table(cands) -> list:
    """The candidates' lines: label, IC above the least, probability, note."""
    ic0 = min(c.ic for c in cands)
    rows = [
        (c.label[:44], c.ic - ic0, 100 * c.probability, c.reason or _spoil_note(c)) for c in cands
    ]
    return table_lines(
        (("candidate", "<44s"), ("dIC", "12.4g"), ("prob. [%]", "10.3g"), ("note", "s")),
        rows,
        indent=4,
    )


def _warnings(gaps, base, named) -> list:
    """What the named candidate (or the plain joint) leaves, and what it rests on."""
    warns = []
    if gaps and named is None:
        warns.append(
            "no effect named on modes "
            + ", ".join(map(str, gaps))
            + " closes its gap in the joint without spoiling another mode (see the candidates)"
        )
    best = named or base
    for m, s in (best.scores or {}).items():
        if s["rms"] > 3.0:
            warns.append(
                f"mode {m}: misfit of {s['rms']:.3g} noise units left "
                f"({'after ' + best.label if named else 'plain joint'}; max df/f "
                f"{100 * s['frequency_error']:.3g} %, dz/z {100 * s['damping_error']:.3g} %)"
            )
    if named is not None and named.capped:
        warns.append(
            f"{named.label}: {', '.join(named.capped)} holds all the stiffness of its "
            "points (stiffness_cap): the mode asks for a larger patch than that placement "
            "has, so the named effect closes only part of the gap"
        )
    if named is not None:
        warns.append(
            f"the named effect was fitted on mode {named.mode}'s curve: its gap there is a "
            "fit, not a prediction; the other modes and held-out tests are its check"
        )
    return warns


def _spoil_note(c) -> str:
    return "spoils mode " + ", ".join(map(str, c.spoils)) if c.spoils else ""
