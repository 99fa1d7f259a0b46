"""Benchmark: the full detection matrix of :func:`iwan_element.diagnose.diagnose`.

Synthetic records (``tests/_diagnosis_cases.py``: REFERENCE.md test vector (1000 N, 1e6 N/m,
-0.5, 0.2), two loading protocols, three cycles of 96 samples per amplitude, 5 N force
noise) with one effect hidden at three magnitudes (added-force RMS 2, 4 and 8 times the
noise RMS), several noise seeds; and clean records (white and AR(1) coloured noise, both
protocols) for the false-positive count. The diagnosis is never told what is hidden.

Prints per effect: how often the hidden effect is named, how often another one (or none),
how often the result is flagged ambiguous, and error_after / noise_level (median, max, and
the share within 10 %); then the clean-data false positives and the timing.

Run from the repository root::

    PYTHONPATH=. python benchmarks/bench_diagnosis.py [--seeds 2] [--clean-seeds 20]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _diagnosis_cases import MAGNITUDES, PROTOCOLS, SHAPES, record  # noqa: E402

from iwan_element.diagnose import diagnose  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--clean-seeds", type=int, default=20)
    ap.add_argument("--colour", type=float, default=0.8, help="AR(1) coefficient of coloured noise")
    ap.add_argument("--magnitudes", type=float, nargs="+", default=list(MAGNITUDES),
                    help="effect RMS / noise RMS (default 2 4 8)")
    ap.add_argument("--effect-colour", type=float, default=0.0,
                    help="AR(1) coefficient of the noise on the records with an effect")
    args = ap.parse_args(argv)
    times = []
    rows = []
    print(f"{'effect':<18} {'mag':>4} {'named right':>11} {'other':>18} {'ambig.':>6} "
          f"{'after/noise med':>15} {'max':>6} {'<=1.1':>6}")
    total = right_all = within_all = 0
    for name in SHAPES:
        for mag in args.magnitudes:
            right = amb = within = 0
            other = {}
            ratios = []
            for proto in PROTOCOLS:
                for seed in range(args.seeds):
                    d = record(name, mag, proto, 100 + seed, colour=args.effect_colour)
                    t0 = time.perf_counter()
                    g = diagnose(d.t, d.u, d.F)
                    times.append(time.perf_counter() - t0)
                    ok = g.effect == name
                    right += ok
                    amb += bool(g.ambiguous_with)
                    if not ok:
                        other[g.effect] = other.get(g.effect, 0) + 1
                    q = g.error_after / g.noise_level
                    ratios.append(q)
                    within += q <= 1.1
            n = len(ratios)
            total += n
            right_all += right
            within_all += within
            oth = ",".join(f"{k}:{v}" for k, v in other.items()) or "-"
            print(f"{name:<18} {mag:4.3g} {right:>5}/{n:<5} {oth:>18} {amb:>6} "
                  f"{statistics.median(ratios):15.3f} {max(ratios):6.3f} {within:>3}/{n}")
            rows.append((name, mag, right, n))
    print(f"\nhidden effect named: {right_all}/{total} = {100 * right_all / total:.1f} %; "
          f"error_after within 10 % of the noise: {within_all}/{total}")
    fp = 0
    nclean = 0
    worst = 0.0
    for colour in (0.0, args.colour):
        for proto in PROTOCOLS:
            for seed in range(args.clean_seeds):
                d = record(None, 0, proto, 1000 + seed, colour=colour)
                t0 = time.perf_counter()
                g = diagnose(d.t, d.u, d.F)
                times.append(time.perf_counter() - t0)
                nclean += 1
                worst = max(worst, g.details["misfit_ratio"])
                if g.effect != "none":
                    fp += 1
                    print(f"  false positive: colour {colour}, {proto}, seed {seed}: {g.effect}")
    print(f"clean data (white and AR(1) {args.colour} noise, {len(PROTOCOLS)} protocols, "
          f"{args.clean_seeds} seeds each): {fp} false positives in {nclean}; largest "
          f"SSR/(n sigma^2) {worst:.3f}")
    print(f"diagnose wall time: median {statistics.median(times):.2f} s, max {max(times):.2f} s, "
          f"total {sum(times):.1f} s over {len(times)} records")


if __name__ == "__main__":
    main()
