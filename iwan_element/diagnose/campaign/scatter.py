"""The record-to-record scatter of a campaign about its laws: each record's own values in
the laws' form, their deviations from the laws, the scatter's covariance (a random effect
per record and quantity), a draw of it, and the law coefficients' covariance it gives
(equations: ``docs/campaign.md`` section 6).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ...effects import EFFECTS
from ...fitting import normal_inverse
from .model import design, effect_quantity, to_law

__all__ = ["in_range", "deviations", "scatter_cov", "perturb", "scatter_coef_cov"]


def in_range(model, vals, rm) -> dict:
    """Law-form values as the model uses them on record model ``rm`` (clipped where
    :meth:`.model.CampaignModel.physical` clips; NaN for a one-sided parameter at its bound).
    """
    Fs, (phi, chi, beta), effs = model.physical(vals, rm)
    out = {"Fs": Fs, "log_phi_max": math.log(phi), "chi": chi, "log1p_beta": math.log1p(beta)}
    for nm, d in zip(model.names, effs):
        for sp in EFFECTS[nm].specs:
            out[effect_quantity(nm, sp)] = to_law(sp, d[sp.name])
    return out


def deviations(model, theta, free, skip=None) -> tuple[NDArray[np.float64], int]:
    """``(D, dof)``: per record (``skip`` left out) the deviation of its own values with the
    campaign's stack (``free[r]``, :func:`in_range` form; None: no such fit) from the laws at
    its conditions, one column per quantity (``Fs`` as ``ln(Fs_r / Fs_law)``: the slip
    force scatters in proportion, not by a fixed number of newtons); NaN where a value is
    missing. ``dof`` per quantity: records with a value minus the law's coefficients.
    """
    rows = []
    for r, f in enumerate(free):
        if r == skip or f is None:
            continue
        law = in_range(model, model.law_values(theta, model.X[r]), model.records[r])
        d = [math.log(f["Fs"] / law["Fs"]) if f["Fs"] > 0 and law["Fs"] > 0 else math.nan]
        d += [f[q] - law[q] for q in model.qnames[1:]]
        rows.append(d)
    D = np.array(rows, float).reshape(-1, len(model.qnames))
    n_coef = np.array([1 + len(model.laws[q]) for q in model.qnames])
    dof = np.maximum(np.isfinite(D).sum(axis=0) - n_coef, 1)
    return D, dof


def scatter_cov(D, dof) -> np.ndarray:
    """Covariance of the record-to-record scatter about the laws (a random effect per record
    and quantity, method of moments): ``S_kl = sum_r d_rk d_rl / sqrt(dof_k dof_l)`` over the
    records with both values (docs/campaign.md section 6).
    """
    ok = np.isfinite(D)
    Z = np.where(ok, D, 0.0)
    return (Z.T @ Z) / np.sqrt(np.outer(dof, dof))


def perturb(model, vals: dict, e) -> dict:
    """Law values ``vals`` moved by a scatter draw ``e`` (the columns of :func:`deviations`)."""
    out = dict(vals)
    out["Fs"] = vals["Fs"] * math.exp(float(e[0]))
    for q, v in zip(model.qnames[1:], e[1:]):
        out[q] = vals[q] + float(v)
    return out


def scatter_coef_cov(model, theta, S, skip=None) -> np.ndarray:
    """Covariance of the law coefficients (internal form, ``n_glob`` square, a block per
    quantity) that the record-to-record scatter ``S`` gives: each record's value of a
    quantity off its law by a random effect of variance ``S_kk`` (``Fs``: relative, so
    ``(S_00 Fs_law(x_r)^2``), the generalised least-squares covariance
    ``(A^T V^-1 A)^-1`` of the law over the records (``skip`` left out).
    """
    C = np.zeros((model.n_glob, model.n_glob))
    rs = [r for r in range(model.X.shape[0]) if r != skip]
    for k, q in enumerate(model.qnames):
        A = design(model.X[rs], model.cnames, model.laws[q], model.centre, model.cscale)
        var = np.full(len(rs), S[k, k]) / model.qscale[q] ** 2
        if q == "Fs":
            var = var * np.array([model.law_values(theta, model.X[r])["Fs"] ** 2 for r in rs])
        if not np.all(var > 0):
            continue
        sl = model.slices[q]
        C[sl, sl] = normal_inverse(A / np.sqrt(var)[:, None])[0]  # (A^T V^-1 A)^-1
    return C
