"""What a diagnosis result says of its explanations' probabilities (:mod:`.probabilities`):
an effect's marginal probability, the confidence sentence, and :class:`Probable`, the
mixin every diagnosis result shares (its report lines, tables and JSON list).
"""

from __future__ import annotations

import math

__all__ = ["effect_probability", "confidence_text", "CONFIDENT", "Probable"]

#: Probability above which a report calls an explanation certain enough to act on.
CONFIDENT = 0.9


def effect_probability(probabilities: dict, name: str) -> float:
    """Marginal probability that effect ``name`` is present: the sum over the explanations
    (keys of ``probabilities``) that contain it.
    """
    if not isinstance(name, str):
        raise ValueError(f"name must be an effect name (str), got {name!r}")
    return float(sum(p for k, p in probabilities.items() if name in k))


def confidence_text(probabilities: dict) -> str:
    """One line: the most probable explanation and, when it is not above
    :data:`CONFIDENT`, that the diagnosis is not sure and what competes.
    """
    items = sorted(probabilities.items(), key=lambda kv: -kv[1])
    (top, p), rest = items[0], items[1:]
    name = " + ".join(top) or "the plain joint (no effect)"
    if p > CONFIDENT:
        return f"most probable: {name} (probability {p:.3g})"
    others = ", ".join(
        f"{' + '.join(k) or 'plain joint'} {q:.2g}" for k, q in rest[:3] if q >= 0.01
    )
    return (
        f"NOT SURE: no explanation is above {CONFIDENT:g}; most probable {name} "
        f"(probability {p:.2g})" + (f", then {others}" if others else "")
    )


class Probable:
    """What every diagnosis result offers about its explanations' probabilities (a mixin of
    :class:`~..loops.result.Diagnosis`, :class:`~..vibration.result.VibrationDiagnosis` and
    :class:`~.campaign.CampaignFit`; reads the result's ``explanations``).
    """

    # declared for the type checker only (no default: each result's dataclass field holds it)
    explanations: tuple  # of Explanation, most probable first

    @property
    def probabilities(self) -> dict:
        """``{explanation: posterior probability}``: each explanation the diagnosis fitted,
        a tuple of effect names (sorted; ``()`` the plain joint), most probable first;
        the values sum to 1.
        """
        return {e.effects: e.probability for e in self.explanations}

    def effect_probability(self, name: str) -> float:
        """Posterior probability that effect ``name`` is present (the sum over the
        explanations containing it; 0 for an effect no explanation contains).

        Raises
        ------
        ValueError
            ``name`` is not an effect of :data:`~iwan_element.EFFECTS`.
        """
        from ...effects import EFFECTS

        if name not in EFFECTS:
            raise ValueError(f"name must be one of {sorted(EFFECTS)}, got {name!r}")
        return effect_probability(self.probabilities, name)

    def probability_lines(self, *, rows: int = 6) -> list:
        """Report lines: the confidence sentence, the most probable explanations, the
        effects' marginal probabilities.
        """
        if not self.explanations:
            return []
        probs = self.probabilities
        lines = ["  " + confidence_text(probs)]
        shown = list(self.explanations)[:rows]
        lines.append(
            "    explanation                                probability  ln evidence  ln Occam"
        )
        for e in shown:
            name = " + ".join(e.effects) or "plain joint"
            occ = f"{e.log_occam:9.4g}" if math.isfinite(e.log_occam) else "      n/a"
            lines.append(f"    {name:<42} {e.probability:11.3g} {e.log_evidence:12.6g} {occ}")
        if len(self.explanations) > rows:
            lines.append(
                f"    ({len(self.explanations) - rows} more, together "
                f"{sum(e.probability for e in self.explanations[rows:]):.2g})"
            )
        effs = sorted({n for e in self.explanations for n in e.effects})
        if effs:
            lines.append(
                "    effect present: "
                + ", ".join(f"{n} {effect_probability(probs, n):.3g}" for n in effs)
            )
        return lines

    def probability_tables(self) -> list:
        """The tables ``"probabilities"`` (one row per explanation) and ``"effect
        probabilities"`` (one row per effect) for ``_tables``.
        """
        if not self.explanations:
            return []
        rows = [
            (
                " + ".join(e.effects) or "plain joint",
                e.probability,
                e.log_evidence,
                e.log_likelihood,
                e.log_occam,
                e.log_prior,
                e.n_params,
            )
            for e in self.explanations
        ]
        effs = sorted({n for e in self.explanations for n in e.effects})
        probs = self.probabilities
        return [
            (
                "probabilities",
                (
                    "explanation",
                    "probability [-]",
                    "ln evidence [-]",
                    "ln likelihood [-]",
                    "ln Occam [-]",
                    "ln prior [-]",
                    "parameters",
                ),
                rows,
            ),
            (
                "effect probabilities",
                ("effect", "probability [-]"),
                [(n, effect_probability(probs, n)) for n in effs],
            ),
        ]

    def probabilities_dict(self) -> list:
        """JSON-safe list of the explanations (``to_dict``'s ``"probabilities"``)."""
        return [e.to_dict() for e in self.explanations]
