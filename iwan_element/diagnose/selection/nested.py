"""Nested sampling of an explanation's evidence: the check of the Laplace approximation.

On request (``diagnose(..., evidence="nested")``, ``diagnose_vibration(...,
evidence="nested")``) every explanation's evidence is also computed by nested sampling
(Skilling 2006, Bayesian Analysis 1:833-860) with dynesty (Speagle 2020, MNRAS
493:3132-3158; ``pip install "iwan-element[nested]"``), on the same likelihood
``exp(-chi2 / (2 tau s))`` and the same priors (each variable's declared prior through its
distribution function's inverse, :meth:`~iwan_element.effects.ParamSpec.prior_quantile`;
uniform over the box for the others). dynesty was chosen over UltraNest by measuring both on
the vibration diagnosis (docs/probabilities.md: for the same stated error, dynesty's static
sampler needed fewer likelihood calls and a tenth of the time on these 1-4 parameter
problems; both agreed with each other within their errors).

Its answer is the reference where the posterior is not Gaussian (an effect fitted at zero
size, whose likelihood changes only to second order in its parameter near the bound), and the
Laplace evidence is checked against it (tests/test_evidence.py, benchmarks/
bench_diagnosis_calibration.py ``--nested``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["nested_log_evidence", "nested_options", "SAMPLERS"]

#: The samplers this module can use.
SAMPLERS = ("dynesty", "ultranest")


def nested_options(evidence, nested) -> dict[str, Any] | None:
    """The nested sampler's options (None: Laplace only); ValueError for a bad choice."""
    if evidence not in ("laplace", "nested"):
        raise ValueError(f"evidence must be 'laplace' or 'nested', got {evidence!r}")
    if nested is not None and not isinstance(nested, dict):
        raise ValueError(f"nested must be a dict of sampler options, got {nested!r}")
    if evidence == "laplace":
        return None
    return {"sampler": "dynesty", "nlive": 200, "rng": 0} | dict(nested or {})


def _transform(specs, lo, hi):
    width = np.asarray(hi, float) - np.asarray(lo, float)

    def transform(u):
        x = np.asarray(lo, float) + u * width
        for j, sp in enumerate(specs):
            if sp is not None:
                x[j] = float(sp.prior_quantile(u[j]))
        return x

    return transform


def nested_log_evidence(
    chi2_at,
    lower,
    upper,
    specs,
    *,
    tau: float = 1.0,
    chi2_ref: float = 0.0,
    sampler: str = "dynesty",
    nlive: int = 200,
    dlogz: float = 0.05,
    rng=None,
) -> tuple:
    """``(ln Z, its standard error)`` by nested sampling.

    Parameters
    ----------
    chi2_at : callable
        ``chi2_at(theta) -> chi2`` (noise-normalised chi-square).
    lower, upper : array_like, shape (k,)
        The prior box.
    specs : sequence
        Per variable its :class:`~iwan_element.effects.ParamSpec` (its declared prior) or
        None (uniform over the box).
    tau : float, keyword-only
        ``tau s``: the likelihood is ``exp(-(chi2 - chi2_ref) / (2 tau))``.
    chi2_ref : float, keyword-only
        Subtracted from every chi-square (``ln Z`` is then relative to ``-chi2_ref / (2 tau)``,
        added back in the result): keeps the sampler's numbers near 0.
    sampler : {"dynesty", "ultranest"}, keyword-only
    nlive : int, keyword-only
        Live points.
    dlogz : float, keyword-only
        Stopping tolerance on the remaining evidence [nats].
    rng : numpy.random.Generator or int, keyword-only

    Returns
    -------
    tuple of float

    Raises
    ------
    ImportError
        The sampler is not installed (``pip install "iwan-element[nested]"``).
    ValueError
        An unknown sampler.
    """
    if sampler not in SAMPLERS:
        raise ValueError(f"sampler must be one of {SAMPLERS}, got {sampler!r}")
    lo, hi = np.asarray(lower, float), np.asarray(upper, float)
    transform = _transform(specs, lo, hi)

    def loglike(th):
        c = float(chi2_at(np.clip(th, lo, hi)))
        return -0.5 * (c - chi2_ref) / tau if math.isfinite(c) else -1e300

    shift = -0.5 * chi2_ref / tau
    rng = np.random.default_rng(rng)
    if lo.size == 0:
        return loglike(lo) + shift, 0.0
    if sampler == "dynesty":
        try:
            import dynesty
        except ImportError:
            raise ImportError(
                "nested sampling needs dynesty: pip install 'iwan-element[nested]'"
            ) from None
        import warnings

        with warnings.catch_warnings():  # its bound-enlargement notices: not the user's
            warnings.simplefilter("ignore", UserWarning)
            s = dynesty.NestedSampler(
                loglike,
                transform,
                lo.size,
                nlive=nlive,
                rstate=rng,
                bound="multi",
                sample="rwalk" if lo.size > 3 else "unif",
            )
            s.run_nested(dlogz=dlogz, print_progress=False)
        r = s.results
        return float(r.logz[-1]) + shift, float(r.logzerr[-1])
    try:
        import ultranest
    except ImportError:
        raise ImportError("this sampler needs ultranest: pip install ultranest") from None
    import logging

    logging.getLogger("ultranest").setLevel(logging.WARNING)
    names = [f"p{j}" for j in range(lo.size)]
    s = ultranest.ReactiveNestedSampler(names, loglike, transform, vectorized=False, log_dir=None)
    r = s.run(min_num_live_points=nlive, dlogz=dlogz, show_status=False, viz_callback=False)
    return float(r["logz"]) + shift, float(r["logzerr"])
