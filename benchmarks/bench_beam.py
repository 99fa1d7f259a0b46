"""Cost of the jointed-beam runs: Iwan connector vs linear joint, and the main job's profile.

Run:  python benchmarks/bench_beam.py [--repeat 3] [--no-profile]

(a) The same free-decay run (first bending mode, 30 periods, 100 steps per period,
    generalized-alpha at spectral radius 1, static pre-load excluded) with the exact Iwan
    joint in the two contact-point connectors, and with built-in linear springs of stiffness
    KT/2 in their place; wall time of ``SolveDynamic`` only, best of ``--repeat``.
(b) The main job ``examples/jointed_beam.py`` on defaults under cProfile: total wall time
    and where it goes.
"""
from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import runpy
import sys
import tempfile
import time
from pathlib import Path

from iwan_element.models.jointed_beam import JointedBeamConfig
from iwan_element.models.scenarios import free_decay


def transient_ratio(repeat: int):
    best = {"iwan": float("inf"), "linear": float("inf")}
    steps = 0
    for _ in range(repeat):
        res = free_decay(JointedBeamConfig(), levels=(2e-3,), cycles=30, steps_per_period=100)
        best["iwan"] = min(best["iwan"], res.runs[0].wall_time)
        best["linear"] = min(best["linear"], res.linear_runs[0].wall_time)
        steps = len(res.runs[0].t) - 1
    return best, steps


def profile_main_job(top: int = 14):
    script = Path(__file__).resolve().parents[1] / "examples" / "jointed_beam.py"
    out = Path(tempfile.mkdtemp()) / "jb"
    argv = sys.argv
    sys.argv = [str(script), "--out", str(out)]
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    try:
        prof.enable()
        runpy.run_path(str(script), run_name="__main__")
        prof.disable()
    finally:
        sys.argv = argv
    wall = time.perf_counter() - t0
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(top)
    return wall, s.getvalue()


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-profile", action="store_true")
    args = ap.parse_args(argv)
    best, steps = transient_ratio(args.repeat)
    print(f"(a) free decay, {steps} steps, 2 contact points, 136 coordinates")
    print("| joint | wall [s] | us per step | ratio |")
    print("|---|---|---|---|")
    for k in ("linear", "iwan"):
        print(f"| {k} | {best[k]:.3f} | {best[k] / steps * 1e6:.0f} | {best[k] / best['linear']:.2f} |")
    if not args.no_profile:
        wall, table = profile_main_job()
        print(f"\n(b) main job on defaults: {wall:.1f} s wall (under cProfile)\n")
        print(table)


if __name__ == "__main__":
    main()
