"""Speed-up of an amplitude-curve ensemble on a dask.distributed LocalCluster: 1 vs 2 workers.

Each task is a heavy, independent model run: by default the quasi-static modal analysis
(QSMA, Exudyn static solves) of the example lap-jointed beam at one preload and friction
coefficient (``--task qsma``), or a transient ring-down of the single-mode Iwan oscillator
(``--task ringdown``, pure Python). The same parameter sets and seed run on clusters of
each worker count (one thread per worker process); every cluster first runs one warm-up task
per worker (imports, Exudyn start-up, the cached linear model), then the timed ensemble.
The worker counts are timed in turn ``--repeat`` times and the best and median wall times
are reported (other processes on a shared machine only ever add time). The results of all
runs are checked to be identical. The load average is printed: on a shared machine, other
processes take cores from the workers and lower the speed-up.

    python benchmarks/bench_ensemble.py                 # 100 QSMA tasks, 1 and 2 workers
    python benchmarks/bench_ensemble.py --task ringdown --tasks 40
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import io
import logging
import os
import time
import warnings

import numpy as np
from iwan_element.models.studies import specimen_curve_task

from iwan_element import IwanParameters
from iwan_element.ensemble import SingleModeSystem, parameter_samples, run_ensemble
from iwan_element.ensemble.oscillator import _integrate


def ringdown_task(params, rng, *, cycles=400, steps_per_period=64):
    """Amplitude decay of a single-mode Iwan oscillator released at x0 (peak per cycle)."""
    p = IwanParameters(Fs=params["Fs"], KT=5e7, chi=-0.5, beta=0.5)
    system = SingleModeSystem(mass=10.0, stiffness=2.5e7, zeta0=1e-3)
    h = 1.0 / (system.linear_frequency(p) * steps_per_period)
    _, x = _integrate(
        p, system, h=h, n=cycles * steps_per_period, load=lambda t: 0.0, x0=params["x0"]
    )
    peaks = x[:-1].reshape(cycles, steps_per_period).max(axis=1)
    return {"peaks": peaks[::20]}


def quiet_qsma_task(params, rng, *, specimen, amplitudes):
    """specimen_curve_task without Exudyn's solver banner on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        return specimen_curve_task(params, rng, specimen=specimen, amplitude=amplitudes)


def make(task: str, n: int):
    if task == "qsma":
        from iwan_element.models.specimens import preset

        func = functools.partial(
            quiet_qsma_task, specimen=preset("example"), amplitudes=np.geomspace(1e-6, 1e-3, 20)
        )
        sets = parameter_samples(n, seed=1, preload=(5e3, 40e3), friction=(0.15, 0.5))
    else:
        func = ringdown_task
        sets = parameter_samples(n, seed=1, Fs=(4e3, 12e3), x0=(5e-5, 2e-4))
    return func, sets


def warm_up(func, params):
    func(params, np.random.default_rng(0))


def start(workers: int):
    from distributed import Client, LocalCluster

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.CRITICAL,
        )
        return cluster, Client(cluster)


def timed(client, func, sets, seed: int):
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    res = run_ensemble(func, sets, executor=client, seed=seed)
    return res, time.perf_counter() - t0, load0, os.getloadavg()[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", choices=("qsma", "ringdown"), default="qsma")
    ap.add_argument("--tasks", type=int, default=100)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args()
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    func, sets = make(args.task, args.tasks)
    print(
        f"{args.tasks} '{args.task}' tasks on a dask LocalCluster (processes, 1 thread per "
        f"worker); machine: {os.cpu_count()} cores; {args.repeat} alternating repeats"
    )
    print(
        f"{'run':>4} {'workers':>8} {'wall [s]':>9} {'s/task':>8} {'load before':>12} "
        f"{'load after':>11} {'failed':>7}"
    )
    clusters = {w: start(w) for w in args.workers}
    logging.getLogger("distributed").setLevel(logging.CRITICAL)  # LocalCluster resets it
    walls = {w: [] for w in args.workers}
    ref = None
    try:
        for _, client in clusters.values():  # warm-up on every worker (imports, caches)
            client.run(warm_up, func, sets[0])
        for r in range(args.repeat):
            for w, (_, client) in clusters.items():
                res, wall, l0, l1 = timed(client, func, sets, args.seed)
                walls[w].append(wall)
                if ref is None:
                    ref = res
                for a, b in zip(ref.rows, res.rows):
                    for k in a:
                        np.testing.assert_array_equal(a[k], b[k])
                print(
                    f"{r + 1:4d} {w:8d} {wall:9.2f} {wall / len(sets):8.3f} {l0:12.2f} "
                    f"{l1:11.2f} {len(res.errors):7d}",
                    flush=True,
                )
    finally:
        for cluster, client in clusters.values():
            client.close()
            cluster.close()
    w0 = args.workers[0]
    print(
        f"\n{'workers':>8} {'best [s]':>9} {'median [s]':>11} {'speed-up (best)':>16} "
        f"{'speed-up (median)':>18} {'paired speed-up':>16}"
    )
    for w in args.workers:
        paired = np.median(np.array(walls[w0]) / np.array(walls[w]))
        print(
            f"{w:8d} {min(walls[w]):9.2f} {np.median(walls[w]):11.2f} "
            f"{min(walls[w0]) / min(walls[w]):16.2f} "
            f"{np.median(walls[w0]) / np.median(walls[w]):18.2f} {paired:16.2f}"
        )
    print(
        "paired speed-up: median over the repeats of (wall with the first worker count) / "
        "(wall of the run right after it); it cancels slow drifts of the machine's load"
    )
    print("results identical across worker counts and repeats: yes")


if __name__ == "__main__":
    main()
