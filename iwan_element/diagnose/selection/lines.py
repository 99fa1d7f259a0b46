"""The report pieces both diagnoses share (:class:`~iwan_element.diagnose.loops.result.Diagnosis`
and :class:`~iwan_element.diagnose.vibration.result.VibrationDiagnosis`): an effect
parameter's unit label and the closing verdict lines.
"""

from __future__ import annotations

from ...base.result_shape import unit_label, wrap
from ...effects import EFFECTS

__all__ = ["effect_unit", "verdict_lines"]


def effect_unit(name: str, key: str, modal: bool = False) -> str:
    """``"[unit]"`` of parameter ``key`` of effect ``name`` (its modal form if ``modal``)."""
    specs = EFFECTS[name].modal_specs if modal else EFFECTS[name].specs
    return "[" + unit_label(next((s.unit for s in specs if s.name == key), "")) + "]"


def verdict_lines(word: str, result) -> list:
    """The closing lines of a diagnosis report: misfit before and after, noise, warnings."""
    lines = [
        f"  {word} before {100 * result.error_before:.3g} % -> after "
        f"{100 * result.error_after:.3g} % (noise {100 * result.noise_level:.3g} %)"
    ]
    if result.warnings:
        lines.append("  warnings:")
        for w in result.warnings:
            lines += wrap(f"  - {w}", indent="    ")
    return lines
