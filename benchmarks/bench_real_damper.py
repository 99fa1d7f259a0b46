"""Diagnose every real friction-damper record in ../shared/data/arts-damper.

Per record: the effect(s) named, the wall and the process CPU time of its diagnosis, the RMS misfit
in the band |F| < 0.25 max|F| (where backlash acts) before and after, and their ratio. The rig's
40-50 Hz ringing is removed first by a zero-phase low-pass (``--lowpass``, default 20 Hz; the joint
is driven at 0.5-1 Hz), and the band misfit is measured on that low-passed force. The last column is
the force-channel lag [samples] that would minimise the band misfit after (the fitted force shifted
by -10..10 samples) and the band misfit after at that lag: a channel time lag is a nuisance worth
fitting only if that misfit is much smaller than the unshifted one. ``at speed`` is the share [%] of
the band's squared misfit after that lies where the drive moves at over 90 % of its top speed, away
from the reversals and gap crossings: a rate-independent joint slides there at its friction level,
so a large share puts the misfit in the sliding phase, not in the transitions (a sliding level
inside the band, as on the decreasing branch of the 0 lb records, or the chatter after the gap
closes at full speed in the velocity-limited 1-2 Hz ds2 records: see docs/damper_range.md).

    python benchmarks/bench_real_damper.py [--data DIR] [--lowpass 20] [--jobs 1]
"""

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def run(path, lowpass):
    from iwan_element import diagnose
    from iwan_element.diagnose.loops.batch import band_misfit

    t, u, F = np.loadtxt(path, delimiter=",", skiprows=1).T
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        g = diagnose(t, u, F, lowpass=lowpass)
    except ValueError as exc:  # a refusal is a result, reported as such
        return (
            path.name,
            f"REFUSED: {exc}",
            np.nan,
            np.nan,
            time.perf_counter() - t0,
            (0, np.nan, np.nan),
            time.process_time() - c0,
        )
    cpu = time.process_time() - c0
    rb, ra = band_misfit(g.F, g.force_before, 0.25), band_misfit(g.F, g.force_after, 0.25)
    band = np.abs(g.F) < 0.25 * np.abs(g.F).max()
    lags = np.arange(-10, 11)
    shifted = [
        np.sqrt(np.mean((g.F - np.interp(g.t - k / fs, g.t, g.force_after))[band] ** 2))
        for fs in [1.0 / float(np.median(np.diff(g.t)))]
        for k in lags
    ]
    lag = (int(lags[int(np.argmin(shifted))]), float(np.min(shifted)))
    speed = np.abs(np.gradient(g.u, g.t))
    r2 = np.where(band, (g.F - g.force_after) ** 2, 0.0)
    fast = 100.0 * r2[speed > 0.9 * speed.max()].sum() / max(r2.sum(), 1e-300)
    return (
        path.name,
        " + ".join(g.effects) or "none",
        rb,
        ra,
        time.perf_counter() - t0,
        (*lag, fast),
        cpu,
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data",
        default=None,
        help="folder of the records (default: ../shared/data/arts-damper next to "
        "the repository or the current directory)",
    )
    ap.add_argument("--lowpass", type=float, default=20.0)
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args(argv)
    if args.data is None:
        where = [
            p / "shared" / "data" / "arts-damper"
            for p in (Path.cwd().parent, ROOT.parent, ROOT.parent.parent)
        ]
        args.data = str(next((p for p in where if p.is_dir()), where[0]))
    files = sorted(Path(args.data).glob("*.csv"))
    if not files:
        print(f"no records in {args.data} (the shared data folder is absent): skipped")
        return 0
    with ProcessPoolExecutor(args.jobs) as ex:
        rows = list(ex.map(run, files, [args.lowpass] * len(files)))
    print(
        f"{'record':<26} {'named':<44} {'band before [N]':>15} {'after [N]':>10} "
        f"{'ratio':>6} {'time [s]':>8} {'CPU [s]':>7} {'lag':>4} {'at lag [N]':>10} "
        f"{'at speed':>8}"
    )
    ok = 0
    for name, eff, rb, ra, dt, lag, cpu in rows:
        print(
            f"{name:<26} {eff:<44} {rb:15.0f} {ra:10.0f} {ra / rb:6.2f} {dt:8.1f} {cpu:7.1f} "
            f"{lag[0]:4d} {lag[1]:10.0f} {lag[2]:7.0f}%"
        )
        ok += ("backlash" in eff) and ra <= 0.5 * rb
    print(f"{ok}/{len(rows)} records: backlash named and band misfit at least halved")
    return 0


if __name__ == "__main__":
    sys.exit(main())
