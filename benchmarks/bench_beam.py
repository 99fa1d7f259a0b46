"""Cost of the lap-jointed beam routes: distributed Iwan interface vs linear springs, and QSMA.

Run:  python benchmarks/bench_beam.py [--points 50] [--cycles 20] [--repeat 3] [--profile]
      [--compare-with DIR]

(a) The Brake-Reuss specimen with ``--points`` contact strips (the points inside the pressure
    cones get an element), released from 60 um at the sensor, ``--cycles`` periods at 48
    steps per period (generalized-alpha, spectral radius 1): wall time of ``SolveDynamic``
    with the compiled multi-contact Iwan interface (``add_iwan_interface``), with one Python
    ``IwanJoint`` connector per point (reference route), and with built-in linear springs
    ``KT_i`` in their place; best of ``--repeat`` interleaved rounds (wall and CPU time,
    the CPU time being less sensitive to other load on a shared machine), with the Newton
    iterations per step of each route (same solver settings for all). Two labelled floors:
    ``linear+zero-law`` (the linear model plus one symbolic Cartesian connector per point
    whose law is zero: the cost of the extra connector objects alone) and
    ``symbolic-backbone`` (one symbolic connector per point whose law is the stateless Iwan
    virgin backbone along x plus the normal spring along y, the built-in springs switched
    off, no post-step function: the floor of any symbolic nonlinear law in the compiled
    route's one-object-per-point form, with its own Newton iterations per step; not a
    ring-down with hysteresis).
    With ``--compare-with DIR`` the compiled route is also run with the interface of the
    package in ``DIR/iwan_element`` (e.g. ``git archive main iwan_element | tar -x -C DIR``),
    interleaved (row ``compiled@base``).
(b) A QSMA f(X), zeta(X) curve of 20 amplitudes: first call (including the extraction of the
    linear matrices from Exudyn) and a repeated call on a changed friction coefficient.
(c) With ``--profile``, the main job ``examples/jointed_beam.py --quick`` under cProfile.
"""
from __future__ import annotations

import argparse
import cProfile
import io
import math
import pstats
import runpy
import sys
import tempfile
import time
from pathlib import Path

import exudyn as exu
import numpy as np

from iwan_element.models import modal_amplitude_curve, preset
from iwan_element.models.assembly import build_specimen_model
from iwan_element.models.qsma import static_modal_load
from iwan_element.models.solver import solver_settings


BASE = {}
_KEEP = []


def _base_interface(mbs, pairs, joints, stiffness=None, **kw):
    """``add_iwan_interface`` of the package loaded with ``--compare-with``; springs it
    cannot carry (``stiffness``, new) become built-in springs, as that package's model had."""
    from exudyn.itemInterface import ObjectConnectorCartesianSpringDamper
    pkg = BASE["pkg"]
    for (m0, m1), k in zip(pairs, stiffness if stiffness is not None else []):
        mbs.AddObject(ObjectConnectorCartesianSpringDamper(
            markerNumbers=[m0, m1], stiffness=list(k), damping=[0.0, 0.0, 0.0]))
    conv = [pkg.IwanParameters(Fs=p.Fs, KT=p.KT, chi=p.chi, beta=p.beta) for p in joints]
    return pkg.exudyn.add_iwan_interface(mbs, pairs, conv, **kw)


def _add_floor_connectors(model, law: str) -> None:
    """One symbolic Cartesian connector per contact point, without post-step: a zero law, or
    the stateless Iwan virgin backbone of the point along x plus its normal spring along y
    in place of the built-in springs (the floors in the docstring)."""
    from exudyn.advancedUtilities import CreateSymbolicUserFunction
    from exudyn.itemInterface import ObjectConnectorCartesianSpringDamper
    esym = exu.symbolic
    def make(p, kn):
        a, e1, pm = p.R / ((p.chi + 1.0) * (p.chi + 2.0)), p.chi + 1.0, p.phi_max

        def uf(mbs_, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            u = displacement[0]
            if law == "zero":
                fx = u * 0.0
            else:
                x = esym.abs(u)
                fx = esym.sign(u) * esym.IfThenElse(x < pm, x * (p.KT - a * esym.pow(x, e1)),
                                                    esym.Real(p.Fs))
            fy = esym.Real(0.0) if law == "zero" else displacement[1] * kn
            return [fx, fy, esym.Real(0.0)]
        return uf

    if law != "zero":
        for s in model.springs:
            model.mbs.SetObjectParameter(s, "activeConnector", False)
    for (ma, mb), p, kn in zip(model.marker_pairs, model.points.params,
                               model.points.normal_stiffness):
        uf = make(p, float(kn))
        fn = CreateSymbolicUserFunction(model.mbs, uf, "springForceUserFunction",
                                        itemTypeName="ObjectConnectorCartesianSpringDamper")
        _KEEP.append(fn)                   # the expression must outlive the run
        model.mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[ma, mb],
                                                                 springForceUserFunction=fn))
    model.mbs.Assemble()


