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

4. when the noise level the standard errors rest on was estimated from the fit's own
   residuals, it has at least :data:`MIN_NOISE_DOF` degrees of freedom (fewer, and the
   standard error is itself uncertain by ``sqrt(1 / (2 dof))``: at 1 degree of freedom
   ``+- 2 stderr`` covers 70 %, not 95 %; Student 1908).

A fit succeeds when its optimiser converged, every reported parameter is identified and no
misfit beyond the noise is left unexplained (docs/guards.md).
"""

from __future__ import annotations

import math

from scipy import stats

__all__ = ["verdict", "fit_success", "noise_dof_warning", "RELATIVE", "MIN_NOISE_DOF"]

#: Largest standard error, as a fraction of the reference magnitude, of an identified parameter.
RELATIVE = 0.5
#: Fewest degrees of freedom of a noise level estimated from the residuals (+-2 stderr then
#: covers at least about 90 %, Student's t).
MIN_NOISE_DOF = 5.0


def noise_dof_warning(dof: float, source: str = "") -> str | None:
    """Why no parameter is identified when the noise level rests on ``dof`` degrees of
    freedom (``source``: where it came from, for the text), or None when ``dof`` suffices.
    """
    if dof >= MIN_NOISE_DOF:
        return None
    cover = 100.0 * (1.0 - 2.0 * stats.t.sf(2.0, max(dof, 0.1)))
    return (
        f"the noise level rests on {dof:.2g} degrees of freedom{source}: the standard "
        f"errors are themselves uncertain by about {100 * math.sqrt(0.5 / max(dof, 0.1)):.0f}"
        f" % and +-2 stderr covers only about {cover:.0f} % (Student t), so no parameter "
        f"is identified; at least {MIN_NOISE_DOF:g} are needed"
    )


def verdict(
    name: str,
    value: float,
    stderr: float,
    *,
    at_bound: bool = False,
    degenerate: bool | None = None,
    nuisance: bool = False,
    relative: bool = True,
    reference: float | None = None,
    reference_text: str = "its value",
    why_degenerate: str = "",
    noise_dof: float | None = None,
) -> tuple[bool, str | None]:
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
    noise_dof : float, optional, keyword-only
        Degrees of freedom of the noise level ``stderr`` rests on when it was estimated from
        the fit's residuals (rule 4); None (default) when it was stated or is ample.

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
        return False, (
            f"{name} is not determined by the data (its Jacobian direction is "
            f"degenerate){why_degenerate}: NOT identified"
        )
    if noise_dof is not None and noise_dof < MIN_NOISE_DOF:
        return False, (
            f"{name}: its standard error rests on a noise level with "
            f"{float(noise_dof):.2g} degrees of freedom: NOT identified"
        )
    if relative and not nuisance and stderr > RELATIVE * ref:
        return False, (
            f"{name}: std. error {stderr:.3g} exceeds half of {reference_text} "
            f"({ref:.3g}): NOT identified"
        )
    return True, None


def fit_success(converged: bool, identified, required=None, *, explained: bool = True) -> bool:
    """The one ``success`` rule (docs/guards.md): the fit converged, every reported parameter
    is identified and no misfit beyond the noise is left unexplained.

    Parameters
    ----------
    converged : bool
        The optimiser's verdict (and whatever else the fit requires of the data, e.g. that
        they are more than noise).
    identified : mapping of str to bool
        The verdict of each parameter.
    required : iterable of str, optional
        The reported parameters that must be identified (default: all in ``identified``).
    explained : bool, keyword-only
        False when a misfit beyond the noise remains that the result does not explain.
    """
    if isinstance(required, str):
        raise ValueError(
            f"required must be an iterable of parameter names, not the str "
            f"{required!r} (write ({required!r},))"
        )
    keys = identified.keys() if required is None else required
    return bool(converged and explained and all(identified.get(k, False) for k in keys))
