"""Benchmark: whether the diagnosis' probabilities are calibrated on cases with a known answer.

Generated cases with a known truth, held out from the tests (other joints, envelopes and
seeds than ``tests/_diagnosis_cases.py``):

* **loops** (:func:`iwan_element.diagnose`): the two joints of ``bench_diagnosis.py``, three
  amplitude envelopes, a force offset; one hidden effect of the six loop candidates at a
  size from a grid of 1/8 to 4 x "noticeable" (the project's unit for each diagnosis: for
  loops the RMS of the force the effect adds is twice the noise RMS, so 1/4 to 8 x the
  noise: from below the noise to dominant), at two noise levels (0.2 % and 1 % of Fs), each
  on one of two record lengths (1-3 cycles of 64 samples per amplitude, or 3-6 of 128;
  alternating over the sizes, so every effect meets both lengths at both noise levels); and
  as many records with no effect (the default prior gives the plain joint even odds, and so
  does the case mix);
* **vibration curves** (:func:`iwan_element.diagnose_vibration`): the modal joint of
  ``bench_vibration_diagnosis.py``, curves from the time-domain elements (not the modal
  forms the diagnosis fits), one hidden effect of the four with a modal form at a size from
  the grid (noticeable: an RMS change of the noise-normalised curves of 4, as in
  ``bench_vibration_diagnosis.py``; so 1/2 to 16 x the noise), two noise levels
  (damping 1 % and 3 %) and two lengths (12 and 36 amplitudes); and as many without.

Scored (every case):

* the **reliability table** of the stated probability of the most probable explanation
  against the fraction of cases where it is the truth (bins of 0.1), and of every
  candidate effect's marginal probability against whether it is present;
* the **Brier score** of those two (mean squared difference of probability and outcome);
* the **log score** ``-ln p(truth)`` (``p`` the probability of the true explanation,
  clipped to ``[1e-3, 1 - 1e-3]``) of the probabilities and of today's yes/no answer (the
  stepwise rule: probability 1 for what it names), over all cases and in the **transition
  zone**: hidden effects of 1/4 to 2 x noticeable, where the rule's answer turns from miss
  to hit; and how many cases there the probability warned (below 0.9) where the yes/no
  answer was wrong;
* the **cost** per record: CPU time of the diagnosis with and without the probabilities
  (``diagnose(..., probabilities=False)`` on the same loop records, ``--timing N`` of them).

    nice -n 10 python benchmarks/bench_diagnosis_calibration.py [--repeats 1] [--timing 12]
        [--only loops|vibration] [--json out.json] [--stride K] [--nested N]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import _vibration_cases as vc
from _diagnosis_cases import _calibrate

from iwan_element import AmplitudeCurve, IwanJoint, IwanParameters, make_effect
from iwan_element.diagnose import diagnose, diagnose_vibration, simulate_element_test
from iwan_element.diagnose.loops.diagnosis import loop_candidates
from iwan_element.diagnose.vibration.diagnosis import vibration_candidates

JOINTS = {
    "stiff": IwanParameters(2500.0, 4e6, -0.3, 0.6),
    "soft": IwanParameters(400.0, 5e5, -0.7, 0.05),
}
ENVELOPES = {
    "constant": ("steps", (0.4, 0.9, 1.7)),
    "ramped": ("linear", (0.15, 1.9)),
    "triangular": ("linear", (0.3, 1.6, 0.3)),
}
SHAPES = {
    "viscous_damping": ("c", {}),
    "pinning_stiffness": ("k_p", {"delta": 0.6}),
    "backlash": ("gap", {}),
    "slip_degradation": ("rate", {}),
    "asymmetric_slip": ("asymmetry", {}),
    "breakaway": ("ratio", {}),
}
SIZES = (0.125, 0.25, 0.5, 1.0, 2.0, 4.0)  # x noticeable
LOOP_NOTICEABLE = 2.0  # added force RMS / noise RMS
LOOP_NOISE = (0.002, 0.01)  # force noise / Fs
#: cycles per amplitude (per envelope: constant, ramped, triangular) and samples per cycle
LENGTHS = {
    "short": ({"constant": 1, "ramped": 3, "triangular": 2}, 64),
    "long": ({"constant": 3, "ramped": 6, "triangular": 4}, 128),
}
ZONE = (0.25, 2.0)  # the transition zone's sizes
VIB_P = IwanParameters(250.0, 1.8e5, -0.35, 0.5)
VIB_NOISE = (0.01, 0.03)  # damping noise (frequency: 1e-4)
VIB_LENGTHS = (12, 36)
CLIP = 1e-3
RELIABILITY_EDGES = np.linspace(0.0, 1.0, 11)  # bins of the stated probability


def _loop_record(p, env, length, el, noise, seed):
    kind, amps = ENVELOPES[env]
    cyc, spc = LENGTHS[length]
    cyc = cyc[env]
    rng = np.random.default_rng(seed)
    d = simulate_element_test(
        el,
        np.array(amps) * p.phi_max,
        envelope=kind,
        cycles=cyc,
        samples_per_cycle=spc,
        force_noise=noise * p.Fs,
        seed=seed,
        force_offset=rng.uniform(50, 300) * rng.choice([-1, 1]),
        rest_samples=10,
    )
    return d.t, d.u, d.F


def _element(p, name, x):
    key, extra = SHAPES[name]
    extra = {k: v * p.phi_max for k, v in extra.items()}
    return make_effect(name, IwanJoint(p), **{key: x}, **extra)


def _parameter(p, env, length, name, target):
    """Effect parameter whose added force RMS on the drive is ``target`` [N]."""
    kind, amps = ENVELOPES[env]
    cyc, spc = LENGTHS[length]
    cyc = cyc[env]
    d = simulate_element_test(
        IwanJoint(p), np.array(amps) * p.phi_max, envelope=kind, cycles=cyc, samples_per_cycle=spc
    )
    v = np.gradient(d.u, d.t)
    base = IwanJoint(p).force_history(d.u)
    key = SHAPES[name][0]

    def rms(x):
        el = _element(p, name, 1.0 + x if key == "ratio" else x)
        return float(np.sqrt(np.mean((el.force_history(d.u, v) - base) ** 2)))

    x0 = {
        "c": 0.1 * p.Fs / p.phi_max,
        "k_p": 0.01 * p.KT,
        "gap": 0.01 * p.phi_max,
        "rate": 0.01 / (p.Fs * p.phi_max),
        "asymmetry": 0.01,
        "ratio": 0.05,
    }[key]
    x = _calibrate(rms, x0, target)
    return 1.0 + x if key == "ratio" else x


def loop_cases(repeats: int):
    """(kind, joint, envelope, length, noise, effect or None, size, seed) of every loop case."""
    cases, seed = [], 50_000
    joints, envs = list(JOINTS), list(ENVELOPES)
    lengths = list(LENGTHS)
    for rep in range(repeats):
        for name in SHAPES:
            for ks, size in enumerate(SIZES):
                for kn, noise in enumerate(LOOP_NOISE):  # both noises, both lengths
                    length = lengths[(ks + kn + rep) % 2]
                    seed += 1
                    cases.append(
                        ("loop", joints[seed % 2], envs[seed % 3], length, noise, name, size, seed)
                    )
                    seed += 1  # and one without effect
                    cases.append(
                        ("loop", joints[seed % 2], envs[seed % 3], length, noise, None, 0.0, seed)
                    )
    return cases


def vibration_cases(repeats: int):
    cases, seed = [], 70_000
    for _ in range(repeats):
        for name in vibration_candidates():
            for size in SIZES:
                for noise in VIB_NOISE:
                    for n in VIB_LENGTHS:
                        seed += 1
                        cases.append(("vibration", name, size, noise, n, seed))
                        seed += 1
                        cases.append(("vibration", None, 0.0, noise, n, seed))
    return cases


def run_loop(case, *, probabilities=True):
    _, joint, env, length, noise, name, size, seed = case
    p = JOINTS[joint]
    if name is None:
        el = IwanJoint(p)
    else:
        el = _element(
            p, name, _parameter(p, env, length, name, size * LOOP_NOTICEABLE * noise * p.Fs)
        )
    t, u, F = _loop_record(p, env, length, el, noise, seed)
    c0 = time.process_time()
    d = diagnose(t, u, F, probabilities=probabilities)
    return d, time.process_time() - c0


_VIB_BASE = {}


def run_vibration(case):
    _, name, size, z_noise, n, seed = case
    vc.K_INF = 1.2e5
    X = np.geomspace(0.01, 1.2, n) * VIB_P.phi_max
    if n not in _VIB_BASE:
        _VIB_BASE[n] = vc.element_curve(X, VIB_P)
    X, fm, zm, fp, zp, _ = vc.seeded_case(
        seed, name, size, P=VIB_P, X=X, base=_VIB_BASE[n], z_noise=z_noise
    )
    curve = AmplitudeCurve(
        X, fm, zm, frequency_std=vc.F_NOISE * fm, damping_ratio_std=z_noise * zm, method="seeded"
    )
    c0 = time.process_time()
    d = diagnose_vibration(
        curve, predicted_frequency=fp, predicted_damping_ratio=zp, predicted_zeta0=vc.ZETA0
    )
    return d, time.process_time() - c0


def score(d, truth, candidates):
    """Per case: the probability of the truth, the top explanation's probability and
    whether it is the truth, each candidate's marginal probability and presence, and the
    rule's yes/no answer.
    """
    probs = d.probabilities
    truth = tuple(sorted(truth))
    top = max(probs, key=probs.get)
    rule = tuple(sorted(d.details.get("rule_named", d.effects)))
    return {
        "p_truth": float(probs.get(truth, 0.0)),
        "p_top": float(probs[top]),
        "top_right": top == truth,
        "rule_right": rule == truth,
        "named": list(d.effects),
        "rule": list(rule),
        "effects": {c: (float(d.effect_probability(c)), c in truth) for c in candidates},
    }


def reliability(pairs, edges=RELIABILITY_EDGES):
    """Rows (bin, count, mean stated, fraction true) of (probability, outcome) pairs."""
    p = np.array([a for a, _ in pairs])
    y = np.array([float(b) for _, b in pairs])
    rows = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (p >= lo) & ((p < hi) if hi < 1 else (p <= hi))
        if m.any():
            rows.append((lo, hi, int(m.sum()), float(p[m].mean()), float(y[m].mean())))
    return rows


def brier(pairs) -> float:
    return float(np.mean([(a - float(b)) ** 2 for a, b in pairs]))


def log_score(ps) -> float:
    return float(np.mean([-math.log(min(max(p, CLIP), 1 - CLIP)) for p in ps]))


def summary(rows, label):
    out = {"label": label, "cases": len(rows)}
    top = [(r["p_top"], r["top_right"]) for r in rows]
    eff = [pe for r in rows for pe in r["effects"].values()]
    out["reliability_top"] = reliability(top)
    out["reliability_effects"] = reliability(eff)
    out["brier_top"] = brier(top)
    out["brier_top_rule"] = brier([(1.0, r["rule_right"]) for r in rows])
    out["brier_effects"] = brier(eff)
    out["brier_effects_rule"] = brier(
        [(float(c in r["rule"]), pres) for r in rows for c, (_, pres) in r["effects"].items()]
    )
    out["log_score"] = log_score([r["p_truth"] for r in rows])
    out["log_score_rule"] = log_score([float(r["rule_right"]) for r in rows])
    out["named_right"] = int(sum(r["top_right"] for r in rows))
    out["rule_right"] = int(sum(r["rule_right"] for r in rows))
    out["warned_where_rule_wrong"] = int(
        sum(1 for r in rows if not r["rule_right"] and r["p_top"] <= 0.9)
    )
    out["rule_wrong"] = int(sum(1 for r in rows if not r["rule_right"]))
    return out


def print_summary(s):
    print(f"\n== {s['label']}: {s['cases']} cases")
    for title, key in (
        ("most probable explanation", "reliability_top"),
        ("each candidate effect present", "reliability_effects"),
    ):
        print(f"  reliability, {title}:")
        print("     bin          n   stated   fraction true   |diff|")
        for lo, hi, n, ps, fr in s[key]:
            print(
                f"    {lo:.1f}-{hi:.1f} {n:6d} {ps:8.3f} {fr:12.3f} {abs(ps - fr):10.3f}"
                + ("" if n >= 20 or abs(ps - fr) <= 0.1 else "   (fewer than 20)")
            )
    print(
        f"  Brier (most probable right): probabilities {s['brier_top']:.4f}, yes/no "
        f"{s['brier_top_rule']:.4f}"
    )
    print(
        f"  Brier (each effect present): probabilities {s['brier_effects']:.4f}, yes/no "
        f"{s['brier_effects_rule']:.4f}"
    )
    print(
        f"  log score -ln p(truth): probabilities {s['log_score']:.4f}, yes/no "
        f"{s['log_score_rule']:.4f}"
    )
    print(
        f"  right: most probable {s['named_right']}/{s['cases']}, yes/no rule "
        f"{s['rule_right']}/{s['cases']}; the probability warned (<= 0.9) on "
        f"{s['warned_where_rule_wrong']} of the {s['rule_wrong']} the rule got wrong"
    )


def nested_check(cases):
    """Laplace against nested sampling (dynesty) on vibration cases: per explanation the
    difference of the log evidences and the sampler's stated error, split into explanations
    whose size parameter sits at its "no effect" value (within 1e-3 of the range) and the
    others.
    """
    from iwan_element.effects import EFFECTS

    rows = []
    for case in cases:
        _, name, size, z_noise, n, seed = case
        X = np.geomspace(0.01, 1.2, n) * VIB_P.phi_max
        if n not in _VIB_BASE:
            _VIB_BASE[n] = vc.element_curve(X, VIB_P)
        X, fm, zm, fp, zp, _ = vc.seeded_case(
            seed, name, size, P=VIB_P, X=X, base=_VIB_BASE[n], z_noise=z_noise
        )
        curve = AmplitudeCurve(
            X,
            fm,
            zm,
            frequency_std=vc.F_NOISE * fm,
            damping_ratio_std=z_noise * zm,
            method="seeded",
        )
        d = diagnose_vibration(
            curve,
            predicted_frequency=fp,
            predicted_damping_ratio=zp,
            predicted_zeta0=vc.ZETA0,
            evidence="nested",
            nested={"rng": seed, "nlive": 200},
        )
        for e in d.explanations:
            if not e.effects or not np.isfinite(e.log_evidence_nested):
                continue
            at_zero, k = False, 0
            for nm in e.stack:
                for sp in EFFECTS[nm].modal_specs:
                    lo, hi = sp.prior_range
                    if sp.neutral is not None and abs(e.theta[k] - sp.neutral) < 1e-3 * (hi - lo):
                        at_zero = True
                    k += 1
            rows.append(
                (
                    name,
                    size,
                    e.effects,
                    e.n_params,
                    at_zero,
                    e.log_evidence_laplace - e.log_evidence_nested,
                    e.nested_error,
                )
            )
    print("\nLaplace against nested sampling (vibration; ln Z difference, sampler's error):")
    for label, sel in (
        ("effect at zero size", [r for r in rows if r[4]]),
        ("effect fitted away from zero", [r for r in rows if not r[4]]),
    ):
        if not sel:
            continue
        dz = np.array([r[5] for r in sel])
        err = np.array([r[6] for r in sel])
        within = int(np.sum(np.abs(dz) <= 3 * np.maximum(err, 0.05)))
        print(
            f"  {label}: {len(sel)} explanations, median |dlnZ| {np.median(np.abs(dz)):.3f},"
            f" max {np.max(np.abs(dz)):.3f}, within 3 errors {within}/{len(sel)}"
        )
        for eff in sorted({r[2] for r in sel}):
            d_e = np.array([r[5] for r in sel if r[2] == eff])
            print(
                f"    {' + '.join(eff):<20} n={d_e.size:3d} mean {d_e.mean():+.3f} "
                f"max |.| {np.max(np.abs(d_e)):.3f}"
            )
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument(
        "--timing",
        type=int,
        default=12,
        help="loop records diagnosed again without the probabilities",
    )
    ap.add_argument("--only", choices=("loops", "vibration"))
    ap.add_argument("--json", type=Path)
    ap.add_argument("--stride", type=int, default=1, help="every STRIDE-th case (a pilot)")
    ap.add_argument(
        "--nested",
        type=int,
        default=0,
        help="vibration cases whose evidences are also computed by nested "
        "sampling (dynesty), Laplace against it",
    )
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    rows, cost = [], {"with": [], "without": []}
    cases = ([] if a.only == "vibration" else loop_cases(a.repeats)) + (
        [] if a.only == "loops" else vibration_cases(a.repeats)
    )
    cases = cases[:: a.stride]
    lc, vcands = loop_candidates(), vibration_candidates()
    for i, case in enumerate(cases):
        if case[0] == "loop":
            d, cpu = run_loop(case)
            name, size, cands = case[5], case[6], lc
            cost["with"].append(cpu)
        else:
            d, cpu = run_vibration(case)
            name, size, cands = case[1], case[2], vcands
        r = score(d, () if name is None else (name,), cands)
        r.update(kind=case[0], effect=name, size=size, cpu=cpu, case=list(case[1:]))
        rows.append(r)
        print(
            f"{i + 1:4d}/{len(cases)} {case[0]:<9} {str(name):<18} {size:5.2f} "
            f"p(truth) {r['p_truth']:.3f} top {r['p_top']:.3f} {'ok ' if r['top_right'] else 'BAD'}"
            f" rule {'ok ' if r['rule_right'] else 'bad'} {cpu:6.2f} s",
            flush=True,
        )
    if a.nested:
        vib = [c for c in cases if c[0] == "vibration"]
        nested_check(vib[:: max(1, len(vib) // a.nested)][: a.nested])
    loops = [c for c in cases if c[0] == "loop"]
    for case in loops[: a.timing]:
        _, cpu = run_loop(case, probabilities=False)
        cost["without"].append(cpu)
    zone = [r for r in rows if r["effect"] is not None and ZONE[0] <= r["size"] <= ZONE[1]]
    out = [summary(rows, "all cases")]
    for kind in ("loop", "vibration"):
        sel = [r for r in rows if r["kind"] == kind]
        if sel:
            out.append(summary(sel, f"{kind} cases"))
    if zone:
        out.append(
            summary(zone, f"transition zone (hidden effect {ZONE[0]:g}-{ZONE[1]:g} x noticeable)")
        )
    for s in out:
        print_summary(s)
    if cost["with"]:
        k = len(cost["without"])
        w, wo = np.array(cost["with"][:k]), np.array(cost["without"])
        print(
            f"\ncost per loop record (CPU, first {k} records): with probabilities median "
            f"{np.median(w):.2f} s (max {w.max():.2f}), without {np.median(wo):.2f} s "
            f"(max {wo.max():.2f}); ratio of totals {w.sum() / wo.sum():.2f}"
        )
        print(
            f"all {len(cost['with'])} loop records with probabilities: median "
            f"{np.median(cost['with']):.2f} s, max {np.max(cost['with']):.2f} s"
        )
    print(f"wall time {time.perf_counter() - t0:.0f} s")
    if a.json:
        a.json.write_text(
            json.dumps({"summaries": out, "rows": rows, "cost": cost}, default=float, indent=1)
        )


if __name__ == "__main__":
    main()
