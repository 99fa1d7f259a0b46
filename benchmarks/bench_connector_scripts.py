"""Cost per step of the Iwan connector swapped into three Exudyn scripts, against the spring it
replaced, with and without the energy recorder.

The scripts are the examples' from-scratch versions of Exudyn's own
(``examples/exudyn_duffing_sweep.py``: a coordinate spring-damper with a Python user
function, swept; ``examples/exudyn_cartesian_mass.py``: a built-in Cartesian spring-damper on
a mass point; ``examples/exudyn_rotor_bearing.py``: a reduced flexible rotor on built-in
Cartesian bearings). Variants per script, run interleaved in each round (the machine is
shared: compare ratios within one run):

* ``spring``        the script as it is (the reference, 1.0);
* ``iwan``          one spring-damper swapped for ``create_iwan_connector`` (default route);
* ``iwan+energy``   the same with ``record_energy`` attached (recording only: the states of
                    every accepted step);
* ``balance``       the energy balance evaluated after the run, per recorded step (not
                    part of the solve; listed for completeness).

Wall time of ``mbs.SolveDynamic`` only, the best of ``--repeat`` rounds, per step.

Run: ``python benchmarks/bench_connector_scripts.py [--repeat 5] [--quick]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import exudyn_cartesian_mass as cartesian
import exudyn_duffing_sweep as duffing
import exudyn_rotor_bearing as rotor


def _scripts(quick: bool):
    fem = rotor.truss_rotor()
    scale = 5 if quick else 1
    return {
        "duffing sweep (user-function coordinate spring)": (
            duffing,
            dict(steps=40_000 // scale),
            40_000 // scale,
        ),
        "Cartesian mass (built-in Cartesian spring)": (
            cartesian,
            dict(steps=100_000 // scale),
            100_000 // scale,
        ),
        "reduced rotor (built-in Cartesian bearing)": (
            rotor,
            dict(t_end=0.2 / scale, fem=fem),
            int(round(2000 / scale)),
        ),
    }


def _time(module, kw, variant):
    joint = "spring" if variant == "spring" else "iwan"
    model = module.build(joint, energy=variant == "iwan+energy", **kw)
    wall = module.run(model)
    extra = None
    if model.recorder is not None:
        t0 = time.perf_counter()
        model.recorder.balance()
        extra = time.perf_counter() - t0
    return wall, extra


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="interleaved rounds (best taken)")
    ap.add_argument("--quick", action="store_true", help="a fifth of the steps")
    args = ap.parse_args(argv)
    variants = ("spring", "iwan", "iwan+energy")
    print(f"{'script / variant':58s} {'us/step':>9s} {'/ spring':>9s}")
    for name, (module, kw, steps) in _scripts(args.quick).items():
        best = {v: float("inf") for v in variants}
        balance = float("inf")
        for _ in range(args.repeat):
            for v in variants:
                wall, extra = _time(module, kw, v)
                best[v] = min(best[v], wall)
                if extra is not None:
                    balance = min(balance, extra)
        print(f"{name} ({steps} steps)")
        for v in variants:
            us = 1e6 * best[v] / steps
            print(f"  {v:56s} {us:9.2f} {best[v] / best['spring']:9.2f}")
        print(f"  {'balance() afterwards, per recorded step':56s} {1e6 * balance / steps:9.2f}")


if __name__ == "__main__":
    main()
