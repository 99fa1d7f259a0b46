"""The natural frequencies a specimen's physical parameter ranges allow (the prior band):
each parameter drawn from its prior, the stuck modes followed by their shapes (MAC).
"""

from __future__ import annotations

import math

import numpy as np

from .parameters import updatable, with_parameters
from .sensitivities import modal_state, pair_modes

__all__ = ["prior_band"]


def prior_band(
    specimen,
    *,
    parameters=("attachments", "boundary"),
    modes=(1, 2),
    n: int = 200,
    rng=None,
    quantiles=(0.025, 0.5, 0.975),
) -> dict:
    """The natural frequencies the physical ranges of ``parameters`` allow: each parameter
    drawn from its prior (:class:`Updatable`: log-normal, or normal for a range from 0,
    clipped to the range), ``n`` draws, the ``quantiles`` of each mode's stuck frequency.

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    parameters : sequence of str, keyword-only
        Groups of :data:`GROUPS` or parameter names (:func:`updatable`).
    modes : sequence of int, keyword-only
        Elastic modes (1: lowest).
    n : int, keyword-only
        Draws (>= 10).
    rng : numpy.random.Generator or int, optional, keyword-only
        The random source (explicit, for a repeatable band).
    quantiles : sequence of float, keyword-only
        In (0, 1).

    Returns
    -------
    dict
        ``{mode: {"nominal": Hz, "quantiles": {q: Hz}}}``.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 10:
        raise ValueError(f"n must be an integer >= 10, got {n!r}")
    names = (parameters,) if isinstance(parameters, str) else tuple(parameters)
    rows = [u for u in updatable(specimen) if u.group in names or u.name in names]
    if not rows:
        raise ValueError(
            f"parameters name no updatable parameter of {specimen.name!r}: {parameters!r}"
        )
    gen = np.random.default_rng(rng)
    st0 = modal_state(specimen)
    out: dict[int, list[float]] = {int(r): [] for r in modes}  # {mode: frequencies [Hz]}
    for _ in range(int(n)):
        vals = {}
        for u in rows:
            if u.log:
                s = math.log(u.upper / u.lower) / 4.0
                v = math.exp(gen.normal(math.log(u.nominal), s))
            else:
                v = gen.normal(u.nominal, (u.upper - u.lower) / 4.0)
            vals[u.name] = min(max(v, u.lower), u.upper)
        st = modal_state(with_parameters(specimen, vals))
        pairs = pair_modes(st, st0, out)
        for r, k in pairs.items():
            out[r].append(st.frequency(k))
    return {
        r: {
            "nominal": st0.frequency(st0.index(r)),
            "quantiles": {float(q): float(np.quantile(v, q)) for q in quantiles},
        }
        for r, v in out.items()
    }
