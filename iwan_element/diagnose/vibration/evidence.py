"""The probability stage of a vibration diagnosis (:mod:`.diagnosis`): the explanations it
fitted, each one's Jacobian, prior box and chi-square for the evidence
(:func:`..selection.probabilities.rank`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ...effects import EFFECTS
from ..selection.probabilities import key

if TYPE_CHECKING:
    from ..selection.averaging import AveragedBand

__all__ = ["collect", "jacobian", "evaluate"]


def collect(base, steps) -> dict:
    """``{key: (stack, chi2, n_params, z)}``: the best fit of each explanation fitted."""
    out = {(): ((), float(base["chi2"]), int(base["state"].size), base["state"])}
    for st in steps:
        for r in st["rows"]:
            k = key(r["names"])
            if k not in out or r["chi2"] < out[k][1]:
                out[k] = (tuple(r["names"]), float(r["chi2"]), int(r["state"].size), r["state"])
    return out


def jacobian(vib, names, z) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Forward-difference Jacobian of the noise-normalised residual in ``z``."""
    h = 1e-6 * np.maximum(np.abs(z), 1e-3)
    r0 = vib.resid(names, z)
    J = np.empty((r0.size, z.size))
    for j in range(z.size):
        zz = z.copy()
        zz[j] += h[j]
        J[:, j] = (vib.resid(names, zz) - r0) / h[j]
    return J, r0


def evaluate(
    vib, names, z
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    Callable[[NDArray[np.float64]], float],
    list[Any],
]:
    """What :func:`.probabilities.rank` needs of a vibration fit: Jacobian, residual,
    variables, prior box (the nuisances' fit bounds, each effect variable's declared prior
    range) and the chi-square as a function of the variables.
    """
    J, r0 = jacobian(vib, names, z)
    specs = [s for nm in names for s in EFFECTS[nm].modal_specs]
    lo = np.array([s.prior_range[0] for s in specs])
    hi = np.array([s.prior_range[1] for s in specs])
    if vib.nn:
        lo = np.concatenate([vib.nuisance_bounds[0], lo])
        hi = np.concatenate([vib.nuisance_bounds[1], hi])

    def chi2_at(th):
        r = vib.resid(names, th)
        return float(r @ r) if np.all(np.isfinite(r)) else math.inf

    return J, r0, np.asarray(z, float), lo, hi, chi2_at, [None] * vib.nn + specs


def vibration_band(diag, amplitude, base, level) -> AveragedBand:
    """The model-averaged frequency and damping of a vibration diagnosis ``diag`` at
    ``amplitude`` (:class:`.averaging.AveragedBand`, channels ``"frequency"`` [Hz] and
    ``"damping_ratio"`` [-]); ``base``: the model without effects there (None: the
    prediction the diagnosis was given, interpolated in log amplitude, held at its ends).
    """
    from ...base.validation import finite_array
    from ..selection.averaging import band, linear_spread, members

    X = finite_array("amplitude", amplitude, ndim=1, min_size=1)
    if np.any(X <= 0):
        raise ValueError("amplitude must be > 0 [m]")
    if base is None:
        o = np.argsort(diag.amplitude)
        lx = np.log(diag.amplitude[o])
        fb = np.exp(np.interp(np.log(X), lx, np.log(diag.predicted_frequency[o])))
        zb = np.exp(np.interp(np.log(X), lx, np.log(diag.predicted_damping_ratio[o])))
    else:
        if not np.allclose(np.asarray(base.amplitude), X, rtol=1e-9, atol=0.0):
            raise ValueError("base must be the model's curve at exactly these amplitudes")
        fb, zb = np.asarray(base.frequency, float), np.asarray(base.damping_ratio, float)
    refs, nn = diag.details["refs"], int(diag.details["nuisances"])
    z0 = float(diag.details.get("predicted_zeta0", 0.0))
    parts = []
    for e, w in members(diag.explanations):
        if e.theta.size == 0 and e.effects:
            continue

        def predict(th, stack=e.stack):
            f, z, k = fb, zb, nn
            for nm in stack:
                vals = {}
                for sp in EFFECTS[nm].modal_specs:
                    vals[sp.name] = float(th[k]) / refs[sp.ref] ** sp.ref_power
                    k += 1
                f, z = EFFECTS[nm].modal_form(X, f, z, z0, **vals)
            return np.concatenate([f, z])

        if e.theta.size:
            mu, sd = linear_spread(predict, e.theta, e.covariance)
        else:
            mu, sd = predict(np.zeros(0)), np.zeros(2 * X.size)
        parts.append(
            (
                e.effects,
                w,
                {
                    "frequency": (mu[: X.size], sd[: X.size], "Hz"),
                    "damping_ratio": (mu[X.size :], sd[X.size :], "-"),
                },
            )
        )
    s = sum(p[1] for p in parts)
    return band(X, "amplitude [m]", [(a, w / s, c) for a, w, c in parts], level)


__all__ += ["vibration_band"]
