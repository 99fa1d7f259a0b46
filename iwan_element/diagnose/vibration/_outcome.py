"""What a vibration diagnosis (:mod:`.diagnosis`) reports of its chosen fit: where the
measured curves leave the prediction, what is left after the fit, the fitted values at
the end of their fit range and their covariance.
"""

from __future__ import annotations

import math

import numpy as np

from ...effects import EFFECTS
from ...fitting import covariance
from ..selection.rule import criterion_text
from .evidence import jacobian


def _where(X, rf0, rz0, sf, sz, misfit):
    """Where the measured curves leave the prediction by more than 3 x noise: per curve, the
    amplitude ranges (in increasing amplitude) where the measurement is above or below, with
    the largest relative difference in each (a turn, e.g. a frequency that falls and then
    rises again, shows as two ranges of opposite sign).
    """
    order = np.argsort(X)
    parts = []
    for label, r, s in (("frequency", rf0[order], sf), ("damping", rz0[order], sz)):
        xs = X[order]
        sign = np.where(r > 3 * s, 1, np.where(r < -3 * s, -1, 0))
        runs, k = [], 0
        while k < sign.size:
            j = k
            while j + 1 < sign.size and sign[j + 1] == sign[k]:
                j += 1
            if sign[k] != 0 and j > k:  # two or more points in a row
                i = k + int(np.argmax(np.abs(r[k : j + 1])))
                runs.append(
                    f"{'above' if sign[k] > 0 else 'below'} it from {xs[k]:.3g} to "
                    f"{xs[j]:.3g} m (up to {100 * abs(math.expm1(r[i])):.3g} % at "
                    f"{xs[i]:.3g} m)"
                )
            k = j + 1
        if runs:
            parts.append(
                f"measured {label} beyond 3 x noise of the prediction: " + ", then ".join(runs)
            )
    where = (
        "; ".join(parts)
        if (misfit and parts)
        else "measured and predicted curves agree within the noise"
    ) + "."
    return where[0].upper() + where[1:]


def _left(X, rf, rz, sf, sz):
    """Where residuals left after the fit exceed 3 x noise: amplitude ranges per curve."""
    parts = []
    for label, r, s in (("frequency", rf, sf), ("damping", rz, sz)):
        big = np.abs(r) > 3 * s
        if big.any():
            parts.append(
                f"{label} off by up to {100 * np.max(np.abs(r[big])):.3g} % at "
                f"{X[big].min():.3g} .. {X[big].max():.3g} m"
            )
    return (": " + "; ".join(parts)) if parts else ""


def _at_upper_bound(vib, names, z):
    """Fitted values at the upper end of their fit range (the data do not bound them, and
    predictions beyond the measured amplitudes depend on that end): ``(warnings, names as
    "effect.parameter")``.
    """
    out, at, k = [], [], vib.nn
    for nm in names:
        for sp in EFFECTS[nm].modal_specs:
            lo, hi = sp.fit_bounds
            if z[k] >= hi - 1e-6 * (hi - lo):
                out.append(
                    f"{nm} {sp.name} sits at the upper end of its fit range "
                    f"({hi:g} in fit units): the data do not bound it, and predictions "
                    "beyond the measured amplitudes depend on that end"
                )
                at.append(f"{nm}.{sp.name}")
            k += 1
    return out, at


def _covariance(vib, names, z, chi2):
    """Covariance of the fitted modal values: ``(J^T J)^-1`` of the noise-normalised residual
    in the fitting variables (:func:`iwan_element.fitting.covariance`, docs/fitting.md;
    NaN errors along a degenerate direction), scaled by the reduced chi-square when above 1,
    mapped to the values (each value is its variable over a fixed reference scale). Returns
    that matrix (None without effects; a pseudo-inverse along a degenerate direction, used
    for the prediction bands), the values' standard errors (NaN for a value the data do not
    determine) and the standard errors of the between-test nuisances (relative frequency and
    damping offsets; empty without them).
    """
    if z.size == 0:
        return None, np.zeros(0), ()
    J, r0 = jacobian(vib, names, z)
    dof = max(r0.size - z.size, 1)
    cz = covariance(J, s2=max(1.0, chi2 / dof), dof=dof)
    Cz, sd = cz.covariance, cz.stderr
    nuis = (
        ()
        if not vib.nn
        else (float(sd[0] * math.exp(float(z[0]))), float(sd[1] * math.exp(float(z[1]))))
    )
    if not names:
        return None, np.zeros(0), nuis
    scale = np.array(
        [1.0 / vib.refs[sp.ref] ** sp.ref_power for nm in names for sp in EFFECTS[nm].modal_specs]
    )
    return Cz[vib.nn :, vib.nn :] * np.outer(scale, scale), sd[vib.nn :] * scale, nuis


def _steps(sel):
    """The selection's steps as records: each step's base and its candidates' rows."""
    steps = [
        {
            "on": st["on"],
            "candidates": [
                {k: r.get(k) for k in ("name", "error", "dIC", "explained", "verdict")}
                for r in st["rows"]
            ],
        }
        for st in sel.steps
    ]
    return steps


def _details(
    vib, sel, names, se, at_bound, rule_named, chi_b, rf0, rz0, f_new, z_new, alpha, noise_from
):
    """The diagnosis' ``details``: noise source, misfit before and after, errors, standard
    errors, values at their bound, the rule's naming and the references.
    """
    details = {
        "noise_from": noise_from,
        "misfit_p": sel.p_before,
        "misfit_p_after": sel.p_after,
        "alpha": alpha,
        "chi2_before": chi_b,
        "chi2_after": sel.final["chi2"],
        "criterion": criterion_text(),
        "predicted_zeta0": vib.zeta0,
        "frequency_error_before": float(np.sqrt(np.mean(rf0**2))),
        "damping_error_before": float(np.sqrt(np.mean(rz0**2))),
        "frequency_error_after": float(np.sqrt(np.mean(np.log(vib.fm / f_new) ** 2))),
        "damping_error_after": float(np.sqrt(np.mean(np.log(vib.zm / z_new) ** 2))),
        "stderr": dict(
            zip((f"{nm}.{sp.name}" for nm in names for sp in EFFECTS[nm].modal_specs), se)
        ),
        "at_bound": at_bound,
        "rule_named": list(rule_named),
        "refs": dict(vib.refs),
        "nuisances": vib.nn,
    }
    return details
