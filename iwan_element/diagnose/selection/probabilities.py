"""How sure a diagnosis is: posterior probabilities of the explanations it considered.

Every explanation a diagnosis fits (the plain joint, each single effect, each pair or larger
stack it fitted on the way) gets a probability (docs/probabilities.md, "How sure is the
diagnosis"; Beck and Yuen 2004, J. Eng. Mech. 130:192-203; Hoeting et al. 1999, Statist.
Sci. 14:382-417):

``P(M | data) = P(M) Z_M / sum_M' P(M') Z_M'``

* ``Z_M``, the evidence, is the Laplace approximation on a box prior
  (:func:`iwan_element.fitting.evidence.laplace_evidence`) of the likelihood the selection
  rule scores: ``exp(-chi2 / (2 tau s))``, ``chi2`` the noise-normalised residual, ``tau``
  the noise's correlation time (``n / tau`` effective samples, as in the rule) and ``s`` the
  model-error factor: when even the best explanation leaves more misfit than the noise
  (``chi2 / tau`` above ``n_eff - q``), the misfit no candidate explains is treated as more
  noise (``s = chi2_best / (tau (n_eff - q_best))``, at least 1), and, when that excess is
  significant (``s > 1 + 3 sqrt(2 / n_eff)``), ``tau`` becomes the best explanation's
  residual correlation time where that is longer (model error is correlated over far more
  samples than the noise), so an explanation is not declared certain by differences that a
  missing physics makes;
* each effect parameter's prior is uniform over its declared range
  (``ParamSpec.prior_range``, written with the effect), the joint's own variables over the
  loop model's bounds, the force scale, force offset and starting state over boxes that are
  the same for every explanation of a record (they cancel);
* ``P(M)``, the prior model probability: each of the ``K`` candidate effects the record can
  test is present independently with probability ``p`` (default ``1 - 2**(-1/K)``: even odds
  that the plain joint is enough), ``effect_prior=`` overrides it (one value, or one per
  effect).

The named effects are the most probable explanation; ``effect_probability(name)`` is the
sum of the probabilities of the explanations that contain it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...base.validation import check_scalar
from ...fitting.evidence import laplace_evidence, posterior_probabilities
from ...identify.loops.noise import integrated_time

__all__ = [
    "Explanation",
    "key",
    "default_effect_prior",
    "check_effect_prior",
    "log_model_prior",
    "model_error_scale",
    "rank",
    "NEGLIGIBLE",
]

#: Explanations whose log likelihood is this far below the best get no Laplace evaluation:
#: their probability is below ``exp(-NEGLIGIBLE)`` of the best's times the Occam factors'
#: ratio (bounded by the plain joint's, about ``exp(-40)`` on a record).
NEGLIGIBLE = 120.0
#: An explanation whose evidence by the Gaussian alone (:func:`laplace_evidence` without its
#: line integrals), times its prior, is this many nats below the best explanation's is
#: given that evidence: its probability is below ``exp(-BOUNDED)`` of the best's (about
#: 3e-7) and its line integrals, each 20-100 evaluations of its model, are not computed.
#: (The Gaussian over-counts an effect at zero size, where the line integrals lower the
#: evidence: docs/probabilities.md section 3.)
BOUNDED = 15.0


def key(names) -> tuple:
    """The key of an explanation in ``probabilities``: its effect names, sorted."""
    return tuple(sorted(names))


@dataclass(frozen=True, eq=False)
class Explanation:
    """One explanation a diagnosis fitted, with its evidence and probability.

    Attributes
    ----------
    effects : tuple of str
        Its effects, sorted (the key of ``probabilities``; ``()`` for the plain joint).
    stack : tuple of str
        The same effects in the order the model stacks them (innermost first).
    chi2 : float
        Noise-normalised residual sum of squares of its fit [-].
    n_params : int
        Parameters fitted.
    log_likelihood, log_occam, log_evidence : float
        ``-chi2 / (2 tau s)``, the Occam factor and their sum (up to a constant common to
        the record's explanations); NaN Occam factor when not evaluated (``NEGLIGIBLE``).
    log_prior : float
        Log prior model probability (normalised over the explanations considered).
    probability : float
        Posterior probability.
    theta, covariance : ndarray
        Fitted variables and their posterior covariance (Laplace, model-error factor
        included); empty when not evaluated.
    log_evidence_laplace : float
        The Laplace evidence (equal to ``log_evidence`` unless nested sampling was asked).
    log_evidence_nested, nested_error : float
        The nested-sampling evidence and its standard error (:mod:`.nested`), NaN when it
        was not asked; ``log_evidence`` is then this one.
    """

    effects: tuple
    stack: tuple
    chi2: float
    n_params: int
    log_likelihood: float
    log_occam: float
    log_evidence: float
    log_prior: float
    probability: float
    theta: np.ndarray
    covariance: np.ndarray
    log_evidence_laplace: float = math.nan
    log_evidence_nested: float = math.nan
    nested_error: float = math.nan

    def to_dict(self) -> dict:
        """The candidate's scores as a dict (probability in 0..1, log-evidence terms [-])."""
        return {
            "effects": list(self.effects),
            "probability": self.probability,
            "log_evidence": self.log_evidence,
            "log_likelihood": self.log_likelihood,
            "log_occam": self.log_occam,
            "log_prior": self.log_prior,
            "chi2": self.chi2,
            "n_params": self.n_params,
            "log_evidence_laplace": self.log_evidence_laplace,
            "log_evidence_nested": self.log_evidence_nested,
            "nested_error": self.nested_error,
        }


def default_effect_prior(n_candidates: int) -> float:
    """``1 - 2**(-1/K)``: each of ``K`` effects present independently with this probability
    gives the plain joint a prior probability of 1/2.
    """
    return 1.0 - 2.0 ** (-1.0 / max(int(n_candidates), 1))


def check_effect_prior(effect_prior, candidates) -> dict:
    """``{effect: prior probability}`` for ``candidates`` from ``effect_prior`` (None: the
    default; a number in (0, 1); or a dict of such numbers by effect name, others default).

    Raises
    ------
    ValueError
        A probability outside (0, 1), an unknown effect name, or another type.
    """
    p0 = default_effect_prior(len(candidates))
    if effect_prior is None:
        return dict.fromkeys(candidates, p0)
    if isinstance(effect_prior, dict):
        unknown = set(effect_prior) - set(candidates)
        if unknown:
            raise ValueError(
                f"effect_prior names effects that are not candidates: "
                f"{sorted(unknown)} (candidates: {list(candidates)})"
            )
        out = dict.fromkeys(candidates, p0)
        for k, v in effect_prior.items():
            out[k] = check_scalar(
                f"effect_prior[{k!r}]", v, low=0.0, high=1.0, low_open=True, high_open=True
            )
        return out
    v = check_scalar("effect_prior", effect_prior, low=0.0, high=1.0, low_open=True, high_open=True)
    return dict.fromkeys(candidates, v)


def log_model_prior(explanations, prior: dict) -> dict:
    """Log prior probabilities of ``explanations`` (keys) under independent effect priors
    ``prior`` (:func:`check_effect_prior`), normalised over them.
    """
    lp = {}
    for ex in explanations:
        lp[ex] = sum(math.log(p) if e in ex else math.log1p(-p) for e, p in prior.items())
    top = max(lp.values())
    norm = top + math.log(sum(math.exp(v - top) for v in lp.values()))
    return {k: v - norm for k, v in lp.items()}


def model_error_scale(chi2: float, tau: float, n_eff: float, q: int) -> float:
    """``s = chi2 / (tau (n_eff - q))``, at least 1: the misfit the best explanation leaves
    beyond the noise, counted as more noise (module docstring).
    """
    return max(1.0, chi2 / tau / max(n_eff - q, 1.0))


def rank(
    fitted, *, tau: float, n_eff: float, prior: dict, evaluate, nested: dict | None = None
) -> list:
    """Evidences and probabilities of the fitted explanations.

    Parameters
    ----------
    fitted : dict
        ``{key: (stack, chi2, n_params, state)}``: the best fit of each explanation.
    tau, n_eff : float
        The noise's correlation time [samples] and effective sample count.
    prior : dict
        ``{effect: prior probability}`` (:func:`check_effect_prior`).
    evaluate : callable
        ``evaluate(stack, state) -> (J, r, theta, lower, upper, chi2_at, specs)``: the
        noise-normalised Jacobian and residual of a fit, its variables, its prior box, its
        chi-square as a function of the variables (for the parameters fitted near a
        bound, :func:`~iwan_element.fitting.evidence.laplace_evidence`) and the
        :class:`~iwan_element.effects.ParamSpec` of each variable (None: uniform over the
        box), whose declared priors (:meth:`~iwan_element.effects.ParamSpec.log_prior`) are
        used.
    nested : dict, optional
        Also compute each evaluated explanation's evidence by nested sampling
        (:func:`.nested.nested_log_evidence` with these keyword options, e.g.
        ``{"sampler": "dynesty", "nlive": 200, "rng": 0}``; ``"explanations"``: the keys to
        sample, default all) and use it for the probabilities (the Laplace evidence where
        it was not sampled).

    Returns
    -------
    list of Explanation
        Most probable first.
    """
    best = min(fitted.values(), key=lambda f: f[1])
    s = model_error_scale(best[1], tau, n_eff, best[2])
    ts = tau * s
    if s > 1.0 + 3.0 * math.sqrt(2.0 / max(n_eff, 1.0)):
        # a misfit beyond the noise is left: it is model error, correlated over far more
        # samples than the noise; counted with its own correlation time
        r_best = evaluate(best[0], best[3])[1]
        ts = s * max(tau, integrated_time(r_best))
    lp = log_model_prior(list(fitted), prior)
    nested = None if nested is None else dict(nested)
    only = None if nested is None else nested.pop("explanations", None)
    only = None if only is None else {key(k) for k in only}
    rows, ns = {}, {}
    ll_best = -0.5 * best[1] / ts
    top = -math.inf  # the best ln Z + ln prior evaluated in full so far
    for k in sorted(fitted, key=lambda k: 0.5 * fitted[k][1] / ts - lp[k]):
        stack, chi2, q, state = fitted[k]
        ll = -0.5 * chi2 / ts
        if ll_best - ll > NEGLIGIBLE:
            rows[k] = (stack, chi2, q, ll, math.nan, np.zeros(0), np.zeros((0, 0)))
            continue
        J, r, theta, lo, hi, chi2_at, specs, *rdg = evaluate(stack, state)
        rdg = rdg[0] if rdg else None
        theta = np.clip(theta, lo, hi)
        log_prior, knots = spec_prior(specs, lo, hi)
        ev = laplace_evidence(J, r, theta, lo, hi, tau=ts, log_prior=log_prior)
        if nested is not None or rdg is not None or ev.log_evidence + lp[k] >= top - BOUNDED:
            ev = laplace_evidence(
                J,
                r,
                theta,
                lo,
                hi,
                tau=ts,
                chi2_at=chi2_at,
                log_prior=log_prior,
                prior_knots=knots,
                switched_off=switched_off(specs),
                lines=[sp is not None for sp in specs],
                ridge=rdg,
            )
            top = max(top, ev.log_evidence + lp[k])
        rows[k] = (stack, chi2, q, ll, ev.log_occam, theta, ev.covariance)
        if nested is not None and (only is None or k in only):
            from .nested import nested_log_evidence

            ns[k] = nested_log_evidence(chi2_at, lo, hi, specs, tau=ts, chi2_ref=chi2, **nested)
    occ = [v[4] for v in rows.values() if math.isfinite(v[4])]
    floor = min(occ) if occ else 0.0  # an unevaluated one: no better than the worst
    le = {k: v[3] + (v[4] if math.isfinite(v[4]) else floor) for k, v in rows.items()}
    use = dict(le)
    if nested is not None:  # the nested evidences decide
        use.update({k: v[0] for k, v in ns.items()})
    post = posterior_probabilities(use, lp)
    out = [
        Explanation(
            effects=k,
            stack=tuple(v[0]),
            chi2=float(v[1]),
            n_params=int(v[2]),
            log_likelihood=float(v[3]),
            log_occam=float(v[4]),
            log_evidence=float(use[k]),
            log_prior=float(lp[k]),
            probability=post[k],
            theta=v[5],
            covariance=v[6],
            log_evidence_laplace=float(le[k]),
            log_evidence_nested=float(ns[k][0]) if k in ns else math.nan,
            nested_error=float(ns[k][1]) if k in ns else math.nan,
        )
        for k, v in rows.items()
    ]
    return sorted(out, key=lambda e: -e.probability)


def spec_prior(specs, lo, hi):
    """``(log_prior(theta), knots)`` for :func:`~iwan_element.fitting.evidence.laplace_evidence`
    from each variable's ParamSpec (None: uniform over ``[lo, hi]``).
    """
    uniform = -np.log(np.asarray(hi, float) - np.asarray(lo, float))
    knots = np.array(
        [np.nan if sp is None or sp.neutral is None else float(sp.neutral) for sp in specs]
    )

    def log_prior(th):
        out = uniform.copy()
        for j, sp in enumerate(specs):
            if sp is not None:
                out[j] = float(sp.log_prior(th[j]))
        return out

    return log_prior, knots


#: Points (midpoint rule over prior probability) at which an effect's other parameters are
#: taken when its size is zero: per number of other parameters.
OFF_POINTS = {1: 7, 2: 3}


def switched_off(specs) -> dict:
    """``{size index: (other indices, values)}`` for
    :func:`~iwan_element.fitting.evidence.laplace_evidence`: an effect's parameters other
    than its size (its first with a ``neutral`` value: a gap's drag, a pinning spring's
    clearance, a slipping patch's onset and shape) do nothing at zero size; their values:
    the product grid of
    :data:`OFF_POINTS` quantiles of their declared priors. ``specs`` lists each variable's
    ParamSpec (None for the joint's own), the effects' in declaration order.
    """
    out, j = {}, 0
    while j < len(specs):
        sp = specs[j]
        if sp is None:
            j += 1
            continue
        group = [j]  # one effect's variables: consecutive, its own
        while (
            j + len(group) < len(specs)
            and specs[j + len(group)] is not None
            and specs[j + len(group)] in _siblings(sp)
        ):
            group.append(j + len(group))
        sizes = [g for g in group if specs[g].neutral is not None][:1]
        others = [g for g in group if g not in sizes]
        if sizes and others:
            m = OFF_POINTS.get(len(others), 2)
            q = (np.arange(m) + 0.5) / m
            grids = np.meshgrid(*[specs[g].prior_quantile(q) for g in others], indexing="ij")
            out[sizes[0]] = (tuple(others), np.column_stack([g.ravel() for g in grids]))
        j += len(group)
    return out


def _siblings(sp):
    """The ParamSpecs declared with ``sp`` (of the same effect, loop or modal)."""
    from ...effects import EFFECTS

    for cls in EFFECTS.values():
        for specs in (cls.specs, cls.modal_specs):
            if any(s is sp for s in specs):
                return specs
    return (sp,)
