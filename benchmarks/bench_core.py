"""Accuracy and cost of the exact Iwan joint against discretised slider models.

Run:  python benchmarks/bench_core.py [--quick] [--baseline DIR]

``--baseline DIR`` also times the exact joint of another checkout (DIR holds its
``iwan_element`` package, e.g. from ``git archive <commit> iwan_element | tar -x -C DIR``)
side by side in the same run: the before/after figure for a change to the hot path.

(a) Relative error of the dissipation per steady cycle, measured as the closed-path work
    (loop area) of a simulated cycle, against the closed form ``dissipation()``, at
    r = u0/phi_max from 1e-5 to 10, for the exact ``IwanJoint`` and for ``DiscreteIwan`` with
    100 uniform (midpoint) and 100 log-spaced (moment-matched) sliders.
(b) Cost per ``trial()`` and ``commit()`` call in microseconds, all elements measured side by
    side in this run (best of several repeats), within steps of a decaying vibration.
"""

from __future__ import annotations

import argparse
import math
import platform
import time

import numpy as np

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters, dissipation

PARAMS = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.1)
RATIOS = [1e-5, 1e-4, 1e-3, 4.9e-3, 5.1e-3, 1e-2, 0.1, 0.5, 1.0, 2.0, 10.0]


_BASELINE = {}


def load_baseline(src: str):
    """Import the ``iwan_element`` package under ``src`` as ``iwan_element_baseline``."""
    import importlib.util
    import sys
    from pathlib import Path

    init = Path(src) / "iwan_element" / "__init__.py"
    spec = importlib.util.spec_from_file_location(
        "iwan_element_baseline", init, submodule_search_locations=[str(init.parent)]
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules["iwan_element_baseline"] = mod
    spec.loader.exec_module(mod)
    return mod


def elements():
    base = {}
    if "mod" in _BASELINE:
        m = _BASELINE["mod"]
        p = m.IwanParameters(PARAMS.Fs, PARAMS.KT, PARAMS.chi, PARAMS.beta)
        base = {"baseline IwanJoint": m.IwanJoint(p)}
    return {
        "exact IwanJoint": IwanJoint(PARAMS),
        **base,
        "100 uniform sliders": DiscreteIwan(PARAMS, 100, spacing="uniform"),
        "100 log sliders": DiscreteIwan(PARAMS, 100, spacing="log"),
    }


def loop_area(el, u0: float, n: int = 200) -> float:
    """Closed-path work of the second of two cycles u0 cos(2 pi t) (steady state)."""
    el.reset()
    u = u0 * np.cos(np.linspace(0.0, 4.0 * np.pi, 2 * n + 1))
    for x in u[: n + 1]:
        el.trial(x)
        el.commit()
    W0 = el.work
    for x in u[n + 1 :]:
        el.trial(x)
        el.commit()
    return el.work - W0


def accuracy_table():
    els = elements()
    rows = []
    for r in RATIOS:
        u0 = r * PARAMS.phi_max
        D = dissipation(u0, PARAMS)
        rows.append((r, [abs(loop_area(el, u0) / D - 1.0) for el in els.values()]))
    return list(els), rows


def _time_steps(el, u, probes, with_trials: bool) -> float:
    el.reset()
    trial, commit = el.trial, el.commit
    t0 = time.perf_counter()
    if with_trials:
        for x, (a, b, c, d, e, f, g, h) in zip(u, probes):
            trial(a)
            trial(b)
            trial(c)
            trial(d)
            trial(e)
            trial(f)
            trial(g)
            trial(h)
            trial(x)
            commit()
    else:
        for x in u:
            trial(x)
            commit()
    return (time.perf_counter() - t0) / len(u)


def cost_table(n_steps: int, repeats: int, exact_only: bool = False):
    """Cost per trial and per commit on a decaying vibration through macro- and microslip.

    Each step makes 8 extra trials at Newton-like iterates around the accepted displacement
    (perturbations of either sign, so some trials reverse the motion) before the final trial
    and the commit. The marginal cost of a trial is (t9 - t1)/8, t9 and t1 being the per-step
    times with and without the 8 extra trials; a commit costs t1 minus one trial.
    """
    rng = np.random.default_rng(0)
    t = np.arange(n_steps)
    u = PARAMS.phi_max * (
        1.5 * np.exp(-t / (0.3 * n_steps)) * np.sin(2 * np.pi * t / 50)
        + 1e-3 * rng.normal(size=n_steps)
    )
    du = np.abs(np.diff(u, prepend=0.0))
    probes = (u[:, None] + du[:, None] * rng.normal(scale=0.3, size=(n_steps, 8))).tolist()
    els = {k: v for k, v in elements().items() if not (exact_only and "sliders" in k)}
    best = {name: [math.inf, math.inf] for name in els}
    for _ in range(repeats):  # round-robin, so that a load change hits all alike
        for name, el in els.items():
            best[name][0] = min(best[name][0], _time_steps(el, u, probes, False))
            best[name][1] = min(best[name][1], _time_steps(el, u, probes, True))
    out = {}
    for name, (t1, t9) in best.items():
        trial = (t9 - t1) / 8.0
        out[name] = (trial * 1e6, (t1 - trial) * 1e6, t9 * 1e6)
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer timing samples")
    ap.add_argument("--repeats", type=int, default=None, help="timing repeats (default 5, 3 quick)")
    ap.add_argument(
        "--timing-only",
        action="store_true",
        help="skip the accuracy table and the slider banks (exact joints only)",
    )
    ap.add_argument(
        "--baseline",
        metavar="DIR",
        help="also time the IwanJoint of the iwan_element package under DIR",
    )
    args = ap.parse_args(argv)
    if args.baseline:
        _BASELINE["mod"] = load_baseline(args.baseline)
    print(f"Parameters: {PARAMS}  (phi_max = {PARAMS.phi_max:.4g} m)")
    print(f"python {platform.python_version()}, numpy {np.__version__}, {platform.machine()}\n")
    if not args.timing_only:
        names, rows = accuracy_table()
        print(
            "(a) relative error of dissipation per cycle (loop area of a simulated steady cycle)\n"
        )
        print("| r = u0/phi_max | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
        for r, errs in rows:
            print(f"| {r:g} | " + " | ".join(f"{e:.1e}" for e in errs) + " |")
    repeats = args.repeats or (3 if args.quick else 5)
    costs = cost_table(5000 if args.quick else 50000, repeats, exact_only=args.timing_only)
    print("\n(b) cost per call, best of repeats, measured side by side in this run\n")
    print(
        "| element | us per trial() | us per commit() | us per step (9 trials + commit) "
        "| trial cost / exact |"
    )
    print("|---|---|---|---|---|")
    base = costs["exact IwanJoint"][0]
    for name, (tr, cm, st) in costs.items():
        print(f"| {name} | {tr:.2f} | {cm:.2f} | {st:.2f} | {tr / base:.1f} |")


if __name__ == "__main__":
    main()
