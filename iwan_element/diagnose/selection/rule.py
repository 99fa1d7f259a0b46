"""One stepwise selection rule for both diagnoses (loops and vibration curves).

The rule, stated once:

* Every model is scored on its **noise-normalised** residual ``chi2 = SSR / sigma^2`` with
  ``n_eff = n / tau`` effective independent samples (``tau``: the noise's integrated
  correlation time in samples; 1 for white noise or independent points).
* **Misfit test.** What is left is called noise when ``chi2 / tau`` is not significantly
  above its expectation ``n_eff - q`` (``q`` fitted parameters): the chi-square upper tail
  ``P(chi2_{n_eff - q} >= chi2 / tau) >= alpha``. A step starts only if the current model
  fails this test, so clean data and pure noise name nothing.
* **Criterion.** A Bayesian information criterion on the effective samples,
  ``IC = chi2 / tau + q ln(n_eff)``; a candidate effect (``q_e`` more parameters) is
  eligible when it lowers the IC (``delta chi2 / tau > q_e ln n_eff``, a per-parameter
  evidence threshold that grows with the data) and
* **"explains little" guard**: it removes at least ``explain_fraction`` (default 25 %) of the
  *excess* misfit ``chi2 / tau - (n_eff - q)`` of the current model (a real but tiny gain on a
  large unexplained misfit is not a diagnosis); a caller may add a condition (``guard``).
  The vibration diagnosis also drops a named set that leaves its unweighted mismatch higher
  than before.
* Among eligible candidates the lowest IC is named; others within ``ambiguity`` IC units are
  reported as nearly as good. The loop then continues on top of the named effect, until the
  rest is noise, nothing is eligible, or ``max_effects`` effects are named.
* **Pair step.** Two effects can each hide the other: a joint with backlash *and*
  direction-dependent slip leaves a misfit where either alone explains too little (a forward
  greedy step cannot see it). When no single candidate is eligible, the misfit is not noise
  and two more effects may be named, the best single candidate (lowest IC among those that
  lower it) is fitted together with **each** other candidate that lowers the IC on its own
  (starting from the best single's fit), and the runner-up with the best (starting from the
  runner-up's fit). The partner a leading effect hides need not be the runner-up alone: on a
  damper with backlash and direction-dependent slip, a dashpot alone explains more than the
  asymmetry, whose misfit the open gap displaces. A pair is named if it passes the same
  tests with both effects' parameters counted (lowers IC, removes ``explain_fraction`` of the
  excess) **and** each member earns its place on top of the other (the pair's IC is below
  each single's IC: adding the partner to that single lowers ``chi2 / tau`` by more than its
  own ``q ln n_eff``); the lowest IC among such pairs wins. Clean data and pure noise never
  reach a step, so this cannot name anything there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.stats import chi2 as _chi2

__all__ = ["SelectionResult", "criterion_text", "misfit_p", "stepwise_select"]

EXPLAIN_FRACTION = 0.25


def criterion_text(explain_fraction: float = EXPLAIN_FRACTION) -> str:
    """The rule in one line, for reports."""
    return (
        "BIC on the noise-normalised residual, IC = chi2/tau + q ln(n_eff); an effect is "
        f"named when it lowers IC and removes >= {100 * explain_fraction:.0f} % of the "
        "excess misfit; stop when the rest is noise (chi-square test)"
    )


def misfit_p(chi2: float, tau: float, n_eff: float, q: int) -> float:
    """Upper-tail probability that noise alone leaves ``chi2`` (``tau``, ``n_eff`` as above)."""
    dof = max(n_eff - q, 1.0)
    return float(_chi2.sf(chi2 / tau, dof))


@dataclass
class SelectionResult:
    """Outcome of :func:`stepwise_select`."""

    named: list
    ambiguous: tuple
    steps: list
    final: dict  # the last accepted model: {"names", "chi2", "q", "state"}
    p_before: float
    p_after: float


def _verdicts(rows, best, ambiguity):
    best_ic = min(r["ic"] for r in rows)
    for r in rows:
        r["dIC"] = r["ic"] - best_ic
        if r is best:
            r["verdict"] = "NAMED"
        elif not r["lowers_ic"]:
            r["verdict"] = "not supported (IC)"
        elif not r["enough"]:
            r["verdict"] = "explains little"
        elif not r["guard_ok"]:
            r["verdict"] = "raises the mismatch"
        elif best is not None and r["ic"] - best["ic"] < ambiguity:
            r["verdict"] = "nearly as good"
        else:
            r["verdict"] = "worse"


def stepwise_select(
    fit_candidate,
    candidates,
    base: dict,
    *,
    tau: float,
    n_eff: float,
    alpha: float = 1e-3,
    max_effects: int = 2,
    ambiguity: float = 10.0,
    explain_fraction: float = EXPLAIN_FRACTION,
    allowed=None,
    guard=None,
    pairs: bool = True,
    first_step: bool = False,
) -> SelectionResult:
    """Run the selection rule (module docstring).

    Parameters
    ----------
    fit_candidate : callable
        ``fit_candidate(current, name) -> dict`` with at least ``chi2`` (noise-normalised
        SSR), ``q`` (parameters added), ``names`` (the new stack) and ``state`` (anything the
        caller needs to continue from it); extra keys are kept in the step table.
    candidates : sequence of str
    base : dict
        The starting model: ``names`` (tuple), ``chi2``, ``q``, ``state``.
    tau, n_eff : float
        Correlation time [samples] and effective number of independent samples.
    allowed : callable, optional
        ``allowed(names, name) -> bool``: whether ``name`` may be stacked on ``names``.
    guard : callable, optional
        ``guard(current, row) -> bool``: an extra condition for naming (True: passes).
    pairs : bool
        Whether the pair step (module docstring) is tried when no single effect is eligible.
    first_step : bool
        Fit every candidate on the base model even when the base's misfit is noise (the
        step's rows then say so and nothing is named): the model probabilities
        (:mod:`.probabilities`) need the single effects' fits on every record, the rule's
        answer is the same.
    """
    cur = dict(base)
    p0 = misfit_p(cur["chi2"], tau, n_eff, cur["q"])
    named: list[str] = []
    steps: list[dict] = []
    ambiguous: tuple = ()
    pen = math.log(max(n_eff, 2.0))
    while len(named) < max_effects:
        noise = misfit_p(cur["chi2"], tau, n_eff, cur["q"]) >= alpha
        if noise and not (first_step and not steps):
            break
        rest = [
            c
            for c in candidates
            if c not in cur["names"] and (allowed is None or allowed(cur["names"], c))
        ]
        if not rest:
            break
        excess = max(cur["chi2"] / tau - (n_eff - cur["q"]), 0.0)
        ic_cur = cur["chi2"] / tau + cur["q"] * pen
        score = _scorer(cur, excess, ic_cur, tau, pen, explain_fraction, guard)
        rows = []
        for name in rest:
            r = dict(fit_candidate(cur, name))
            r["name"] = name
            rows.append(score(r, r["q"]))
        ok = [r for r in rows if r["lowers_ic"] and r["enough"] and r["guard_ok"]]
        best = min(ok, key=lambda r: r["ic"]) if ok and not noise else None
        _verdicts(rows, best, ambiguity)
        if noise:
            for r in rows:
                r["verdict"] = "not needed (rest is noise)"
        steps.append({"on": list(cur["names"]), "rows": rows})
        if noise:
            break
        if best is None and pairs and len(named) + 2 <= max_effects:
            pair, tried = _pair_step(fit_candidate, cur, rows, score, allowed)
            if tried:
                steps.append({"on": list(cur["names"]), "rows": tried})
            if pair is not None:
                named.extend(pair[0])
                cur = pair[2]
                continue
        if best is None:
            break
        if not named:
            ambiguous = tuple(r["name"] for r in rows if r["verdict"] == "nearly as good")
        named.append(best["name"])
        cur = {
            "names": best["names"],
            "chi2": best["chi2"],
            "q": cur["q"] + best["q"],
            "state": best["state"],
            "row": best,
        }
    return SelectionResult(
        named=named,
        ambiguous=ambiguous,
        steps=steps,
        final=cur,
        p_before=p0,
        p_after=misfit_p(cur["chi2"], tau, n_eff, cur["q"]),
    )


def _scorer(cur, excess, ic_cur, tau, pen, explain_fraction, guard):
    """The rule's tests of a fitted model ``r`` on top of ``cur`` that adds ``q`` parameters:
    its IC, whether it lowers the current IC, the fraction of the excess misfit it explains,
    whether that is enough, and the caller's guard. Returns ``score(r, q) -> r``.
    """

    def score(r, q):
        gain = max(cur["chi2"] - r["chi2"], 0.0) / tau
        r["ic"] = r["chi2"] / tau + (cur["q"] + q) * pen
        r["lowers_ic"] = r["ic"] < ic_cur
        r["explained"] = gain / excess if excess > 0 else 0.0
        r["enough"] = gain >= explain_fraction * excess
        r["guard_ok"] = True if guard is None else bool(guard(cur, r))
        return r

    return score


def _pair_step(fit_candidate, cur, rows, score, allowed):
    """The pair step of the rule (module docstring): ``((names, row, new current) or None,
    rows of the pairs tried)``; ``score`` is the step's :func:`_scorer`.

    A pair may be fitted in both orders (each member on top of the other: the fits start
    from different points); the table keeps one row per pair, the better order's, titled
    in one order (the names sorted), and only the pair named is marked NAMED (another that
    passes every test too is "qualifies, less good than the named pair").
    """
    singles = sorted((r for r in rows if r["lowers_ic"]), key=lambda r: r["ic"])
    if len(singles) < 2:
        return None, []
    orders = [(singles[0], r) for r in singles[1:]] + [(singles[1], singles[0])]
    fits = {}  # {pair (frozenset): (row, first, second, q of the pair)}
    for first, second in orders:
        if allowed is not None and not allowed(first["names"], second["name"]):
            continue
        on = {
            "names": first["names"],
            "chi2": first["chi2"],
            "q": cur["q"] + first["q"],
            "state": first["state"],
        }
        r = dict(fit_candidate(on, second["name"]))
        q_pair = first["q"] + r["q"]
        r["name"] = " + ".join(sorted((first["name"], second["name"])))
        score(r, q_pair)
        # each member earns its parameters on top of the other
        earns = r["ic"] < min(first["ic"], second["ic"])
        r["qualifies"] = bool(r["lowers_ic"] and r["enough"] and r["guard_ok"] and earns)
        r["dIC"] = r["ic"] - min(first["ic"], second["ic"])
        key = frozenset((first["name"], second["name"]))
        if key not in fits or r["ic"] < fits[key][0]["ic"]:
            fits[key] = (r, first, second, q_pair)
    tried = [f[0] for f in fits.values()]
    good = [f for f in fits.values() if f[0]["qualifies"]]
    top = min(good, key=lambda f: f[0]["ic"]) if good else None
    for r in tried:
        r["verdict"] = (
            "NAMED (pair)"
            if top is not None and r is top[0]
            else "qualifies, less good than the named pair"
            if r["qualifies"]
            else "pair explains little"
        )
    if top is None:
        return None, tried
    r, first, second, q_pair = top
    return (
        (first["name"], second["name"]),
        r,
        {
            "names": r["names"],
            "chi2": r["chi2"],
            "q": cur["q"] + q_pair,
            "state": r["state"],
            "row": r,
        },
    ), tried
