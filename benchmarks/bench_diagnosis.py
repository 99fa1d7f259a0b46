"""Benchmark: whether :func:`iwan_element.diagnose` names the right effect on held-out tests.

Held out from the tests (``tests/_diagnosis_cases.py`` uses the joint (1000 N, 1e6 N/m,
-0.5, 0.2), step protocols of 96 samples per cycle, effects at 6 x noise, seeds < 600):
here two other base joints, three other amplitude envelopes -- constant (steps), ramped and
triangular (``simulate_element_test(envelope="linear")``) -- 128 samples per cycle, seeds
from 1000, and effect sizes from half to three times "noticeable", where noticeable is an
added-force RMS of twice the noise RMS (so 1 to 6 x the noise). Every record also carries a
force offset of 50-300 N and a displacement offset of 5-20 um, and starts after 20 rest
samples. Clean records (offsets only) and pure-noise forces must name nothing.

Pass criteria per hidden effect: the effect named first is the hidden one, and the RMS
residual after is within 1.3 x the noise RMS. Clean records must succeed, pure noise must not.
Every record also checks that ``success``, the report's status column and the warnings
agree (:func:`agree`).

With ``--pairs`` two effects are hidden in each record instead (each calibrated alone to the
size; default sizes 1 and 3): both must be named, in either order, and the residual after
must be within 1.3 x the noise.

    python benchmarks/bench_diagnosis.py [--sizes 0.5 3] [--jobs 2] [--effects ...] [--seed 1000]
                                         [--cases N] [--timing REPEATS] [--pairs [A+B ...]]
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _diagnosis_cases import _calibrate

from iwan_element import IwanJoint, IwanParameters, make_effect
from iwan_element.diagnose import diagnose, simulate_element_test

JOINTS = {
    "stiff": IwanParameters(2500.0, 4e6, -0.3, 0.6),
    "soft": IwanParameters(400.0, 5e5, -0.7, 0.05),
}
ENVELOPES = {
    "constant": ("steps", (0.4, 0.9, 1.7), 2),
    "ramped": ("linear", (0.15, 1.9), 5),
    "triangular": ("linear", (0.3, 1.6, 0.3), 3),
}
SHAPES = {
    "viscous_damping": ("c", {}),
    "pinning_stiffness": ("k_p", {"delta": 0.6}),
    "backlash": ("gap", {}),
    "slip_degradation": ("rate", {}),
    "asymmetric_slip": ("asymmetry", {}),
    "breakaway": ("ratio", {}),
}
#: Two hidden effects per record (``--pairs``): the damper's backlash with direction-dependent
#: slip, and two combinations with a dashpot.
PAIRS = ("backlash+asymmetric_slip", "viscous_damping+asymmetric_slip", "backlash+viscous_damping")
NOISE = 0.004  # force noise / Fs
NOTICEABLE = 2.0  # added-force RMS / noise RMS


def _record(p, env, el, seed, *, pure_noise=False):
    kind, amps, cyc = ENVELOPES[env]
    rng = np.random.default_rng(seed)
    d = simulate_element_test(
        el,
        np.array(amps) * p.phi_max,
        envelope=kind,
        cycles=cyc,
        samples_per_cycle=128,
        force_noise=NOISE * p.Fs,
        seed=seed,
        force_offset=rng.uniform(50, 300) * rng.choice([-1, 1]),
        displacement_offset=rng.uniform(5e-6, 20e-6) * rng.choice([-1, 1]),
        rest_samples=20,
    )
    F = rng.normal(0, NOISE * p.Fs, d.F.size) if pure_noise else d.F
    return d.t, d.u, F


def _element(p, name, x, inner=None):
    key, extra = SHAPES[name]
    extra = {k: v * p.phi_max for k, v in extra.items()}
    return make_effect(name, IwanJoint(p) if inner is None else inner, **{key: x}, **extra)


def _parameter(p, env, name, size):
    """Effect parameter whose added force RMS is ``size x NOTICEABLE x noise``."""
    kind, amps, cyc = ENVELOPES[env]
    u = simulate_element_test(
        IwanJoint(p), np.array(amps) * p.phi_max, envelope=kind, cycles=cyc, samples_per_cycle=128
    ).u
    t = np.arange(u.size) / 128.0
    v = np.gradient(u, t)
    base = IwanJoint(p).force_history(u)
    key = SHAPES[name][0]

    def rms(x):
        el = _element(p, name, 1.0 + x if key == "ratio" else x)
        return float(np.sqrt(np.mean((el.force_history(u, v) - base) ** 2)))

    x0 = {
        "c": 0.1 * p.Fs / p.phi_max,
        "k_p": 0.01 * p.KT,
        "gap": 0.01 * p.phi_max,
        "rate": 0.01 / (p.Fs * p.phi_max),
        "asymmetry": 0.01,
        "ratio": 0.05,
    }[key]
    x = _calibrate(rms, x0, size * NOTICEABLE * NOISE * p.Fs)
    return 1.0 + x if key == "ratio" else x


def agree(g) -> bool:
    """``success``, the report's status column and the warnings say the same: a parameter
    called identified in the status column has a finite stderr of at most half its value
    (chi: of chi + 1) and is not at a bound of its search range; one that is not is named in
    a warning; ``success`` holds only when Fs, KT and chi are identified.
    """
    f = g.fit
    rows = {
        line.split()[0]: line
        for line in f.report().splitlines()
        if line.strip().split(" ")[0] in ("Fs", "KT", "chi", "beta") and "identified" in line
    }
    warns = " | ".join(tuple(f.warnings) + tuple(g.warnings))
    ok = True
    for k in ("Fs", "KT", "chi", "beta"):
        v, se = getattr(f.joint, k), f.stderr.get(k, float("nan"))
        scale = abs(v + 1.0) if k == "chi" else abs(v)
        bound = (k == "chi" and not -0.98 + 1e-6 < v < 1.0 - 1e-6) or (
            k == "beta" and not 1e-6 < v < 100.0 - 1e-6
        )
        says = "NOT identified" not in rows[k] and " identified" in rows[k]
        if says and (not np.isfinite(se) or se > 0.5 * scale or bound):
            ok = False
        if says != bool(f.identified[k]):
            ok = False
        if not says and k not in warns and "noise" not in warns:
            ok = False
    return ok and (not g.success or all(f.identified[k] for k in ("Fs", "KT", "chi")))


def _pair_element(p, env, names, size):
    """Two effects stacked on the joint (slider-level innermost), each calibrated alone to
    ``size`` x noticeable.
    """
    from iwan_element.effects.engine.evaluate import order_stack

    el = IwanJoint(p)
    for nm in order_stack(names):
        el = _element(p, nm, _parameter(p, env, nm, size), inner=el)
    return el


def one(case):
    kind, joint, env, name, size, seed = case
    p = JOINTS[joint]
    if kind == "effect":
        el = _element(p, name, _parameter(p, env, name, size))
    elif kind == "pair":
        el = _pair_element(p, env, name.split("+"), size)
    else:
        el = IwanJoint(p)
    t, u, F = _record(p, env, el, seed, pure_noise=(kind == "noise"))
    t0 = time.perf_counter()
    g = diagnose(t, u, F)
    ratio = float(np.sqrt(np.mean((g.F - g.force_after) ** 2)) / (NOISE * p.Fs))
    return case, g.effect, g.effects, ratio, (g.success, agree(g)), time.perf_counter() - t0


def timing(repeats: int) -> None:
    """Diagnosis time with the slip-degradation bank solved per monotone run (as shipped) vs
    the per-sample reference loop, interleaved (A, B, A, B, ...), minimum per variant; the
    named effects and the residual after must be the same.
    """
    from iwan_element.effects import SlipDegradation
    from iwan_element.effects.engine.sliders import SliderEffect

    fast = SlipDegradation._correction_energy
    recs = []
    for joint, env, seed in (
        ("soft", "constant", 1),
        ("stiff", "ramped", 2),
        ("soft", "triangular", 3),
    ):
        p = JOINTS[joint]
        el = _element(p, "slip_degradation", _parameter(p, env, "slip_degradation", 3.0))
        recs.append((joint, env, _record(p, env, el, seed)))
    print(f"{'record':<18} {'n':>5} {'per-run [s]':>12} {'per-sample [s]':>15} {'ratio':>6}  same")
    for joint, env, (t, u, F) in recs:
        times, out = {"run": [], "sample": []}, {}
        for _ in range(repeats):
            for tag, meth in (("run", fast), ("sample", SliderEffect._correction_energy)):
                SlipDegradation._correction_energy = meth
                t0 = time.perf_counter()
                g = diagnose(t, u, F, candidates=("slip_degradation", "asymmetric_slip"))
                times[tag].append(time.perf_counter() - t0)
                out[tag] = (g.effects, g.error_after)
        SlipDegradation._correction_energy = fast
        a, b = min(times["run"]), min(times["sample"])
        same = (
            out["run"][0] == out["sample"][0]
            and abs(out["run"][1] - out["sample"][1]) <= 1e-9 * out["sample"][1]
        )
        print(f"{joint + ' ' + env:<18} {u.size:5d} {a:12.2f} {b:15.2f} {b / a:6.1f}  {same}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--sizes",
        type=float,
        nargs="+",
        default=None,
        help="effect size in units of noticeable (default 0.5 1 3; with --pairs 1 3)",
    )
    ap.add_argument("--effects", nargs="+", default=list(SHAPES))
    ap.add_argument("--envelopes", nargs="+", default=list(ENVELOPES))
    ap.add_argument("--clean", type=int, default=6, help="clean and pure-noise records each")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument(
        "--seed",
        type=int,
        default=1000,
        help="first seed of the effect cases (clean: seed + 1000, noise: + 2000)",
    )
    ap.add_argument(
        "--cases",
        type=int,
        default=None,
        help="run only every k-th case so that about this many run (default all)",
    )
    ap.add_argument(
        "--pairs",
        nargs="*",
        default=None,
        metavar="A+B",
        help="run two hidden effects per record instead (default pairs: "
        + " ".join(PAIRS)
        + "), at --sizes (default here 1 3) x noticeable "
        "each; pass: both named, residual within 1.3 x the noise",
    )
    ap.add_argument(
        "--timing",
        type=int,
        default=0,
        metavar="REPEATS",
        help="only time diagnose with the slip-degradation run solver vs the "
        "per-sample loop (interleaved, this many repeats) and exit",
    )
    args = ap.parse_args(argv)
    if args.timing:
        timing(args.timing)
        return 0
    cases, seed = [], args.seed
    joints = list(JOINTS)
    if args.pairs is not None:
        pairs = args.pairs or list(PAIRS)
        sizes = args.sizes or [1.0, 3.0]
        for i, name in enumerate(pairs):
            for j, env in enumerate(args.envelopes):
                for size in sizes:
                    seed += 1
                    cases.append(("pair", joints[(i + j) % 2], env, name, size, seed + 3000))
        args.effects, args.clean = [], 0
    for i, name in enumerate(args.effects):
        for j, env in enumerate(args.envelopes):
            for size in args.sizes or [0.5, 1.0, 3.0]:
                seed += 1
                cases.append(("effect", joints[(i + j) % 2], env, name, size, seed))
    for k in range(args.clean):
        env = list(ENVELOPES)[k % 3]
        cases.append(("clean", joints[k % 2], env, None, 0.0, args.seed + 1000 + k))
        cases.append(("noise", joints[k % 2], env, None, 0.0, args.seed + 2000 + k))
    if args.cases is not None and args.cases < len(cases):
        step = len(cases) / args.cases
        cases = [cases[int(i * step)] for i in range(args.cases)]
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(one, cases))
    print(
        f"{'hidden':<18} {'joint':<6} {'envelope':<10} {'size':>5} {'named':<36} "
        f"{'resid/noise':>11} {'pass':>5} {'success':>7} {'agree':>5} {'time':>6}"
    )
    passed = {}
    n_agree = 0
    for (kind, joint, env, name, size, _), eff, effs, ratio, (ok, agr), dt in rows:
        if kind == "effect":
            good = eff == name and ratio <= 1.3
        elif kind == "pair":
            good = set(effs) == set(name.split("+")) and ratio <= 1.3
        else:
            good = effs == () and (ok if kind == "clean" else not ok)
        label = name if kind in ("effect", "pair") else kind
        passed.setdefault(label, []).append(good)
        n_agree += agr
        print(
            f"{label:<18} {joint:<6} {env:<10} {size:5.2g} {' + '.join(effs) or 'none':<36} "
            f"{ratio:11.3f} {'yes' if good else 'NO':>5} {str(ok):>7} {'yes' if agr else 'NO':>5} "
            f"{dt:6.1f}"
        )
    print("\nsummary (passed / cases):")
    for label, v in passed.items():
        print(f"  {label:<18} {sum(v)}/{len(v)}")
    print(f"  success, status column and warnings agree: {n_agree}/{len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
