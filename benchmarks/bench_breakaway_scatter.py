"""Benchmark: whether the stated standard error of a diagnosed break-away holds.

Seeded repeats of one held-out record (joint and envelope of ``bench_diagnosis.py``, the
break-away ratio set to ``--size`` x noticeable, force noise 0.4 % of Fs, offsets), each
diagnosed with break-away as the only candidate (the question is the uncertainty, not the
selection). Prints, per parameter, the scatter of the estimates over the repeats, the median
stated standard error, their ratio and how often the stated 95 % interval holds the truth.

    python benchmarks/bench_breakaway_scatter.py [--repeats 20] [--joint soft] [--envelope ramped]
                                                [--size 1] [--jobs 2]
"""

from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import bench_diagnosis as B

from iwan_element.diagnose import diagnose

NAMES = ("ratio", "Fs", "KT", "chi", "beta")


def one(args):
    joint, env, ratio, seed = args
    p = B.JOINTS[joint]
    t, u, F = B._record(p, env, B._element(p, "breakaway", ratio), seed)
    g = diagnose(t, u, F, candidates=("breakaway",), max_effects=1)
    if g.effects != ("breakaway",):
        return None
    e = g.fit.details["effects"][0]
    est = [e["parameters"]["ratio"]] + [getattr(g.fit.joint, k) for k in NAMES[1:]]
    se = [e["stderr"]["ratio"]] + [g.fit.stderr[k] for k in NAMES[1:]]
    return est, se


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--joint", default="soft", choices=list(B.JOINTS))
    ap.add_argument("--envelope", default="ramped", choices=list(B.ENVELOPES))
    ap.add_argument("--size", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=5000)
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args(argv)
    p = B.JOINTS[a.joint]
    ratio = B._parameter(p, a.envelope, "breakaway", a.size)
    truth = np.array([ratio, p.Fs, p.KT, p.chi, p.beta])
    with ProcessPoolExecutor(a.jobs) as ex:
        rows = list(
            ex.map(one, [(a.joint, a.envelope, ratio, a.seed + k) for k in range(a.repeats)])
        )
    ok = [r for r in rows if r is not None]
    est = np.array([r[0] for r in ok])
    se = np.array([r[1] for r in ok])
    print(
        f"{a.joint} joint, {a.envelope} envelope, ratio {ratio:.4f} ({a.size:g} x noticeable); "
        f"break-away named in {len(ok)}/{len(rows)} repeats"
    )
    print(
        f"{'parameter':>9} {'truth':>11} {'mean':>11} {'scatter':>10} {'median se':>10} "
        f"{'se/scatter':>10} {'95% holds':>9}"
    )
    for j, k in enumerate(NAMES):
        sd = float(np.std(est[:, j], ddof=1))
        cover = float(np.mean(np.abs(est[:, j] - truth[j]) <= 1.96 * se[:, j]))
        print(
            f"{k:>9} {truth[j]:11.5g} {np.mean(est[:, j]):11.5g} {sd:10.3g} "
            f"{np.median(se[:, j]):10.3g} {np.median(se[:, j]) / sd:10.2f} {100 * cover:8.0f}%"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
