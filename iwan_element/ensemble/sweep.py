"""Parameter sets for studies: full grids and space-filling samples (scipy.stats.qmc)."""

from __future__ import annotations

import itertools
import math

import numpy as np
from scipy.stats import qmc

from ..base.validation import check_int, check_scalar

__all__ = ["parameter_grid", "parameter_samples"]


def parameter_grid(**axes) -> list[dict]:
    """Every combination of the given values, the last axis varying fastest.

    Parameters
    ----------
    **axes : sequence
        ``name=values`` for each swept input, for instance
        ``parameter_grid(preload=[10e3, 20e3], mu=[0.2, 0.3])``; each sequence non-empty.

    Returns
    -------
    list of dict
        ``prod(len(values))`` parameter sets, ready for :func:`run_ensemble`.
    """
    if not axes:
        raise ValueError("give at least one axis, e.g. parameter_grid(preload=[1e4, 2e4])")
    vals = {}
    for name, values in axes.items():
        if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or len(values) == 0:
            raise ValueError(f"{name} must be a non-empty sequence of values, got {values!r}")
        vals[name] = [v.item() if isinstance(v, np.generic) else v for v in values]
    return [dict(zip(vals, combo)) for combo in itertools.product(*vals.values())]


def parameter_samples(n: int, *, seed=None, method: str = "lhs", log=(), **ranges) -> list[dict]:
    """``n`` parameter sets spread over box ranges (Latin hypercube, Sobol or plain random).

    Parameters
    ----------
    n : int
        Number of sets, ``>= 1``.
    seed : int or None, keyword-only
        Seed of the sampler.
    method : {"lhs", "sobol", "random"}, keyword-only
        ``scipy.stats.qmc.LatinHypercube`` (default), scrambled ``Sobol`` or independent
        uniform draws.
    log : sequence of str, keyword-only
        Names sampled uniformly in the logarithm (their ranges must be ``> 0``).
    **ranges : (low, high)
        ``name=(low, high)`` with ``low < high``, finite.

    Returns
    -------
    list of dict
    """
    n = check_int("n", n, 1)
    if not ranges:
        raise ValueError("give at least one range, e.g. parameter_samples(8, preload=(1e4, 4e4))")
    if method not in ("lhs", "sobol", "random"):
        raise ValueError(f"method must be 'lhs', 'sobol' or 'random', got {method!r}")
    unknown = set(log) - set(ranges)
    if unknown:
        raise ValueError(f"log names {sorted(unknown)} have no range")
    lo, hi = [], []
    for name, r in ranges.items():
        if not (isinstance(r, (tuple, list)) and len(r) == 2):
            raise ValueError(f"{name} must be a (low, high) pair, got {r!r}")
        a, b = check_scalar(f"{name} low", r[0]), check_scalar(f"{name} high", r[1])
        if not a < b:
            raise ValueError(f"{name}: low must be < high, got ({a}, {b})")
        if name in log:
            if a <= 0:
                raise ValueError(f"{name}: a log range needs low > 0, got {a}")
            a, b = math.log(a), math.log(b)
        lo.append(a)
        hi.append(b)
    d = len(ranges)
    if method == "random":
        u = np.random.default_rng(seed).random((n, d))
    elif method == "lhs":
        u = qmc.LatinHypercube(d=d, seed=seed).random(n)
    else:
        u = qmc.Sobol(d=d, scramble=True, seed=seed).random(n)
    x = qmc.scale(u, lo, hi)
    out = []
    for row in x:
        out.append({name: float(math.exp(v) if name in log else v) for name, v in zip(ranges, row)})
    return out
