"""The one identification verdict and the one ``success`` rule (docs/fitting.md, section 5).

A fitted parameter is identified when the data determine it:

1. it is not at a bound of its search range (an optimum on a bound is not a stationary
   point, so the Jacobian's covariance does not describe it);
2. its standard error is finite (it has no component along a degenerate direction of the
   Jacobian);
3. unless it is a nuisance (a sensor offset, a starting state: fitted so the others are
   right, of no interest in itself), its standard error is at most half its reference
   magnitude: ``|value|`` by default, ``|chi + 1|`` for the Iwan exponent ``chi`` (the
   exponent of the slider density; ``chi = 0`` is a valid value), so a 95 % interval
   ``value +- 1.96 stderr`` excludes zero. A quantity whose value zero is itself a
   finding (a campaign law's slope) is asked only 1 and 2 (``relative=False``).

A fit succeeds when its optimiser converged and every required parameter is identified.
"""
from __future__ import annotations

import math

__all__ = ["verdict", "fit_success", "RELATIVE"]

#: Largest standard error, as a fraction of the reference magnitude, of an identified parameter.
RELATIVE = 0.5


def verdict(name: str, value: float, stderr: float, *, at_bound: bool = False,
            degenerate: bool | None = None, nuisance: bool = False, relative: bool = True,
            reference: float | None = None, reference_text: str = "its value",
            why_degenerate: str = "") -> tuple[bool, str | None]:
    """Whether the fitted parameter ``name`` is identified, and the warning when not.

    Parameters
    ----------
    name : str
        Parameter name, for the warning.
    value, stderr : float
        Fitted value and standard error (NaN: not determined), in the parameter's unit.
    at_bound : bool, keyword-only
        The value sits on a bound of its search range.
    degenerate : bool, optional, keyword-only
        The parameter lies along a degenerate direction of the Jacobian (default: a
        non-finite ``stderr``). Changes only the warning's wording.
    nuisance : bool, keyword-only
        Nuisance parameters skip the relative-precision test.
    relative : bool, keyword-only
        Apply the relative-precision test (default). False for a quantity whose value zero
        is itself a finding (a law's slope: "no dependence"), which asks only rules 1-2.
    reference : float, optional, keyword-only
        Magnitude the standard error is compared with (default ``|value|``).
    reference_text : str, keyword-only
        What ``reference`` is, for the warning (default ``"its value"``).
    why_degenerate : str, keyword-only
        Explanation appended to the warning of a degenerate parameter.

    Returns
    -------
    identified : bool
    warning : str or None
        Why the parameter is not identified; None when it is.
    """
    value, stderr = float(value), float(stderr)
    if not (math.isnan(stderr) or stderr >= 0.0):
        raise ValueError(f"stderr of {name} must be >= 0 or NaN (not determined), got {stderr}")
    if not math.isfinite(value):
        return False, f"{name} has no finite value ({value}): NOT identified"
    ref = abs(value) if reference is None else abs(reference)
    if at_bound:
        return False, f"{name} = {value:.4g} is at a bound of its search range: NOT identified"
    if not math.isfinite(stderr):
        if degenerate is False:
            return False, f"{name} has no standard error: NOT identified"
        return False, (f"{name} is not determined by the data (its Jacobian direction is "
                       f"degenerate){why_degenerate}: NOT identified")
    if relative and not nuisance and stderr > RELATIVE * ref:
        return False, (f"{name}: std. error {stderr:.3g} exceeds half of {reference_text} "
                       f"({ref:.3g}): NOT identified")
    return True, None


def fit_success(converged: bool, identified, required=None) -> bool:
    """The one ``success`` rule: the optimiser converged and every required parameter is
    identified.

    Parameters
    ----------
    converged : bool
        The optimiser's verdict (and whatever else the fit requires of the data, e.g. that
        they are more than noise).
    identified : mapping of str to bool
        The verdict of each parameter.
    required : iterable of str, optional
        The parameters that must be identified (default: all in ``identified``).
    """
    if isinstance(required, str):
        raise ValueError(f"required must be an iterable of parameter names, not the str "
                         f"{required!r} (write ({required!r},))")
    keys = identified.keys() if required is None else required
    return bool(converged and all(identified.get(k, False) for k in keys))