def transient(spec, route: str, cycles: float, spp: int = 48) -> tuple:
    """(wall [s], CPU [s] of SolveDynamic, steps, contact points, Newton iterations per step)
    for one route."""
    st = static_modal_load(spec, [60e-6])
    L, w0 = st["system"], st["omega0"]
    if route in ("linear", "linear+zero-law"):
        model = build_specimen_model(spec, tangential="linear")
        if route != "linear":
            _add_floor_connectors(model, "zero")
    elif route == "symbolic-backbone":
        model = build_specimen_model(spec, tangential="none")
        _add_floor_connectors(model, "backbone")
    elif route == "compiled@base":
        import iwan_element.models.assembly as asm
        own = asm.add_iwan_interface
        asm.add_iwan_interface = _base_interface
        try:
            model = build_specimen_model(spec, tangential="iwan")
        finally:
            asm.add_iwan_interface = own
    else:
        model = build_specimen_model(spec, tangential="iwan", joint_elements=(route == "python"))
    x0 = np.zeros(L.n_coordinates)
    x0[L.free] = st["x"][0]
    for cfg in (exu.ConfigurationType.Initial, exu.ConfigurationType.Current):
        model.mbs.systemData.SetODE2Coordinates(x0, configuration=cfg)
    h = 2 * math.pi / (w0 * spp)
    n = int(round(cycles * spp))
    sim = solver_settings(force_scale=float(np.max(np.abs(L.K0 @ st["x"][0]))))
    sim.timeIntegration.numberOfSteps = n
    sim.timeIntegration.endTime = n * h
    t0, c0 = time.perf_counter(), time.process_time()
    model.mbs.SolveDynamic(sim)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    newton = model.mbs.sys["dynamicSolver"].it.newtonStepsCount / n
    return wall, cpu, n, len(model.points), newton


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=50)
    ap.add_argument("--cycles", type=float, default=20)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--compare-with", metavar="DIR",
                    help="also run the compiled route with DIR/iwan_element (row 'compiled@base')")
    ap.add_argument("--no-floors", action="store_true", help="skip the two floor rows")
    args = ap.parse_args(argv)
    spec = preset("brake-reuss").replace(n_points=args.points, damping_floor=0.0)
    routes = ["linear", "compiled", "python"]
    if args.compare_with:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from bench_connector import load_package
        BASE["pkg"] = load_package(args.compare_with)
        routes.insert(1, "compiled@base")
    if not args.no_floors:
        routes += ["linear+zero-law", "symbolic-backbone"]
    best = {r: [math.inf, math.inf, math.nan] for r in routes}
    for _ in range(args.repeat):           # interleaved rounds: load changes hit all routes
        for route in routes:
            wall, cpu, steps, npts, newton = transient(spec, route, args.cycles)
            b = best[route]
            best[route] = [min(b[0], wall), min(b[1], cpu), newton]
    print(f"(a) Brake-Reuss ring-down, {npts} contact points with an element "
          f"({args.points} strips), {steps} steps, best of {args.repeat} interleaved rounds")
    print("| interface | wall [s] | us per step | ratio to linear | CPU ratio | Newton it/step |")
    print("|---|---|---|---|---|---|")
    lw, lc = best["linear"][0], best["linear"][1]
    for k in routes:
        w, c, newton = best[k]
        print(f"| {k} | {w:.3f} | {w / steps * 1e6:.0f} | {w / lw:.2f} | {c / lc:.2f} | "
              f"{newton:.2f} |")
    amps = np.geomspace(2e-6, 60e-6, 20)
    fresh = spec.replace(n_points=args.points + 1)          # not in the matrix cache yet
    t0 = time.perf_counter()
    modal_amplitude_curve(fresh, amplitude=amps)
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    modal_amplitude_curve(fresh.replace(friction=0.3), amplitude=amps)
    warm = time.perf_counter() - t0
    print(f"\n(b) QSMA, 20 amplitudes, {args.points + 1} strips: first call {cold:.3f} s "
          f"(matrix extraction included), changed friction {warm:.3f} s")
    if args.profile:
        script = Path(__file__).resolve().parents[1] / "examples" / "jointed_beam.py"
        out = Path(tempfile.mkdtemp()) / "jb"
        argv0 = sys.argv
        sys.argv = [str(script), "--quick", "--out", str(out)]
        prof = cProfile.Profile()
        t0 = time.perf_counter()
        try:
            prof.enable()
            runpy.run_path(str(script), run_name="__main__")
            prof.disable()
        finally:
            sys.argv = argv0
        s = io.StringIO()
        pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(14)
        print(f"\n(c) main job --quick: {time.perf_counter() - t0:.1f} s wall under cProfile\n")
        print(s.getvalue())


if __name__ == "__main__":
    main()
