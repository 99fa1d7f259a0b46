"""One stage's failure stops the next: the rule of every route that chains stages.

A route that feeds one stage's result into the next (a static release into a ring-down, a
calibration into a prediction, a fit's covariance into an ensemble) stops at the first stage
whose result is not usable, with that stage's own reasons, before any later stage (a time
run of minutes) starts. :class:`StageFailed` is the error; :func:`require_usable` applies the
rule to a result with the package's shape (``success``, ``failure_reasons()``), and
:func:`stop_at` to reasons a stage stated itself. A route that lets an expert go on past an
unusable stage (for instance to look at what its parameters predict) names its keyword in the
error (``override``), and says so in the result's warnings when it was used.
"""

from __future__ import annotations

from typing import TypeVar

__all__ = ["StageFailed", "require_usable", "stop_at"]

_R = TypeVar("_R")  # the result require_usable hands back unchanged


class StageFailed(ValueError):
    """A stage of a chained route gave no usable result; the route stopped there.

    Attributes
    ----------
    stage : str
        The stage that failed, in a tester's words (``"release"``, ``"calibration"``).
    reasons : tuple of str
        That stage's own reasons.
    override : str or None
        The keyword that lets the route go on anyway, when it has one.
    """

    def __init__(self, stage: str, reasons, *, override: str | None = None):
        self.stage = str(stage)
        self.reasons = tuple(str(r) for r in reasons) or ("it did not succeed",)
        self.override = override
        text = f"the {self.stage} is not usable, so nothing after it was run: " + "; ".join(
            self.reasons
        )
        if override:
            text += f" (to go on anyway, pass {override})"
        super().__init__(text)


def stop_at(stage: str, reasons, *, override: str | None = None) -> None:
    """Raise :class:`StageFailed` for ``stage`` when ``reasons`` (its stated failures) is not
    empty; return None otherwise.
    """
    reasons = tuple(reasons)
    if reasons:
        raise StageFailed(stage, reasons, override=override)


def require_usable(
    stage: str, result: _R, *, allow: bool = False, override: str | None = None
) -> _R:
    """``result`` when it is usable (``result.success``), or when ``allow`` (the route's
    override keyword, ``override``, was given); else :class:`StageFailed` with the result's
    ``failure_reasons()`` (its warnings when it has none).
    """
    if allow or bool(getattr(result, "success", True)):
        return result
    why = getattr(result, "failure_reasons", None)
    reasons = tuple(why()) if callable(why) else tuple(getattr(result, "warnings", ()))
    raise StageFailed(stage, reasons, override=override)
