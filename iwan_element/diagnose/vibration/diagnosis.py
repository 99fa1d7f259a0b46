"""Vibration diagnosis: measured against predicted amplitude-dependent frequency and damping.

The candidates are the effects of :data:`~iwan_element.EFFECTS` that declare an
amplitude-domain (modal) form (``modal_specs`` and ``modal_form``; e.g. viscous damping, a
damping floor; pinning stiffness, a stiffening after a clearance; hardening, a cubic
stiffening; macroslip onset, a patch that slides above an amplitude), so a new effect module
with a modal form is a candidate without touching this module. Equations:
``docs/vibration_effects.md``. The measurement may be an
:class:`~iwan_element.AmplitudeCurve` (from a decay or from sweeps). The selection rule is
the one shared with the loop diagnosis (:mod:`iwan_element.diagnose.selection`), on the log
residuals of frequency and damping divided by their noise. When the prediction is a beam
specimen's QSMA curve, the fitted modal forms are exactly the augmented specimen's
(``VibrationDiagnosis.augment``). A mismatch no candidate explains is stated with the
amplitudes where it lies. The noise is the per-point uncertainty the caller states, unless
the scatter the data show about a smooth curve (robust, from second differences along
amplitude) lies above that statement's 99 % range, then that scatter; with nothing stated,
the scatter; with too few amplitudes to trust a scatter estimate a warning says so.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from ...base.serialize import json_safe
from ...base.validation import check_int, check_scalar, finite_array
from ...effects import EFFECTS
from ..selection.nested import nested_options
from ..selection.probabilities import check_effect_prior, key, rank
from ..selection.rule import misfit_p, stepwise_select
from ._measurement import _curve_level, _inputs, _measurement, _relative
from ._outcome import _at_upper_bound, _covariance, _details, _left, _steps, _where
from .evidence import collect, evaluate
from .result import VibrationDiagnosis

__all__ = ["diagnose_vibration", "vibration_candidates"]


def vibration_candidates() -> tuple:
    """Names of the effects with a modal form."""
    return tuple(n for n, c in EFFECTS.items() if c.modal_specs)


class _Vib:
    """Modal forms of a stack on the prediction, and its noise-normalised residual."""

    def __init__(self, X, fm, zm, fp, zp, zeta0, sf, sz, between_tests=False):
        self.X, self.fm, self.zm, self.fp, self.zp, self.zeta0 = X, fm, zm, fp, zp, zeta0
        self.sf, self.sz = sf, sz
        w2 = 4 * np.pi**2 * float(np.min(fp)) ** 2
        self.refs = {
            "zeta_ref": float(np.median(zp)),
            "X_max": float(X.max()),
            "omega2_ref": w2,
            "omega2_per_X2": w2 / float(X.max()) ** 2,
            "1": 1.0,
        }
        # between-test nuisances (first in every state vector): the log ratios of the other
        # test's frequency and damping to the model's, constant over the amplitudes
        self.nn = 2 if between_tests else 0
        self.nuisance_bounds = (np.array([-0.05, -1.0]), np.array([0.05, 1.0]))

    def nuisance(self, z):
        """``(relative frequency offset [-], relative damping offset [-])`` of a state."""
        if not self.nn:
            return 0.0, 0.0
        return math.expm1(float(z[0])), math.expm1(float(z[1]))

    def fit_nuisance(self):
        """The base state: the between-test nuisances alone (empty without them)."""
        if not self.nn:
            return np.zeros(0), float(np.sum(self.resid((), np.zeros(0)) ** 2))
        lo, hi = self.nuisance_bounds
        res = least_squares(
            lambda z: self.resid((), z), np.zeros(2), bounds=(lo, hi), method="trf", x_scale="jac"
        )
        return res.x, 2 * float(res.cost)

    def decode(self, names, z):
        vals, k = {}, self.nn
        for nm in names:
            vals[nm] = {}
            for sp in EFFECTS[nm].modal_specs:
                vals[nm][sp.name] = float(z[k]) / self.refs[sp.ref] ** sp.ref_power
                k += 1
        return vals

    def curves(self, names, z):
        f, zz = self.fp, self.zp
        vals = self.decode(names, z)
        for nm in names:
            f, zz = EFFECTS[nm].modal_form(self.X, f, zz, self.zeta0, **vals[nm])
        if self.nn:  # the other test: the whole curve by constant factors
            df, dz = self.nuisance(z)
            f, zz = f * (1.0 + df), zz * (1.0 + dz)
        return f, zz

    def resid(self, names, z):
        f, zz = self.curves(names, z)
        return np.concatenate([np.log(self.fm / f) / self.sf, np.log(self.zm / zz) / self.sz])

    def error(self, names, z):
        f, zz = self.curves(names, z)
        return math.sqrt(np.mean(np.concatenate([np.log(self.fm / f), np.log(self.zm / zz)]) ** 2))

    def fit(self, names, z_prev):
        specs = [s for nm in names for s in EFFECTS[nm].modal_specs]
        lo = np.array([s.fit_bounds[0] for s in specs])
        hi = np.array([s.fit_bounds[1] for s in specs])
        if self.nn:
            lo = np.concatenate([self.nuisance_bounds[0], lo])
            hi = np.concatenate([self.nuisance_bounds[1], hi])
        new = EFFECTS[names[-1]].modal_specs
        best = None
        for j in range(max(len(s.fit_starts) for s in new)):
            z0 = np.concatenate(
                [z_prev, [s.fit_starts[min(j, len(s.fit_starts) - 1)] for s in new]]
            )
            z0 = np.clip(z0, lo, hi - 1e-12)
            res = least_squares(
                lambda z: self.resid(names, z), z0, bounds=(lo, hi), method="trf", x_scale="jac"
            )
            if best is None or res.cost < best.cost:
                best = res
        return best


def diagnose_vibration(
    amplitude,
    frequency=None,
    damping_ratio=None,
    *,
    predicted_frequency,
    predicted_damping_ratio,
    frequency_noise: float | None = None,
    damping_ratio_noise: float | None = None,
    frequency_uncertainty=None,
    damping_ratio_uncertainty=None,
    predicted_zeta0: float = 0.0,
    alpha: float = 1e-3,
    ambiguity: float = 10.0,
    max_effects: int = 2,
    between_tests: bool = False,
    effect_prior=None,
    evidence: str = "laplace",
    nested=None,
) -> VibrationDiagnosis:
    """Compare measured and predicted amplitude-dependent frequency and damping; name what the
    jointed model misses (see the module docstring).

    Parameters
    ----------
    amplitude : array_like, shape (n,), or AmplitudeCurve
        Response amplitude [m], ``> 0``; or a measured :class:`~iwan_element.AmplitudeCurve`
        (from :func:`~iwan_element.amplitude_curve`, :func:`~iwan_element.sweep_curve`, ...):
        then ``frequency`` and ``damping_ratio`` are omitted and its standard errors, relative to
        its values, are the stated uncertainties unless those are given.
    frequency, damping_ratio : array_like, shape (n,)
        Measured frequency [Hz] and damping ratio [-], ``> 0`` (a value of 1 or more, or a
        curve never below 0.05, is refused as percent).
    predicted_frequency, predicted_damping_ratio : array_like, shape (n,), keyword-only
        The model's prediction at the same amplitudes [Hz], [-].
    frequency_noise, damping_ratio_noise : float, optional, keyword-only
        Relative noise standard deviations [-], in ``(0, 0.5]`` (frequency) and ``(0, 1]``
        (damping ratio); when given they are used as they are. Larger values are refused as
        percent given for a ratio.
    frequency_uncertainty, damping_ratio_uncertainty : float or array_like, optional, keyword-only
        Stated per-point relative standard uncertainty [-] (e.g. from
        :class:`~iwan_element.AmplitudeCurve`), in the same ranges; the noise is never taken
        below it.
    predicted_zeta0 : float, keyword-only
        Viscous damping ratio already in the prediction [-], ``>= 0``.
    alpha, ambiguity, max_effects : keyword-only
        As in :func:`~iwan_element.diagnose`.
    between_tests : bool, keyword-only
        True when the measurement comes from another test than the one the model was
        calibrated on (a shaker sweep against a hammer-calibrated model, another day): the
        linear properties then differ between the tests (shaker or stinger attachment,
        suspension, temperature, re-tightening), so constant relative offsets of the
        frequency and of the damping ratio (the other test's curves are the model's times
        ``1 + offset``) are fitted as nuisances with every model (reported in
        ``details["between_tests"]``, never named, not carried by :meth:`augment`); an
        effect whose modal form is a constant floor (viscous damping) cannot be told from a
        between-test difference of the linear damping and is not tested. Default False (same
        test, or a synthetic curve).
    effect_prior : float or dict, optional, keyword-only
        Prior probability that each candidate effect is present, as in
        :func:`~iwan_element.diagnose` (default: even prior odds for the plain prediction).
    evidence : {"laplace", "nested"}, keyword-only
        How each explanation's evidence is computed: the Laplace approximation (default),
        or nested sampling as well (:mod:`~iwan_element.diagnose.nested`, needs the
        ``nested`` extra), which then gives the probabilities.
    nested : dict, optional, keyword-only
        Options of the nested sampler (``sampler``, ``nlive``, ``dlogz``, ``rng``).

    Returns
    -------
    VibrationDiagnosis

    Raises
    ------
    ValueError
        Non-positive or non-finite values, unequal lengths, a frequency that is about
        ``2 pi`` times the prediction (rad/s for Hz) or the other way round, damping ratios
        that look like percent (one >= 1, or none below 0.05), or an option out of range.
    """
    amplitude, frequency_uncertainty, damping_ratio_uncertainty, n, X, fm, zm, fp, zp = _arrays(
        amplitude,
        frequency,
        damping_ratio,
        predicted_frequency,
        predicted_damping_ratio,
        frequency_uncertainty,
        damping_ratio_uncertainty,
    )
    zeta0 = check_scalar("predicted_zeta0", predicted_zeta0, low=0.0)
    alpha = check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True)
    ambiguity = check_scalar("ambiguity", ambiguity, low=0.0)
    max_effects = check_int("max_effects", max_effects, 1)
    rf0, rz0, sf, sz, src_f, src_z, warns = _noise_levels(
        X,
        fm,
        zm,
        fp,
        zp,
        n,
        (frequency_noise, damping_ratio_noise),
        (frequency_uncertainty, damping_ratio_uncertainty),
    )
    if not isinstance(between_tests, (bool, np.bool_)):
        raise ValueError(f"between_tests must be True or False, got {between_tests!r}")
    vib = _Vib(X, fm, zm, fp, zp, zeta0, sf, sz, bool(between_tests))
    z_b, chi_b = vib.fit_nuisance()
    err_b = vib.error((), z_b)
    cands = tuple(
        c for c in vibration_candidates() if not (between_tests and EFFECTS[c].modal_floor)
    )

    base, prior, nest, sel = _select(
        vib, cands, chi_b, z_b, n, alpha, max_effects, ambiguity, effect_prior, evidence, nested
    )
    fits, expl, rule_named = _explanations(vib, sel, base, err_b, n, prior, nest, warns)
    _adopt_top(vib, sel, fits, expl, n)
    if vib.nn:  # where: what is left after the between-test offsets
        f_b, z_b_curve = vib.curves((), z_b)
        rf0, rz0 = np.log(fm / f_b), np.log(zm / z_b_curve)
    return _vib_result(
        vib,
        sel,
        chi_b,
        err_b,
        rf0,
        rz0,
        warns,
        alpha,
        f"{src_f}; {src_z}",
        cands,
        tuple(expl),
        rule_named,
    )


def _select(
    vib, cands, chi_b, z_b, n, alpha, max_effects, ambiguity, effect_prior, evidence, nested
):
    """The stepwise selection over the candidates from the base state: ``(base, prior,
    nested options, selection)``.
    """

    def fit_candidate(cur, name):
        names = cur["names"] + (name,)
        res = vib.fit(names, cur["state"])
        return {
            "names": names,
            "chi2": 2 * float(res.cost),
            "state": res.x,
            "q": len(EFFECTS[name].modal_specs),
            "error": vib.error(names, res.x),
        }

    base = {"names": (), "chi2": chi_b, "q": 0, "state": z_b}
    prior = check_effect_prior(effect_prior, cands)
    nest = nested_options(evidence, nested)
    sel = stepwise_select(
        fit_candidate,
        cands,
        base,
        tau=1.0,
        n_eff=2.0 * n,
        alpha=alpha,
        max_effects=max_effects,
        ambiguity=ambiguity,
        first_step=True,
    )
    return base, prior, nest, sel


def _arrays(
    amplitude,
    frequency,
    damping_ratio,
    predicted_frequency,
    predicted_damping_ratio,
    frequency_uncertainty,
    damping_ratio_uncertainty,
):
    """The checked measurement and prediction: ``(amplitude as given or the curve's, the
    stated uncertainties, n, X, fm, zm, fp, zp)``.
    """
    for arg, v in (
        ("frequency_uncertainty", frequency_uncertainty),
        ("damping_ratio_uncertainty", damping_ratio_uncertainty),
    ):
        if v is not None:  # the caller's (not a curve's own scatter, which may be wide)
            _relative(arg, arg.rsplit("_", 1)[0], finite_array(arg, v, ndim=None))
    amplitude, frequency, damping_ratio, frequency_uncertainty, damping_ratio_uncertainty = (
        _measurement(
            amplitude, frequency, damping_ratio, frequency_uncertainty, damping_ratio_uncertainty
        )
    )
    n, a = _inputs(
        amplitude, frequency, damping_ratio, predicted_frequency, predicted_damping_ratio
    )
    X, fm, zm, fp, zp = (
        a[k]
        for k in (
            "amplitude",
            "frequency",
            "damping_ratio",
            "predicted_frequency",
            "predicted_damping_ratio",
        )
    )
    return amplitude, frequency_uncertainty, damping_ratio_uncertainty, n, X, fm, zm, fp, zp


def _noise_levels(X, fm, zm, fp, zp, n, noise, uncertainty):
    """The log residuals before any effect, each curve's noise and its source, and the
    warning when the noise rests on too few amplitudes.
    """
    frequency_noise, damping_ratio_noise = noise
    frequency_uncertainty, damping_ratio_uncertainty = uncertainty
    o = np.argsort(X)
    rf0, rz0 = np.log(fm / fp), np.log(zm / zp)
    warns = []
    sf, src_f = _curve_level("frequency", rf0[o], frequency_noise, frequency_uncertainty, n)
    sz, src_z = _curve_level(
        "damping_ratio", rz0[o], damping_ratio_noise, damping_ratio_uncertainty, n
    )
    if (frequency_noise is None or damping_ratio_noise is None) and n < 12:
        warns.append(
            f"only {n} amplitudes: the noise taken from their scatter is uncertain "
            "(state the per-point uncertainty or the noise levels)"
        )
    return rf0, rz0, sf, sz, src_f, src_z, warns


def _explanations(vib, sel, base, err_b, n, prior, nest, warns):
    """The explanations fitted, ranked by probability, without those that raise the
    unweighted mismatch (each such one a warning): ``(fits, ranked, the rule's naming)``.
    """
    sf, sz = vib.sf, vib.sz
    # never name a set of effects that leaves the unweighted mismatch higher than before (by
    # more than a tenth of the noise: a hidden frequency effect changes the damping-dominated
    # unweighted mismatch by less than the damping noise's own scatter)
    tol = 0.1 * math.sqrt(0.5 * (sf**2 + sz**2))
    fits = collect(base, sel.steps)
    raises = {k for k, f in fits.items() if k and vib.error(f[0], f[3]) > err_b + tol}
    expl = rank(
        {k: f for k, f in fits.items() if k not in raises},
        tau=1.0,
        n_eff=2.0 * n,
        prior=prior,
        evaluate=lambda stack, z: evaluate(vib, stack, z),
        nested=nest,
    )
    rule_named = tuple(sel.named)
    if sel.named and key(sel.named) in raises:
        warns.append(
            f"{' + '.join(sel.named)} lowers the noise-weighted misfit but raises the "
            "mismatch; not named"
        )
    for k in sorted(raises - {key(sel.named)}):
        if fits[k][1] < min(f[1] for kk, f in fits.items() if kk not in raises):
            warns.append(
                f"{' + '.join(k)} lowers the noise-weighted misfit but raises the "
                "mismatch; not considered"
            )
    return fits, expl, rule_named


def _adopt_top(vib, sel, fits, expl, n):
    """Name the most probable explanation when the rule named another (in ``sel``)."""
    top = expl[0]
    if key(top.stack) != key(sel.named):
        f = fits[top.effects]
        sel.named, sel.ambiguous = list(top.stack), ()
        sel.final = {"names": f[0], "chi2": f[1], "q": f[2] - vib.nn, "state": f[3]}
        sel.p_after = misfit_p(f[1], 1.0, 2.0 * n, f[2] - vib.nn)


def _vib_result(
    vib,
    sel,
    chi_b,
    err_b,
    rf0,
    rz0,
    warns,
    alpha,
    noise_from,
    cands,
    explanations=(),
    rule_named=(),
):
    names, z = sel.final["names"], sel.final["state"]
    params = vib.decode(names, z)
    f_new, z_new = vib.curves(names, z)
    misfit = sel.p_before < alpha
    if misfit and sel.p_after < alpha:
        warns.append(
            "mismatch beyond the noise remains"
            + (
                f" after {' + '.join(sel.named)}"
                if sel.named
                else f"; no candidate ({', '.join(cands)}) explains it"
            )
            + _left(vib.X, np.log(vib.fm / f_new), np.log(vib.zm / z_new), vib.sf, vib.sz)
        )
    bound_warns, at_bound = _at_upper_bound(vib, names, z)
    warns.extend(bound_warns)
    steps = _steps(sel)
    cov, se, nuis_std = _covariance(vib, names, z, sel.final["chi2"])
    ro = lambda a: (a.setflags(write=False), a)[1]  # noqa: E731
    details = _details(
        vib, sel, names, se, at_bound, rule_named, chi_b, rf0, rz0, f_new, z_new, alpha, noise_from
    )
    if vib.nn:
        df, dz = vib.nuisance(z)
        details["between_tests"] = {
            "frequency_offset": df,
            "frequency_offset_stderr": nuis_std[0],
            "damping_offset": dz,
            "damping_offset_stderr": nuis_std[1],
            "untested": [c for c in vibration_candidates() if c not in cands],
        }
    return VibrationDiagnosis(
        effect=sel.named[0] if sel.named else "none",
        effects=tuple(sel.named),
        ambiguous_with=sel.ambiguous,
        where=_where(vib.X, rf0, rz0, vib.sf, vib.sz, misfit),
        parameters=params,
        error_before=err_b,
        error_after=vib.error(names, z),
        noise_level=math.sqrt(0.5 * (vib.sf**2 + vib.sz**2)),
        frequency_noise=vib.sf,
        damping_ratio_noise=vib.sz,
        amplitude=ro(vib.X),
        frequency=ro(vib.fm),
        damping_ratio=ro(vib.zm),
        predicted_frequency=ro(vib.fp),
        predicted_damping_ratio=ro(vib.zp),
        model_frequency=ro(f_new),
        model_damping_ratio=ro(z_new),
        steps=tuple(json_safe(s) for s in steps),
        warnings=tuple(warns),
        details=json_safe(details),
        covariance=None if cov is None else ro(cov),
        explanations=explanations,
    )
