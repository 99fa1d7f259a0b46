"""Memory of the Iwan connector and interface with ``record=False`` over long runs (tracemalloc).

Model: one mass (1 kg) on an Iwan joint (KT = 1e6 N/m, Fs = 1 kN, chi = -0.5, beta = 0.2) in
parallel with a linear spring (2e5 N/m), driven by a harmonic force (1.5 kN, 700 rad/s) into
steady forced vibration with microslip and macroslip, so the joint's reversal stack stays
bounded (a free decay would add two reversal points per cycle, physics rather than records).
Generalized-alpha, h = 10 us, one thread. The interface variant has ``--points`` such
oscillators, each with its own contact point.

For each variant the Python heap traced by ``tracemalloc`` is read after a short run of
``--warm`` steps and after a run of ``--steps`` steps (both from the start, each in a fresh
system); the difference is what the long run kept. With ``record=False`` it must stay within
``--bound`` bytes whatever the number of steps. With ``--compare-with DIR`` the connector
variants also run with ``DIR/iwan_element`` (an older revision).

Run: ``python benchmarks/bench_memory.py [--steps 1000000] [--warm 100000] [--bound 65536]``
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
import tracemalloc
from pathlib import Path

import exudyn as exu
from exudyn.itemInterface import (
    CoordinateSpringDamper,
    LoadCoordinate,
    MarkerNodeCoordinate,
    Mass1D,
    Node1D,
    NodePointGround,
)

import iwan_element
import iwan_element.exudyn

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_connector import PACKAGES, load_package

P = iwan_element.IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
H = 1e-5


def build(variant, points):
    name, _, tag = variant.partition("@")
    pkg = PACKAGES[tag]
    params = pkg.IwanParameters(Fs=P.Fs, KT=P.KT, chi=P.chi, beta=P.beta)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    n = points if name == "interface" else 1
    pairs = []
    for k in range(n):
        node = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
        mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
        m = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mg, m], stiffness=2e5))
        amp = 1500.0 * (1.0 + 0.1 * k)
        mbs.AddLoad(LoadCoordinate(markerNumber=m, loadUserFunction=_force(amp)))
        pairs.append((mg, m))
    if name == "interface":
        handle = pkg.exudyn.add_iwan_interface(mbs, pairs, [params] * n, record=False)
    else:
        kw = {} if tag else {"law": "python" if name == "connector-python" else "symbolic"}
        handle = pkg.exudyn.add_iwan_connector(
            mbs, list(pairs[0]), pkg.IwanJoint(params), record=False, **kw
        )
    mbs.Assemble()
    return SC, mbs, handle


def _force(amp):
    def load(mbs, t, load):
        return amp * math.sin(700.0 * t)

    return load


def traced_growth(variant, steps, points):
    SC, mbs, handle = build(variant, points)
    sim = exu.SimulationSettings()
    sim.timeIntegration.numberOfSteps = steps
    sim.timeIntegration.endTime = steps * H
    sim.timeIntegration.verboseMode = 0
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    t0 = time.perf_counter()
    mbs.SolveDynamic(sim)
    wall = time.perf_counter() - t0
    gc.collect()
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    return after - before, wall, handle


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1_000_000)
    ap.add_argument("--warm", type=int, default=100_000)
    ap.add_argument("--points", type=int, default=10)
    ap.add_argument("--bound", type=int, default=65536, help="allowed growth [bytes]")
    ap.add_argument("--compare-with", metavar="DIR")
    ap.add_argument(
        "--variants",
        default="connector-symbolic,connector-python,interface",
        help="comma-separated among connector-symbolic, connector-python, interface",
    )
    args = ap.parse_args(argv)
    variants = args.variants.split(",")
    if args.compare_with:
        PACKAGES["base"] = load_package(args.compare_with)
        variants = ["connector@base"] + variants
    print(
        f"record=False, generalized-alpha, h = {H:g} s, exudyn {exu.__version__}; traced Python "
        f"heap kept by a run of {args.warm} and of {args.steps} steps"
    )
    print(
        f"{'variant':<22} {'kept short [B]':>15} {'kept long [B]':>14} {'growth [B]':>11} "
        f"{'B/step':>8} {'wall long [s]':>13} {'within bound':>13}"
    )
    ok = True
    for v in variants:
        short, _, _ = traced_growth(v, args.warm, args.points)
        long_, wall, _ = traced_growth(v, args.steps, args.points)
        growth = long_ - short
        per = growth / (args.steps - args.warm)
        within = growth <= args.bound
        ok = ok and (within or "@base" in v)
        print(
            f"{v:<22} {short:15d} {long_:14d} {growth:11d} {per:8.3f} {wall:13.1f} "
            f"{'yes' if within else 'NO':>13}"
        )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
