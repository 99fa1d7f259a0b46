"""Cost of the exact Masing kernel: compiled (numba) vs vectorised numpy vs per-sample Python.

Run:  python benchmarks/bench_kernel.py [--n 20000] [--baseline DIR]

One displacement history of ``n`` samples (a slowly drifting sine of 20 cycles plus noise
that adds small reversals, as in a measured record), one parameter set. Timed in one run,
best of several repeats, one core:

* ``kernel``: :func:`iwan_element.core.masing.masing_history` (force, tangent, work and
  dissipation of every sample), and the same for a batch of 16 parameter sets (per set);
* ``numpy``: the vectorised route of :class:`iwan_element.core.history.History`: the
  reversal structure once (compiled walk), then the forces of a parameter set with numpy;
* ``element``: :class:`~iwan_element.IwanJoint` ``trial``/``commit`` per sample (the Python fast
  path on a branch, the kernel at reversals);
* ``--baseline DIR``: the same routes of another checkout (its ``iwan_element`` under DIR,
  e.g. ``git archive <commit> iwan_element | tar -x -C DIR``), where they exist: before the
  kernel, the structure walk and the element's reversal walk were Python.

The per-call cost of ``IwanJoint.trial`` (fast path, and at a reversal every call) is also
printed, since the Exudyn connector calls it once per step.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def load(src: str, name: str):
    init = Path(src) / "iwan_element" / "__init__.py"
    spec = importlib.util.spec_from_file_location(
        name, init, submodule_search_locations=[str(init.parent)]
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def best(f, repeat=5):
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        out.append(time.perf_counter() - t0)
    return min(out)


def history(n, p, rng):
    t = np.linspace(0.0, 20.0, n)
    return p.phi_max * (
        1.5 * np.sin(2 * np.pi * t) * (1 + 0.2 * t / 20) + 0.002 * rng.normal(size=n)
    )


def routes(pkg, label, u, ps):
    """(label, seconds per history and parameter set) for the routes ``pkg`` has."""
    from importlib import import_module

    try:  # the module's name before and after it went public
        hist_mod = import_module(pkg.__name__ + ".core.history")
    except ImportError:
        hist_mod = import_module(pkg.__name__ + ".core._history")
    p = ps[0]
    tol = 1e-12 * p.phi_max
    rows = []
    walk = getattr(hist_mod, "walk", None)  # the Python walk before the kernel
    if walk is None:
        walk = import_module(pkg.__name__ + ".core.masing").reversal_structure
    rows.append((f"{label} reversal structure walk", best(lambda: walk(u, tol), 3)))
    rows.append(
        (
            f"{label} numpy: structure + forces",
            best(lambda: hist_mod.History(u, tol=tol).forces(p), 3),
        )
    )
    h = hist_mod.History(u, tol=tol)
    rows.append((f"{label} numpy: forces of a known structure", best(lambda: h.forces(p))))

    def element():
        j = pkg.IwanJoint(p)
        tr, cm = j.trial, j.commit
        for x in u.tolist():
            tr(x)
            cm()

    rows.append((f"{label} element: trial/commit per sample", best(element, 3)))
    try:
        masing = import_module(pkg.__name__ + ".core.masing")
    except ImportError:
        return rows
    masing.masing_history(u[:10], p)  # compile (or load the cache)
    rows.append((f"{label} kernel: F, K, W, D", best(lambda: masing.masing_history(u, p))))
    rows.append(
        (
            f"{label} kernel: batch of {len(ps)}, per set",
            best(lambda: masing.masing_history(u, ps)) / len(ps),
        )
    )
    return rows


def per_call(pkg, label, p):
    j = pkg.IwanJoint(p)
    x = np.linspace(0, 0.5 * p.phi_max, 200001).tolist()
    j.trial(x[1])
    j.commit()
    tr, cm = j.trial, j.commit

    def fast():
        for v in x[2:]:
            tr(v)

    t_fast = best(fast, 3) / (len(x) - 2)
    zig = (
        p.phi_max * 0.3 * np.where(np.arange(100001) % 2, 1.0, -1.0) * np.linspace(1.0, 0.5, 100001)
    ).tolist()

    def slow():
        j.reset()
        for v in zig:
            tr(v)
            cm()

    t_slow = best(slow, 3) / len(zig)
    return [
        (f"{label} IwanJoint.trial, fast path [per call]", t_fast),
        (f"{label} trial+commit, a reversal every step [per call]", t_slow),
    ]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20000)
    ap.add_argument("--baseline", default=None)
    args = ap.parse_args(argv)
    import iwan_element as cur

    rng = np.random.default_rng(0)
    ps = [cur.IwanParameters(1000.0 * (1 + 0.01 * k), 1e6, -0.5, 0.1) for k in range(16)]
    u = history(args.n, ps[0], rng)
    rows = routes(cur, "this", u, ps)
    calls = per_call(cur, "this", ps[0])
    if args.baseline:
        base = load(args.baseline, "iwan_element_baseline")
        bps = [base.IwanParameters(p.Fs, p.KT, p.chi, p.beta) for p in ps]
        rows += routes(base, "baseline", u, bps)
        calls += per_call(base, "baseline", bps[0])
    print(
        f"history of {args.n} samples, {int(np.sum(np.diff(np.sign(np.diff(u))) != 0))} reversals"
    )
    for name, t in rows:
        print(f"{name:<52} {t * 1e3:10.3f} ms   {t / args.n * 1e9:8.1f} ns/sample")
    for name, t in calls:
        print(f"{name:<60} {t * 1e6:8.3f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
