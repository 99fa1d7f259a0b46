"""The verdict on a fitted Iwan joint: its parameter table, which parameters the data
identify (the package's one rule, :func:`iwan_element.fitting.verdict`; ``docs/fitting.md``
section 5), which ones ``success`` requires and the reasons it is False
(``docs/guards.md``). Shared by the loop and dissipation fits and the loop diagnosis.
"""

from __future__ import annotations

import math

from ...core.parameters import IwanParameters
from ...fitting import Parameter, ParameterTable, verdict

__all__ = [
    "PARAM_NAMES",
    "failure_list",
    "joint_table",
    "not_identified_reason",
    "required_parameters",
    "settle_verdict",
]

PARAM_NAMES = ("Fs", "KT", "chi", "beta")
_UNITS = {"Fs": "N", "KT": "N/m", "chi": "1", "beta": "1"}


#: Domain of each Iwan parameter (``IwanParameters``), the bounds in its table.
_DOMAIN = {
    "Fs": (0.0, math.inf),
    "KT": (0.0, math.inf),
    "chi": (-1.0, math.inf),
    "beta": (0.0, math.inf),
}


def joint_table(
    params: IwanParameters, stderr: dict, identified: dict, *, fixed=(), correlation=None
) -> ParameterTable:
    """The :class:`~iwan_element.fitting.ParameterTable` of a fitted joint: ``Fs`` [N],
    ``KT`` [N/m], ``chi``, ``beta`` with their standard errors, verdicts, the ones given
    (``fixed``) and their correlation (order :data:`PARAM_NAMES`).
    """
    rows = [
        Parameter(
            k,
            getattr(params, k),
            stderr.get(k, math.nan),
            *_DOMAIN[k],
            _UNITS[k],
            bool(identified.get(k, False)),
            fixed=k in fixed,
        )
        for k in PARAM_NAMES
    ]
    return ParameterTable(tuple(rows), correlation=correlation)


def settle_verdict(out: dict, fixed) -> tuple[dict, list[str]]:
    """The identification verdict of the Iwan parameters: the package's one rule,
    :func:`iwan_element.fitting.verdict` (docs/fitting.md section 5), with ``chi`` measured
    against ``chi + 1``. A parameter at a bound of its search range gets, for ``beta`` at 0,
    the range ``[0, 1.96 stderr]``; one with too large an error gets its 95 % interval as its
    range.
    """
    ident = dict(out["identified"])
    warns = []
    for k in PARAM_NAMES:
        if k in fixed or not ident.get(k, False):
            continue
        v = getattr(out["params"], k)
        se = out["stderr"].get(k, math.nan)
        at_bound = k in out.get("at_bound", ())
        ok, warn = verdict(
            k,
            v,
            se,
            at_bound=at_bound,
            reference=v + 1.0 if k == "chi" else None,
            reference_text="chi + 1" if k == "chi" else "its value",
        )
        if ok:
            continue
        assert warn is not None  # verdict gives its reason whenever it refuses
        ident[k] = False
        if at_bound and k == "beta" and v < 1e-6:
            hi = 1.96 * se if math.isfinite(se) else math.nan
            out["ranges"]["beta"] = (0.0, hi)
            warn += f"; the data are compatible with beta in [0, {hi:.3g}] (95 %)"
        elif not at_bound and math.isfinite(se):
            floor = {"chi": -1.0}.get(k, 0.0)
            out["ranges"].setdefault(k, (max(floor, v - 1.96 * se), v + 1.96 * se))
        warns.append(warn)
    return ident, warns


def required_parameters(ranges: dict, fixed=()) -> list:
    """The parameters ``success`` asks to be identified (docs/guards.md): every reported one
    but those given, and but ``beta`` when its 95 % range in ``ranges`` reaches down to its
    physical bound 0 with a finite upper limit (a joint without macroslip softening beyond
    that limit: a finding, stated in the report) or when it follows from a given ``Fs``
    (conditional on it, as the warning says).
    """
    lo, hi = ranges.get("beta", (math.nan, math.nan))
    exempt = (lo <= 0.0 and math.isfinite(hi)) or "Fs" in fixed
    return [k for k in PARAM_NAMES if k not in fixed and not (k == "beta" and exempt)]


def not_identified_reason(missing, *, microslip: bool) -> str:
    """The failure reason for the reported parameters ``missing`` the data do not identify:
    in microslip, the loops never slipped far enough to fix them.
    """
    names = ", ".join(missing[:-1]) + " and " + missing[-1] if len(missing) > 1 else missing[0]
    verb = "is" if len(missing) == 1 else "are"
    why = (
        "the loops stay in microslip (test to larger amplitudes)"
        if microslip
        else "their standard errors are too large or they sit at a bound of the search range "
        "(see the warnings)"
    )
    return f"{names} {verb} not identified by these data: {why}"


def failure_list(
    *,
    converged: bool,
    message: str,
    explains: bool,
    noise_text: str,
    ident: dict,
    required,
    microslip: bool,
    fixed=(),
) -> tuple:
    """The reasons ``success`` is False for a fitted joint (empty when it is True). A
    reason about parameters the data do not identify names every one the parameter table
    marks NOT identified (``beta``, not required when its range reaches 0, too), so that
    the verdict and the table agree; ``fixed`` (given) parameters are not fitted.
    """
    out = []
    if not converged:
        out.append(f"the optimiser did not converge ({message})")
    if not explains:
        out.append(noise_text)
    if microslip:  # beta's range then reaches 0 only because Fs is free too
        required = [k for k in PARAM_NAMES if k in required or k == "beta"]
    missing = [k for k in required if not ident.get(k, False)]
    if missing and explains:
        marked = set(missing) | {
            k for k in PARAM_NAMES if k not in fixed and not ident.get(k, True)
        }
        out.append(
            not_identified_reason([k for k in PARAM_NAMES if k in marked], microslip=microslip)
        )
    return tuple(out)
