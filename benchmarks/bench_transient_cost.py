"""Cost of the transient routes per nominal step, with the joint and with linear springs.

Run:  python benchmarks/bench_transient_cost.py [--repeat 3] [--rows ringdown solid multi sine]
      [--before PYTHON] [--json FILE] [--accuracy]

Rows (each the same release with the Iwan elements and with linear springs at the stuck
stiffness, ``tangential="linear"``, on the same bodies):

* ``ringdown``: ``models.ringdown(preset, amplitude=X, cycles=10, steps_per_period=32)`` for
  the Brake-Reuss and two-bolt aluminium presets at 20 and 200 um (the table of the issue
  "transient runs at full speed when the joint slips");
* ``solid``: the coarse Brake-Reuss solid of ``tests/test_solid_ringdown.py`` (mesh 12 mm,
  lap faces 5.1 mm, patches 8.5 mm, 8 stuck modes) released in mode 1 from 60 um, 0.1 s at
  32 steps per period;
* ``multi``: the Brake-Reuss beam released in modes 1 and 2 together (60 and 15 um), 10
  periods of mode 1 at 32 steps per period of mode 2;
* ``sine``: ``models.forced_response`` of ``tests/test_frequency_domain.py``'s stepped sine
  (Brake-Reuss, floor 0.02, 0.02 N, 0.985 / 1.0 / 1.012 x the stuck frequency, spectral
  radius 1, 64 steps a period), with 20 settling and 10 measured periods per frequency.

Every solve (``SolveDynamic`` or the condensed route's) is counted with Exudyn's own solver
counters and timers (the same counters for any version of the package, so ``--before`` can run
this file under another checkout's interpreter): nominal steps, accepted steps beyond them
(step cuts), Newton iterations, Jacobians, and the seconds in Jacobians (``totalJacobian`` +
``factorization``) in residuals (``ODE2RHS``) and in Python (the post-step commit and records),
printed as shares of the fastest run's wall. Wall time is the time inside the solver, min and
median over ``--repeat`` runs in this process. The runs with the joint and with linear springs
alternate (joint, springs, joint, springs ...), and the ratio is the median over the repeats of
each pair's ratio of CPU seconds inside the solver (``time.process_time``): on a machine shared
with other work, the wall of runs made one after the other moves with the load, and a ratio of
walls measured minutes apart moved by 2x between runs of this file.

``--before PATH``: run the same rows under the interpreter ``PATH`` (e.g. a virtual
environment with an older checkout installed), or read them from a ``--json`` file of an
earlier run, and print its columns beside these (``benchmarks/transient_cost_before.json``:
the issue's "before", commit b7979bd, command in docs/transient_cost.md).

``--accuracy``: each ring-down row's amplitude curve (20 periods; the solid 0.25 s) at 32 and
64 steps per period against the same run at 4x the steps: the largest relative frequency and
damping differences over the curve's points (the reference curve interpolated in log
amplitude); the stepped sine's amplitudes (60 settling periods) at 32 and 64 steps against
128 and 256.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

import exudyn as exu
import numpy as np

from iwan_element import models

RINGDOWN = (
    ("brake-reuss", 20e-6),
    ("brake-reuss", 200e-6),
    ("two-bolt-aluminium", 20e-6),
    ("two-bolt-aluminium", 200e-6),
)
_COUNTS = []
_SOLVE = exu.MainSolverImplicitSecondOrder.SolveSystem


def _counted(s, mbs, sim):
    """The implicit solver's ``SolveSystem`` (under ``SolveDynamic`` and the condensed
    route's ``solve_dynamic`` alike) with Exudyn's timers on; its counters appended to
    ``_COUNTS``.
    """
    sim.show.computationTime = True
    t0, c0 = time.perf_counter(), time.process_time()
    out = _SOLVE(s, mbs, sim)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    it, tm = s.it, s.timer
    _COUNTS.append(
        {
            "wall": wall,
            "cpu": cpu,
            "n": int(s.GetODE2size()),
            "steps": int(sim.timeIntegration.numberOfSteps),
            "taken": int(it.currentStepIndex) - 1,
            "newton": int(it.newtonStepsCount),
            "jacobians": int(it.newtonJacobiCount),
            "t_jac": float(tm.totalJacobian + tm.factorization),
            "t_rhs": float(tm.ODE2RHS),
            "t_py": float(tm.python),
        }
    )
    return out


exu.MainSolverImplicitSecondOrder.SolveSystem = _counted


def _solid():
    from iwan_element.models.solid import lap_beam_parts, solid_specimen

    s = models.preset("brake-reuss")
    parts = lap_beam_parts(s, mesh_size=0.012, lap_mesh_size=0.0051)
    return solid_specimen(s, parts, patch_size=0.0085, n_modes=8)


#: The runs of a row: the joint on the default (condensed) route, linear springs, and the
#: joint on Exudyn's own modified Newton (the route before the condensed one).
RUNS = {"iwan": {}, "linear": {"tangential": "linear"}, "exudyn": {"newton": "exudyn"}}


def _rows(kinds):
    """``[(label, run(kind))]`` of the chosen kinds (``kind`` a key of :data:`RUNS`)."""
    rows = []
    if "ringdown" in kinds:
        for name, X in RINGDOWN:
            p = models.preset(name)
            rows.append(
                (
                    f"{name} {X * 1e6:g} um",
                    lambda t, p=p, X=X: models.ringdown(
                        p, amplitude=X, cycles=10, steps_per_period=32, **RUNS[t]
                    ),
                )
            )
    if "solid" in kinds:
        solid = _solid()
        rows.append(
            (
                "solid brake-reuss 60 um",
                lambda t: models.ringdown(
                    solid, amplitude=60e-6, duration=0.1, steps_per_period=32, **RUNS[t]
                ),
            )
        )
    if "multi" in kinds:
        p = models.preset("brake-reuss")
        rows.append(
            (
                "brake-reuss modes 1+2 (60 + 15 um)",
                lambda t: models.ringdown(
                    p, amplitude={1: 60e-6, 2: 15e-6}, cycles=10, steps_per_period=32, **RUNS[t]
                ),
            )
        )
    if "sine" in kinds:
        from iwan_element.models.reduced import reduced_model

        s = models.preset("brake-reuss").replace(damping_floor=0.02, modal_damping=())
        f = np.array([0.985, 1.0, 1.012]) * reduced_model(s).frequency(1)
        rows.append(
            (
                "stepped sine brake-reuss 0.02 N",
                lambda t: (
                    None
                    if t == "linear"
                    else models.forced_response(
                        s,
                        force_levels=(0.02,),
                        frequencies=f,
                        settle_cycles=20,
                        measure_cycles=10,
                        steps_per_period=64,
                        spectral_radius=1.0,
                        **RUNS[t],
                    )
                ),
            )
        )
    return rows


def _counters(run):
    """Counters of one run (summed over its solves), or None when the row has no such run
    (or an older checkout has no such option).
    """
    _COUNTS.clear()
    try:
        if run() is None:
            return None
    except TypeError:  # an older checkout: no ``newton`` option
        return None
    out = {
        k: sum(c[k] for c in _COUNTS)
        for k in ("wall", "cpu", "steps", "taken", "newton", "jacobians", "t_jac", "t_rhs", "t_py")
    }
    out["n"] = _COUNTS[0]["n"]
    return out


def _measure(run, repeat):
    """``{"iwan": counters, "linear": counters or None}`` of a row: the two runs alternate
    ``repeat`` times; each gets the min and median of its walls and CPU seconds, the joint's
    run the median over the pairs of its CPU ratio to the springs' (``ratio_cpu``).
    """
    runs = {t: [] for t in RUNS}
    for _ in range(repeat):
        for t in runs:
            runs[t].append(_counters(lambda t=t: run(t)))
    out = {}
    for t, rs in runs.items():
        if rs[0] is None:
            out[t] = None
            continue
        walls, cpus = [r["wall"] for r in rs], [r["cpu"] for r in rs]
        out[t] = {
            **rs[-1],
            "wall_min": min(walls),
            "wall_median": statistics.median(walls),
            "cpu_median": statistics.median(cpus),
        }
    if out["linear"] is not None:
        for t in ("iwan", "exudyn"):
            if out[t] is not None:
                out[t]["ratio_cpu"] = statistics.median(
                    a["cpu"] / b["cpu"] for a, b in zip(runs[t], runs["linear"])
                )
    return out


def measure(kinds, repeat) -> dict:
    """``{label: {"iwan": counters, "linear": counters or None}}``."""
    return {label: _measure(run, repeat) for label, run in _rows(kinds)}


def _line(label, d, other=None):
    a, b = d["iwan"], d["linear"]
    ms = 1e3 * a["wall_median"] / a["steps"]
    txt = (
        f"{label:36s} {a['n']:4d} {a['steps']:6d} {a['taken'] - a['steps']:5d} "
        f"{a['newton'] / a['taken']:5.2f} {a['jacobians']:5d} "
        f"{1e3 * a['t_jac'] / max(a['jacobians'], 1):7.2f} "
        f"{a['wall_min']:7.2f} {a['wall_median']:7.2f} {ms:7.3f}"
    )
    if b is not None:
        txt += (
            f" {1e3 * b['wall_median'] / b['steps']:7.3f}"
            f" {a['wall_median'] / b['wall_median']:5.2f}"
            f" {a['ratio_cpu']:5.2f} {b['newton'] / b['taken']:5.2f}"
        )
    else:
        txt += f" {'-':>7s} {'-':>5s} {'-':>5s} {'-':>5s}"
    txt += "".join(
        f" {100 * a.get(k, 0.0) / a['wall_min']:4.0f}" for k in ("t_jac", "t_rhs", "t_py")
    )
    e = d.get("exudyn")
    if e is not None:  # the joint on Exudyn's modified Newton, in the same run
        txt += (
            f" | {e['newton'] / e['taken']:5.2f} {e['jacobians']:5d}"
            f" {1e3 * e['wall_median'] / e['steps']:7.3f}"
            f" {e['ratio_cpu'] if 'ratio_cpu' in e else float('nan'):5.2f}"
        )
    else:
        txt += f" | {'-':>5s} {'-':>5s} {'-':>7s} {'-':>5s}"
    if other is not None:
        o = other["iwan"]
        txt += (
            f" | {o['wall_median']:7.2f} {1e3 * o['wall_median'] / o['steps']:7.3f} "
            f"{o['taken'] - o['steps']:5d} {o['jacobians']:5d}"
        )
    return txt


def _gap(a, b):
    """Largest relative frequency and damping gaps of curve ``a`` against curve ``b`` at
    ``a``'s amplitudes inside ``b``'s range (``b`` interpolated in log amplitude), and the
    number of points compared.
    """
    la, lb = np.log(a.amplitude), np.log(b.amplitude)
    o = np.argsort(lb)
    keep = (la >= lb.min()) & (la <= lb.max())
    fb = np.interp(la[keep], lb[o], b.frequency[o])
    zb = np.interp(la[keep], lb[o], b.damping_ratio[o])
    return (
        float(np.max(np.abs(a.frequency[keep] / fb - 1))),
        float(np.max(np.abs(a.damping_ratio[keep] / zb - 1))),
        int(keep.sum()),
    )


def _accuracy_rows():
    """``[(label, run(spp) -> [curves])]``: the ring-down rows over 20 periods."""
    rows = []
    for name, X in RINGDOWN:
        p = models.preset(name)
        rows.append(
            (
                f"{name} {X * 1e6:g} um",
                lambda s, p=p, X=X: [
                    models.ringdown(p, amplitude=X, cycles=20, steps_per_period=s).curve
                ],
            )
        )
    p = models.preset("brake-reuss")
    rows.append(
        (
            "brake-reuss modes 1+2 (60 + 15 um)",
            lambda s: list(
                models.ringdown(
                    p, amplitude={1: 60e-6, 2: 15e-6}, cycles=20, steps_per_period=s
                ).curves
            ),
        )
    )
    solid = _solid()
    rows.append(
        (
            "solid brake-reuss 60 um",
            lambda s: [
                models.ringdown(solid, amplitude=60e-6, duration=0.25, steps_per_period=s).curve
            ],
        )
    )
    return rows


def accuracy():
    print(
        "amplitude curves (20 periods; the solid 0.25 s) against 4x the steps per period: "
        "largest relative gaps over the curve's points (several modes: the worst mode)"
    )
    print(f"{'row':36s} {'spp':>4s} {'points':>6s} {'frequency':>10s} {'damping':>9s}")
    for label, run in _accuracy_rows():
        for spp in (32, 64):
            gaps = [_gap(a, b) for a, b in zip(run(spp), run(4 * spp))]
            df, dz, k = (max(g[0] for g in gaps), max(g[1] for g in gaps), min(g[2] for g in gaps))
            print(f"{label:36s} {spp:4d} {k:6d} {df:10.2e} {100 * dz:8.2f}%", flush=True)
    from iwan_element.models.reduced import reduced_model

    s = models.preset("brake-reuss").replace(damping_floor=0.02, modal_damping=())
    f = np.array([0.985, 1.0, 1.012]) * reduced_model(s).frequency(1)
    amp = {}
    for spp in (32, 64, 128, 256):
        amp[spp] = models.forced_response(
            s,
            force_levels=(0.02,),
            frequencies=f,
            settle_cycles=60,
            measure_cycles=10,
            steps_per_period=spp,
            spectral_radius=1.0,
        ).amplitude[0]
    for spp in (32, 64):
        print(
            f"{'stepped sine brake-reuss 0.02 N':36s} {spp:4d} {f.size:6d} "
            f"{'-':>10s} {100 * np.max(np.abs(amp[spp] / amp[4 * spp] - 1)):8.2f}% "
            "(amplitude)",
            flush=True,
        )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--rows",
        nargs="+",
        default=["ringdown", "solid", "multi", "sine"],
        choices=["ringdown", "solid", "multi", "sine"],
    )
    ap.add_argument(
        "--before",
        help="interpreter of an older checkout to run the same rows, "
        "or a --json file of an earlier run",
    )
    ap.add_argument("--json", help="write the measurements to this file (and print nothing)")
    ap.add_argument("--accuracy", action="store_true")
    a = ap.parse_args(argv)
    if a.accuracy:
        return accuracy()
    res = measure(a.rows, a.repeat)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh)
        return
    before = None
    if a.before:
        path = a.before
        if not path.endswith(".json"):
            path = "/tmp/bench_transient_cost_before.json"
            subprocess.run(
                [a.before, __file__, "--repeat", str(a.repeat), "--rows", *a.rows, "--json", path],
                check=True,
            )
        with open(path) as fh:
            before = json.load(fh)
    print(
        f"exudyn {exu.__version__}; wall = seconds in the solver over {a.repeat} runs; "
        "ratio = median walls, r cpu = median of the paired CPU ratios, l it = Newton "
        "iterations a step with linear springs; the e columns: the joint on Exudyn's "
        "modified Newton (newton='exudyn'), its iterations a step, Jacobians, ms a step "
        "and paired CPU ratio to linear springs"
    )
    head = (
        f"{'row':36s} {'n':>4s} {'steps':>6s} {'cuts':>5s} {'it/st':>5s} {'jacs':>5s} "
        f"{'ms/jac':>7s} {'min s':>7s} {'med s':>7s} {'ms/st':>7s} {'lin ms':>7s} {'ratio':>5s} "
        f"{'r cpu':>5s} {'l it':>5s} "
        f"{'%jac':>4s} {'%res':>4s} {'%py':>4s}"
        f" | {'e it':>5s} {'ejacs':>5s} {'e ms':>7s} {'e cpu':>5s}"
    )
    if before:
        head += f" | {'bef s':>7s} {'ms/st':>7s} {'cuts':>5s} {'jacs':>5s}"
    print(head)
    for label, d in res.items():
        print(_line(label, d, None if before is None else before.get(label)))


if __name__ == "__main__":
    sys.exit(main())
