"""Linear model updating of a specimen on low-level (linear) test data: :func:`linear_update`.

The sensitivity method (Mottershead, Link, Friswell, MSSP 25:2275-2296, 2011;
docs/linear_update.md) on the specimen's stuck-joint modes
(:mod:`~iwan_element.models.updating`):

1. **Targets.** Natural frequencies, mode shapes at sensors (scale-free: each shape
   normalised to unit length over its sensors, sign matched) and drive-point modal constants
   ``(E phi)(S phi)`` [1/kg], each residual divided by its standard error: the measurement's
   and the model-form error ``model_error`` (relative; the default is stated in
   :data:`MODEL_ERROR`), added in quadrature. Modes are numbered as the specimen's elastic
   stuck modes (1: lowest) and followed by their shapes (MAC) as the parameters move.
2. **Prior.** Each parameter's physical range (:func:`~.parameters.updatable`) is the central
   95 % of its prior (log-normal, or normal for a range from 0): the regularisation of the
   Gauss-Newton step, ``(S^T W S + P)^-1 S^T W r``.
3. **What the targets see.** The weighted sensitivity matrix ``W^(1/2) S`` with each column
   in units of its prior width; a column-pivoted QR picks the parameters in the order the
   targets determine them; one whose new information (the pivot ``|R_kk|``) is below the
   prior's (1) is not identifiable: it stays at its nominal value, with a warning naming it
   (never moved silently). The singular values of the whole matrix are reported.
4. **Update** of the identifiable parameters (bounded least squares with the analytic
   Jacobian, :func:`iwan_element.fitting.minimize`), their covariance
   ``(S^T W S + P)^-1`` (scaled by the residuals' variance where the targets outnumber the
   parameters and disagree beyond their errors), correlations, and a prediction with
   stderr for every mode that was not a target (the parameters' share, and with the
   model-form error added: the band a measurement should fall in).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

from iwan_element.base.threads import one_blas_thread
from iwan_element.base.validation import plain_number
from iwan_element.fitting import Parameter, ParameterTable, minimize

from ..reduced.dispatch import check_specimen
from ._targets import _measured, _Targets
from .parameters import GROUPS, Updatable, updatable, with_parameters
from .result import LinearUpdateResult
from .sensitivities import modal_sensitivities, modal_state, pair_modes

__all__ = ["MODEL_ERROR", "LinearUpdateResult", "linear_update"]

#: The model-form error assumed for each kind of target (relative, 1 standard deviation):
#: frequencies 0.5 % (the 1-D and the solid Brake-Reuss models differ by 1.5 % on the second
#: bending mode with the same parameters; mesh and beam theory by 0.1-0.6 %), shapes 0.05 of
#: a unit-length shape, modal constants 5 %.
MODEL_ERROR = {"frequency": 5e-3, "shape": 0.05, "modal_constant": 0.05}
_PRIOR_SIGMAS = 4.0  # a range is the central 95 %: 4 standard deviations wide


def _select(specimen, parameters, ranges) -> list:
    rows = updatable(specimen, ranges=ranges)
    by_name = {u.name: u for u in rows}
    if not isinstance(parameters, str) and not (
        isinstance(parameters, (tuple, list)) and all(isinstance(n, str) for n in parameters)
    ):
        raise ValueError(
            f"parameters must be a group or parameter name or a sequence of them "
            f"(groups {GROUPS}; updatable(specimen) lists the names), got "
            f"{parameters!r}"
        )
    names = (parameters,) if isinstance(parameters, str) else tuple(parameters)
    out = []
    for n in names:
        if n in GROUPS:
            out += [u for u in rows if u.group == n and u not in out]
        elif n in by_name:
            if by_name[n] not in out:
                out.append(by_name[n])
        else:
            raise ValueError(
                f"parameters must name groups {GROUPS} or parameters "
                f"{sorted(by_name)} of {specimen.name!r}, got {n!r}"
            )
    if not out:
        raise ValueError(
            f"parameters name no updatable parameter of {specimen.name!r} "
            f"(groups {GROUPS}; updatable(specimen) lists them)"
        )
    return out


def _prior_sigma(u: Updatable) -> float:
    return (math.log(u.upper / u.lower) if u.log else u.upper - u.lower) / _PRIOR_SIGMAS


def _theta(u: Updatable, v: float) -> float:
    return math.log(v) if u.log else v


def _value(u: Updatable, th: float) -> float:
    return math.exp(th) if u.log else th


class _Problem:
    """The weighted residuals of the targets and their Jacobian at given parameters."""

    def __init__(self, specimen, targets: _Targets, params, reference):
        self.s0, self.t, self.params, self.ref = specimen, targets, params, reference
        self._last = (None, None)
        self.theta0 = [_theta(u, u.nominal) for u in params]

    def specimen(self, theta):
        """The specimen at ``theta`` (a parameter at its starting value is not touched)."""
        return with_parameters(
            self.s0,
            {
                u.name: _value(u, th)
                for u, th, t0 in zip(self.params, theta, self.theta0)
                if th != t0
            },
        )

    def evaluate(self, theta):
        """``(r, J, raw, (specimen, state, pairs))``: weighted residuals, their Jacobian by
        ``theta``, the model's raw values (the last evaluation is kept: the solver asks for
        the residuals and the Jacobian at the same point).
        """
        key = tuple(np.asarray(theta, float))
        if self._last[0] != key:
            with one_blas_thread():  # small dense problems: threads only contend
                self._last = (key, self._evaluate(theta))
        return self._last[1]

    def _evaluate(self, theta):
        s = self.specimen(theta)
        st = modal_state(s)
        pairs = pair_modes(st, self.ref, self.t.modes)
        cur = [
            Updatable(**{**u.to_dict(), "nominal": _value(u, th)})
            for u, th in zip(self.params, theta)
        ]
        sens = modal_sensitivities(s, pairs, cur, positions=self.t.positions, state=st)
        r, J, raw = [], [], []
        pos_all = np.array(self.t.positions)
        for m, (f, se) in self.t.freq.items():
            r.append((sens["f"][m] / f - 1) / se)
            J.append(sens["df"][m] / (f * se))
            raw.append(sens["f"][m])
        for m, (pos, unit, se) in self.t.shapes.items():
            idx = np.searchsorted(pos_all, pos)
            a, da = sens["shape"][m][idx], sens["dshape"][m][idx]
            n = np.linalg.norm(a)
            sgn = 1.0 if a @ unit >= 0 else -1.0
            ah = sgn * a / n
            dah = sgn * (da - np.outer(ah, ah @ (sgn * da))) / n
            r += list((ah - unit) / se)
            J += list(dah / se[:, None])
            raw += list(ah)
        for m, (c, se) in self.t.consts.items():
            r.append((sens["c"][m] / c - 1) / se)
            J.append(sens["dc"][m] / (c * se))
            raw.append(sens["c"][m])
        return (
            np.array(r),
            np.array(J).reshape(len(r), len(self.params)),
            np.array(raw),
            (s, st, pairs),
        )


def _identifiable(Js, names) -> tuple:
    """Column-pivoted QR of the prior-scaled weighted sensitivity ``Js``: ``(kept indices,
    {name: pivot})`` (module docstring, step 3).
    """
    if Js.shape[0] == 0:
        return [], {}
    _, R, piv = sla.qr(Js, mode="economic", pivoting=True)
    d = np.zeros(Js.shape[1])
    d[: min(R.shape)] = np.abs(np.diag(R))
    gain = {names[p]: float(d[k]) for k, p in enumerate(piv)}
    return sorted(int(p) for k, p in enumerate(piv) if d[k] >= 1.0), gain


def linear_update(
    specimen,
    *,
    frequencies,
    shapes=None,
    modal_constants=None,
    parameters,
    model_error: dict | None = None,
    ranges: dict | None = None,
    predict=None,
    max_nfev: int = 60,
) -> LinearUpdateResult:
    """Update a specimen's linear parameters on low-level test data (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
        The nominal model; its setup is the tested setup.
    frequencies : dict, keyword-only
        ``{mode: Hz}`` or ``{mode: (Hz, stderr)}``; mode 1 is the lowest elastic mode (as
        ``ringdown`` and ``modal_amplitude_curve`` number them; rigid-body modes are not
        counted).
    shapes : dict, optional, keyword-only
        ``{mode: {position [m]: amplitude}}`` (real signed or complex; an amplitude may be
        ``(value, stderr)``): compared scale-free (unit length, sign matched).
    modal_constants : dict, optional, keyword-only
        ``{mode: c}`` or ``{mode: (c, stderr)}``: the drive-point modal constant
        ``(E phi)(S phi)`` [1/kg] at the specimen's excitation and sensor points.
    parameters : str or sequence of str, keyword-only
        Groups of :data:`~.parameters.GROUPS` or names of :func:`~.parameters.updatable`.
    model_error : dict, optional, keyword-only
        Relative model-form error per target kind (:data:`MODEL_ERROR`).
    ranges : dict, optional, keyword-only
        ``{name: (lower, upper)}``: physical ranges (priors) overriding the defaults.
    predict : sequence of int, optional, keyword-only
        Modes to predict (default: the modes up to two above the highest target that are
        not targets).
    max_nfev : int, keyword-only
        Evaluation budget of the least-squares solver.

    Returns
    -------
    LinearUpdateResult
    """
    check_specimen(specimen)
    err = {**MODEL_ERROR, **dict(model_error or {})}
    if set(err) != set(MODEL_ERROR) or not all(
        isinstance(plain_number(v), (int, float)) and plain_number(v) > 0 for v in err.values()
    ):
        raise ValueError(
            f"model_error must map {sorted(MODEL_ERROR)} to relative errors > 0, "
            f"got {model_error!r}"
        )
    t = _Targets.build(frequencies, shapes, modal_constants, err)
    params = _select(specimen, parameters, ranges)
    ref = modal_state(specimen)
    for m in t.modes:
        ref.index(m)  # a mode the model has
    prob = _Problem(specimen, t, params, ref)
    th0 = np.array([_theta(u, u.nominal) for u in params])
    sig = np.array([_prior_sigma(u) for u in params])
    r0, J0, raw0, _ = prob.evaluate(th0)
    keep, gain = _identifiable(J0 * sig[None, :], [u.name for u in params])
    warns = [
        f"{u.name}: the targets cannot see it (new information {gain[u.name]:.2g} of its "
        "prior's): left at its nominal value"
        for k, u in enumerate(params)
        if k not in keep
    ]
    sol_th, conv, nfev = th0.copy(), True, 0
    if keep:
        sol_th, conv, nfev = _solve(prob, params, keep, th0, sig, max_nfev, warns)
    return _result(
        specimen,
        prob,
        params,
        keep,
        sol_th,
        th0,
        sig,
        r0,
        raw0,
        gain,
        warns,
        conv,
        nfev,
        t,
        err,
        predict,
    )


def _solve(prob, params, keep, th0, sig, max_nfev, warns):
    """The regularised least squares of :func:`linear_update` over the identifiable
    parameters ``keep`` (module docstring, step 4): ``(theta, converged, nfev)``; a
    parameter ending on its bound is named in ``warns``.
    """
    lo = np.array([_theta(params[k], params[k].lower) for k in keep])
    hi = np.array([_theta(params[k], params[k].upper) for k in keep])

    def full(x):
        th = th0.copy()
        th[keep] = x
        return th

    def fun(x):
        r, _, _, _ = prob.evaluate(full(x))
        return np.concatenate([r, (x - th0[keep]) / sig[keep]])

    def jac(x):
        _, J, _, _ = prob.evaluate(full(x))
        return np.vstack([J[:, keep], np.diag(1.0 / sig[keep])])

    sol = minimize(
        fun, th0[keep], lo, hi, method="trf", max_nfev=max_nfev, jac=jac, x_scale=sig[keep]
    )
    for k, x in zip(keep, sol.x):
        b = min(x - _theta(params[k], params[k].lower), _theta(params[k], params[k].upper) - x)
        if b < 1e-3 * sig[k]:
            warns.append(f"{params[k].name} ended on the bound of its physical range")
    return full(sol.x), bool(sol.success), int(sol.nfev)


def _result(
    specimen, prob, params, keep, th, th0, sig, r0, raw0, gain, warns, conv, nfev, t, err, predict
):
    """Covariance, predictions and the result of :func:`linear_update`."""
    r1, J1, raw1, (spec1, st1, _) = prob.evaluate(th)
    Jk = J1[:, keep]
    dof = r1.size - len(keep)
    chi2 = float(r1 @ r1)
    scale = max(1.0, chi2 / dof) if dof > 0 else 1.0
    if dof > 0 and chi2 / dof > 4.0:
        warns.append(
            f"the targets disagree with the updated model by {math.sqrt(chi2 / dof):.2g}"
            " times their stated errors (reduced chi^2 "
            f"{chi2 / dof:.3g}): a parameter or an effect the model lacks, or errors "
            "stated too small; the stderr are scaled up by it"
        )
    cov = np.zeros((len(params), len(params)))
    if keep:
        P = np.diag(1.0 / sig[keep] ** 2)
        cov[np.ix_(keep, keep)] = scale * np.linalg.inv(Jk.T @ Jk + P)
    sd = np.sqrt(np.diag(cov))
    rows = _parameter_rows(params, keep, th, sd)
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    corr[~np.isfinite(corr)] = np.nan
    Js = J1 * sig[None, :]
    sv = sla.svdvals(Js) if Js.size else np.zeros(0)
    pr = _predictions(prob, params, th, t, spec1, st1, cov, err, predict)
    resid = [
        {
            "target": lab,
            "measured": _measured(t, lab),
            "before": float(b),
            "after": float(a),
            "residual_before": float(rb),
            "residual_after": float(ra),
        }
        for lab, b, a, rb, ra in zip(t.labels, raw0, raw1, r0, r1)
    ]
    return LinearUpdateResult(
        specimen=spec1,
        initial=specimen,
        params=ParameterTable(rows, correlation=corr),
        groups={u.name: u.group for u in params},
        nominal={u.name: u.nominal for u in params},
        information={u.name: gain.get(u.name, 0.0) for u in params},
        singular_values=sv,
        residuals=tuple(resid),
        predictions=pr,
        chi2=chi2,
        dof=dof,
        converged=conv,
        nfev=nfev,
        model_error=dict(err),
        warnings=tuple(warns),
    )


def _parameter_rows(params, keep, th, sd) -> list:
    """The parameter table's rows: the updated values (clipped to their ranges) and stderr
    of the parameters ``keep``, the others fixed at their nominal values.
    """
    rows = []
    for k, u in enumerate(params):
        v = _value(u, th[k]) if k in keep else u.nominal
        se = (v * sd[k] if u.log else sd[k]) if k in keep else math.nan
        rows.append(
            Parameter(
                u.name,
                min(max(v, u.lower), u.upper),
                se,
                u.lower,
                u.upper,
                u.unit,
                identified=k in keep,
                fixed=k not in keep,
            )
        )
    return rows


def _predictions(prob, params, th, t, spec1, st1, cov, err, predict) -> dict:
    """``{mode: {frequency, stderr, parameter_stderr, nominal_frequency}}`` of the modes not
    among the targets (default: up to two above the highest target), from the updated model.
    """
    modes = t.modes
    top = max(modes) + 2
    pred_modes = tuple(range(1, top + 1)) if predict is None else tuple(int(m) for m in predict)
    pred_modes = tuple(
        m for m in pred_modes if m not in t.freq and st1.n_rigid + m - 1 < st1.lam.size
    )
    pr = {}
    if pred_modes:
        cur = [Updatable(**{**u.to_dict(), "nominal": _value(u, x)}) for u, x in zip(params, th)]
        sens = modal_sensitivities(spec1, pair_modes(st1, prob.ref, pred_modes), cur, state=st1)
        for m in pred_modes:
            f, g = sens["f"][m], sens["df"][m]
            pse = math.sqrt(max(float(g @ cov @ g), 0.0))
            pr[m] = {
                "frequency": f,
                "stderr": math.hypot(pse, err["frequency"] * f),
                "parameter_stderr": pse,
                "nominal_frequency": prob.ref.frequency(prob.ref.index(m)),
            }
    return pr
