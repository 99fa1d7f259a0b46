"""Loop diagnosis: what the four-parameter Iwan model misses in a displacement-driven test.

:func:`diagnose` works on a record (time, displacement, force):

1. the joint's unloaded state is the rest position the record starts from: the displacement
   offset is the mean displacement before the motion starts; the force offset is fitted with
   every model (linear, eliminated in closed form with ``Fs``), the rest samples (where the
   unloaded joint carries no force) being part of the fitted data. Offsets are nuisance
   parameters: reported, never named as an effect;
2. the force noise and its correlation time are estimated from the record itself
   (:func:`iwan_element.identify.loops.noise.estimate_noise`; no repeated cycles needed, so
   ramped, swept and random-amplitude protocols work), unless ``noise`` is given;
3. the plain Iwan model is fitted, then effects of :data:`~iwan_element.EFFECTS` are tried
   one after the other with the selection rule of :mod:`iwan_element.diagnose.selection`
   (information criterion on the noise-normalised residual with ``n / tau`` independent
   samples, an "explains little" guard, and "no effect" when the rest is noise);
4. the augmented model is refitted on the whole record and its uncertainty stated (delta
   method, residual variance inflated by the residual's correlation time).

The stages and their modules, each reading only what the one before returned: prepare
(:mod:`.prepare`, :class:`~.prepare.PreparedRecord`), noise (:mod:`.noise`,
:class:`~.noise.NoiseLevel`), fit (:mod:`.fit`), select (:func:`select`, the rule of
:mod:`..selection.rule`; :class:`LoopSelection`) and report (:mod:`.report`,
:class:`~.result.Diagnosis`). An effect the record cannot test (its class' ``needs``) is
reported as untestable, not tried.

A property of the test rig is not an effect of the joint: ``lowpass`` removes structural
ringing of the rig (e.g. the 40-50 Hz ringing of the ARTS damper rig after each break-away),
with a zero-phase Butterworth filter on both channels, stating the reason in the result.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ...base.progress import complete, finish, progress_bar, tick
from ...base.threads import one_blas_thread
from ...base.validation import check_int, check_scalar
from ...effects import EFFECTS
from ...effects.engine.evaluate import order_stack, stack_ok
from ..selection.nested import nested_options
from ..selection.probabilities import check_effect_prior, key, rank
from ..selection.rule import SelectionResult, misfit_p, stepwise_select
from .evidence import collect_fits, loop_evaluator
from .fit import StackFitter, final_fits, fit_base, record_force, z_start
from .locate import _check_candidates
from .noise import NoiseLevel, noise_level, pure_noise
from .prepare import (
    PreparedRecord,
    check_record,
    dissipation_scale,
    prepare_record,
    record_cycles,
    untestable,
)
from .report import assemble
from .result import Diagnosis

__all__ = ["diagnose", "loop_candidates", "LoopSelection", "select"]

log = logging.getLogger(__name__)


def loop_candidates() -> tuple:
    """Names of the effects :func:`diagnose` tries by default, in the order they are reported:
    every effect in :data:`~iwan_element.EFFECTS` that declares a ``loop_rank``, by that rank
    (read when called, as :func:`~iwan_element.diagnose.vibration.vibration_candidates` is, so
    an effect registered later joins too).
    """
    return tuple(
        sorted(
            (n for n, c in EFFECTS.items() if c.loop_rank is not None),
            key=lambda n: EFFECTS[n].loop_rank,
        )
    )


@dataclass(frozen=True, eq=False)
class LoopSelection:
    """What the selection stage decided on a record.

    Attributes
    ----------
    named : tuple of str
        Effects named, in the order named (empty when the record is noise).
    ambiguous : tuple of str
        Effects nearly as good as the first one named.
    steps : list
        The rule's step table (:func:`~.selection.stepwise_select`).
    final : dict or None
        The named stack's fitted row, None when nothing is named.
    p_before, p_after : float
        Misfit-test probabilities of the plain and of the selected model.
    untestable : dict
        ``{effect: why}`` for candidates the record cannot test.
    cycles : sequence of Cycle
        The record's load cycles (for the report's location of the misfit).
    noise : NoiseLevel
        The noise the fits were scored against (re-read from the selected model's residual).
    noise_only : bool
        The force is indistinguishable from noise: nothing is named or identified.
    """

    named: tuple
    ambiguous: tuple
    steps: list
    final: dict | None
    p_before: float
    p_after: float
    untestable: dict
    cycles: Sequence
    noise: NoiseLevel
    noise_only: bool
    candidates: tuple = ()
    explanations: tuple = ()
    rule_named: tuple = ()


def diagnose(
    t,
    u,
    F,
    *,
    candidates=None,
    max_effects: int = 3,
    noise: float | None = None,
    alpha: float = 1e-3,
    ambiguity: float = 10.0,
    max_samples: int = 1500,
    lowpass: float | None = None,
    seed=0,
    progress: bool = False,
    effect_prior=None,
    probabilities: bool = True,
    evidence: str = "laplace",
    nested=None,
) -> Diagnosis:
    """Find what the four-parameter Iwan model misses in a displacement-driven test.

    See the module docstring for the procedure.

    Parameters
    ----------
    t : array_like, shape (n,), or None
        Time [s], strictly increasing. Needed for velocity-dependent effects and ``lowpass``;
        with ``None`` viscous damping is reported as untestable. Not modified.
    u, F : array_like, shape (n,)
        Measured displacement [m] and force [N], ``n >= 40``, starting at rest (any sensor
        zero offsets are absorbed as nuisance parameters). Not modified.
    candidates : sequence of str, optional, keyword-only
        Effects to try (default :func:`loop_candidates`).
    max_effects : int, keyword-only
        Most effects named, ``>= 1`` (default 3: a real damper can show a gap, a
        direction-dependent grip and break-away at once; each must pass the selection
        rule on top of the others, so a record that needs fewer names fewer).
    noise : float, optional, keyword-only
        Force noise standard deviation [N], ``> 1e-9 max|F|`` and in ``[1e-100, 1e100]``,
        taken as white. Default: estimated from the record.
    alpha : float, keyword-only
        Level of the "rest is noise" test, in ``(0, 0.5)`` (default 1e-3).
    ambiguity : float, keyword-only
        Criterion difference below which another effect counts as nearly as good, ``>= 0``.
    max_samples : int, keyword-only
        Samples scored per model (evenly spaced; every turning point is kept), ``>= 100``.
    lowpass : float, optional, keyword-only
        Cut-off [Hz] of a zero-phase low-pass applied to both channels before fitting, to
        remove test-rig dynamics (structural ringing) that is not joint behaviour; in
        ``(0, sample rate / 2)``. Needs ``t``. Default: none.
    seed : int or numpy.random.Generator, keyword-only
        Seed of the starting loop fit's random starts.
    progress : bool, keyword-only
        Show a tqdm progress bar counting the model fits (the base fit, then each
        candidate stack), with the stack being fitted (needs tqdm).
    effect_prior : float or dict, optional, keyword-only
        Prior probability that each candidate effect is present (independently), in
        ``(0, 1)``, or ``{effect: probability}`` for some of them: the prior model
        probabilities of the explanations (:mod:`~iwan_element.diagnose.probabilities`).
        Default ``1 - 2**(-1/K)`` for ``K`` testable candidates: even prior odds that the
        plain joint is enough.
    probabilities : bool, keyword-only
        Compute the explanations' probabilities (default True). False: the stepwise rule
        alone names the effects, the single effects are fitted only where the rule needs
        them, and ``explanations`` is empty (today's cost, for comparison).
    evidence : {"laplace", "nested"}, keyword-only
        How each explanation's evidence is computed: the Laplace approximation (default),
        or nested sampling as well (:mod:`~iwan_element.diagnose.nested`, the ``nested``
        extra; minutes per record), which then gives the probabilities.
    nested : dict, optional, keyword-only
        Options of the nested sampler (``sampler``, ``nlive``, ``dlogz``, ``rng``).

    Returns
    -------
    Diagnosis

    Raises
    ------
    ValueError
        Bad arrays (NaN, unequal lengths, fewer than 40 samples, no motion), a noise level
        below the record's resolution, or an option out of range.
    """
    t_start = time.perf_counter()
    tt, uu, FF, n, noise, lp = check_record(t, u, F, noise, lowpass)
    cand = _check_candidates(candidates, loop_candidates())
    opts = dict(
        alpha=check_scalar("alpha", alpha, low=0.0, high=0.5, low_open=True, high_open=True),
        ambiguity=check_scalar("ambiguity", ambiguity, low=0.0),
        max_effects=check_int("max_effects", max_effects, 1),
    )
    max_samples = check_int("max_samples", max_samples, 100)
    check_effect_prior(effect_prior, cand)  # a bad prior is refused before any fit
    nest = nested_options(evidence, nested)
    bar = None
    try:
        with one_blas_thread():  # tall, narrow least squares: threads only spin
            rec = prepare_record(tt, uu, FF, n, lp, max_samples)
            # the budget, fixed before the first fit: the base fit, then per round every
            # testable candidate, and the pairs; the fits the selection does not need are
            # counted done when it stops
            n_test = sum(1 for c in cand if c not in untestable(rec, cand))
            budget = 1 + n_test * (opts["max_effects"] + 1)
            bar = progress_bar(progress, total=budget, desc="diagnose", unit="fit")
            fitter = StackFitter(rec)
            base = fit_base(fitter, rec, seed=seed)
            tick(bar, text="Iwan")
            nl = noise_level(rec, rec.F_raw - record_force(base, rec.uj, rec.v)[0], noise)
            shape_b, _ = base["model"].decode(base["z"])
            fitter.scales["D_ref"] = dissipation_scale(rec.ev, shape_b)
            if not isinstance(probabilities, (bool, np.bool_)):
                raise ValueError(f"probabilities must be True or False, got {probabilities!r}")
            sel = select(
                fitter,
                base,
                rec,
                nl,
                cand,
                opts,
                fixed_noise=noise is not None,
                bar=bar,
                explore=bool(probabilities),
            )
            if probabilities:
                sel = most_probable(sel, base, rec, effect_prior, nest)
            fits = final_fits(
                fitter, rec, base, sel.final, noise_only=sel.noise_only, t_start=t_start
            )
            complete(bar)
            return assemble(rec, sel, fits, opts, t_start)
    finally:
        finish(bar)


def select(
    fitter: StackFitter,
    base: dict,
    rec: PreparedRecord,
    nl: NoiseLevel,
    cand,
    opts,
    *,
    fixed_noise: bool,
    bar=None,
    explore: bool = True,
) -> LoopSelection:
    """The selection stage: the rule over the candidates the record can test, repeated with
    the noise re-read from the residual of the model it selected unless the noise was given
    (a large misfit leaks into the plain fit's residual and inflates the noise estimate, which
    can hide a further effect; the fits are reused).
    """
    why = untestable(rec, cand)
    testable = tuple(c for c in cand if c not in why)
    cycles = record_cycles(rec)
    # a record that is noise can test no effect: the candidates are then fitted only where
    # the rule needs them (never), not for the probabilities
    explore = explore and not pure_noise(
        rec.F[rec.keep], base["ssr"] / nl.sigma**2, nl.sigma, nl.tau_k, nl.n_eff
    )
    for k in range(3):
        fitter.s2 = nl.sigma**2
        base["chi2"] = base["ssr"] / fitter.s2
        rule = _run_rule(fitter, base, rec, testable, nl, opts, bar, explore)
        if fixed_noise or not rule.named or k == 2:
            break
        new = noise_level(
            rec, rec.F_raw - record_force(rule.final["state"], rec.uj, rec.v)[0], None
        )
        if abs(new.sigma - nl.sigma) <= 0.05 * nl.sigma and abs(new.tau - nl.tau) <= 0.1 * nl.tau:
            break
        nl = replace(new, text=new.text + ", from the residual of the model selected")
    noise_only = pure_noise(rec.F[rec.keep], base["chi2"], nl.sigma, nl.tau_k, nl.n_eff)
    named = () if noise_only else tuple(rule.named)
    return LoopSelection(
        named=named,
        ambiguous=() if noise_only else tuple(rule.ambiguous),
        steps=rule.steps,
        final=rule.final["state"] if named else None,
        p_before=rule.p_before,
        p_after=rule.p_after,
        untestable=why,
        cycles=cycles,
        noise=nl,
        noise_only=noise_only,
        candidates=testable,
    )


def most_probable(
    sel: LoopSelection, base: dict, rec: PreparedRecord, effect_prior, nested=None
) -> LoopSelection:
    """The probability stage: every explanation the selection fitted with its posterior
    probability (:mod:`..selection.probabilities`), and the most probable one named (the rule's own
    answer kept in ``rule_named``). A record that is noise names nothing whatever the
    probabilities say (nothing is identified on it).
    """
    nl = sel.noise
    fits = collect_fits(base, sel.steps)
    expl = rank(
        fits,
        tau=nl.tau_k,
        n_eff=nl.n_eff,
        prior=check_effect_prior(
            {k: v for k, v in effect_prior.items() if k in sel.candidates}
            if isinstance(effect_prior, dict)
            else effect_prior,
            sel.candidates,
        ),
        evaluate=loop_evaluator(nl.sigma, float(np.ptp(rec.F)) or 1.0),
        nested=nested,
    )
    top = expl[0]
    if sel.noise_only or key(top.stack) == key(sel.named):
        return replace(sel, explanations=tuple(expl), rule_named=tuple(sel.named))
    row = fits[top.effects][3]
    q = fits[top.effects][2]
    return replace(
        sel,
        named=tuple(top.stack),
        ambiguous=(),
        final=row if top.stack else None,
        p_after=misfit_p(row["chi2"], nl.tau_k, nl.n_eff, q),
        explanations=tuple(expl),
        rule_named=tuple(sel.named),
    )


def _run_rule(fitter, base, rec, testable, nl, opts, bar, explore=True) -> SelectionResult:
    """One run of the shared selection rule over ``testable`` (``bar``: a progress bar
    counting the fits; ``explore``: fit the single effects even when the plain joint's
    misfit is noise, for the probabilities).
    """
    span = float(np.ptp(rec.F)) or 1.0
    nf = fitter.y.size

    def fit_candidate(cur, name):
        names = order_stack(cur["names"] + (name,))
        k = max(len(s.fit_starts) for s in EFFECTS[name].specs)
        starts = [z_start(names, cur["names"], cur["state"]["z"], j) for j in range(k)]
        row = fitter.run(names, starts, scan=name)
        tick(bar, text=" + ".join(names))
        q = len(EFFECTS[name].specs)
        ssr = row["chi2"] * fitter.s2
        return {
            "names": names,
            "chi2": row["chi2"],
            "q": q,
            "state": row,
            "nrmse": math.sqrt(ssr / nf) / span,
            "ratio": math.sqrt(row["chi2"] / max(nf - 5 - q, 1)),
            "message": row["message"],
        }

    base_state = {"names": (), "chi2": base["chi2"], "q": 5, "state": base}
    return stepwise_select(
        fit_candidate,
        testable,
        base_state,
        tau=nl.tau_k,
        n_eff=nl.n_eff,
        allowed=lambda names, c: stack_ok(tuple(names) + (c,)),
        first_step=explore,
        **opts,
    )
