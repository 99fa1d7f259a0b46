"""Every mode from one joint on the Brake-Reuss hammer record, and the floor matrix's cost.

Run:  python benchmarks/bench_every_mode.py [--duration 1.2] [--no-coupling] [--no-cost]
      [--no-prediction] [--repeat 3]

(a) ``examples/brb_every_mode.py``'s prediction: calibrate the beam on mode 1 at acc3 and
    each mode's floor on its lowest amplitudes, release modes 1 and 2 together 50 ms after
    the impact (amplitudes read off the record), ring down ``--duration`` seconds (both
    modes through the same interface), read the predicted records at acc3 and acc2 like the
    measured ones; each curve against the measured one at the same amplitudes (targets of
    issue 33: mode 1 within 0.05 % in frequency and 15 % in damping, mode 2 within 0.1 % and
    20 %), the first (coupled) measured window of mode 2 against the prediction's first
    window, the ratio of mode 2's amplitudes at acc2 and acc3, and the wall time.
(b) The coupling: ``models.mode_coupling`` of the calibrated beam from the same release
    (each mode's damping with and without the other).
(d) The two-bolt aluminium beam (clamped-free) through the same route: modes 1 and 2
    released together from 300 and 20 um at the tip, floors 0.1 % and 0.05 %, 1 s,
    ``mode_coupling`` against each mode alone and each mode's curve against QSMA.
(c) The per-step cost of the damping floor on the single-mode ring-down (Brake-Reuss, 60 um,
    20 periods, 48 steps per period): no floor, the stiffness-proportional beam damping
    used up to issue 33 (Cable2D bending and axial damping ``beta EI``, ``beta EA``,
    ``beta = 2 zeta w / phi^T K_b phi``), and the modal damping matrix (``ObjectGenericODE2``);
    best of ``--repeat`` interleaved rounds.

The data (GPL-3.0) are read in place from ``../shared/data/brb-hammer``; (a) and (b) are
skipped when it is absent.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import exudyn as exu
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import brb_every_mode as example                      # noqa: E402

from iwan_element import models                        # noqa: E402
from iwan_element.models import transient              # noqa: E402
from iwan_element.models.qsma import linear_modes      # noqa: E402


def prediction(d, duration: float):
    t0 = time.perf_counter()
    out = example.predict(d, duration=duration)
    wall = time.perf_counter() - t0
    print(out.report())
    rd = out.ringdown
    print(f"\n(a) wall time: {wall:.1f} s in all, {rd.wall_time:.1f} s in SolveDynamic for "
          f"{rd.metadata['steps']} steps ({1e3 * rd.wall_time / rd.metadata['steps']:.2f} ms "
          "per step)")
    meas, pred = out.measured[(2, "acc3")], out.predicted[(2, "acc3")]
    print(f"    mode 2's first (coupled) measured window: {1e6 * meas.amplitude[0]:.3g} um, "
          f"f {meas.frequency[0]:.3f} Hz, zeta {100 * meas.damping_ratio[0]:.4f} %; the "
          f"prediction's first window: {1e6 * pred.amplitude[0]:.3g} um, f "
          f"{pred.frequency[0]:.3f} Hz ({100 * (pred.frequency[0] / meas.frequency[0] - 1):+.3f} %), "
          f"zeta {100 * pred.damping_ratio[0]:.4f} % "
          f"({100 * (pred.damping_ratio[0] / meas.damping_ratio[0] - 1):+.1f} %)")
    return out


def coupling(out, duration: float):
    t0 = time.perf_counter()
    c = models.mode_coupling(out.calibration.specimen, amplitude=out.release,
                             duration=duration)
    print(f"\n(b) {time.perf_counter() - t0:.1f} s")
    print(c.report().split("  warning:")[0])
    for r, s in c.summary().items():
        print(f"    mode {r}: largest damping raise by the other mode x{s['max_damping_ratio']:.3f} "
              f"at {1e6 * s['at_amplitude']:.3g} um (frequency {1e6 * s['frequency_shift']:+.0f} ppm)")


def _stiffness_proportional(mbs, nodes, floor, free, n_coordinates):
    """The floor as the stiffness-proportional beam damping used up to issue 33."""
    spec = _stiffness_proportional.specimen
    w0, phi, _, L, _ = linear_modes(spec)
    beta = 2.0 * spec.floor(1) * w0 / float(phi @ L.Kb @ phi)
    for e in range(mbs.systemData.NumberOfObjects()):
        if mbs.GetObject(e)["objectType"] == "ANCFCable2D":
            for k, v in (("bendingDamping", "bendingStiffness"), ("axialDamping", "axialStiffness")):
                mbs.SetObjectParameter(e, k, beta * mbs.GetObjectParameter(e, v))


def floor_cost(repeat: int):
    spec = models.preset("brake-reuss")
    _stiffness_proportional.specimen = spec
    own, own_build, own_solve = (transient.attach_floor_damping, transient.build_specimen_model,
                                 exu.MainSystem.SolveDynamic)
    last = {}

    def build(*a, **k):                    # keep the model: its Newton count
        last["model"] = own_build(*a, **k)
        return last["model"]

    def solve(mbs, *a, **k):               # CPU time of SolveDynamic (less load-sensitive)
        c0 = time.process_time()
        out = own_solve(mbs, *a, **k)
        last["cpu"] = time.process_time() - c0
        return out

    routes = {"no floor": (spec.replace(damping_floor=0.0), own),
              "stiffness-proportional (before)": (spec, _stiffness_proportional),
              "modal matrix (now)": (spec, own)}
    best = {k: (np.inf, np.inf, None, None) for k in routes}
    transient.build_specimen_model, exu.MainSystem.SolveDynamic = build, solve
    try:
        for _ in range(repeat):
            for name, (s, attach) in routes.items():
                transient.attach_floor_damping = attach
                r = models.ringdown(s, amplitude=60e-6, cycles=20, steps_per_period=48)
                it = last["model"].mbs.sys["dynamicSolver"].it.newtonStepsCount
                w, c, _, _ = best[name]
                best[name] = (min(w, r.wall_time), min(c, last["cpu"]), r, it)
    finally:
        transient.attach_floor_damping, transient.build_specimen_model = own, own_build
        exu.MainSystem.SolveDynamic = own_solve
    print(f"\n(c) per-step cost of the floor, best of {repeat} (Brake-Reuss, 60 um, 960 steps)")
    for name, (wall, cpu, r, it) in best.items():
        c, n = r.curve, r.metadata["steps"]
        print(f"    {name:32s} {1e3 * wall / n:.3f} ms/step wall, {1e3 * cpu / n:.3f} CPU, "
              f"{it / n:.2f} Newton/step; zeta {100 * c.damping_ratio.min():.4f}-"
              f"{100 * c.damping_ratio.max():.4f} %, f {c.frequency.min():.4f}-"
              f"{c.frequency.max():.4f} Hz")


def two_bolt():
    s = models.preset("two-bolt-aluminium").replace(modal_damping=(1e-3, 5e-4))
    t0 = time.perf_counter()
    c = models.mode_coupling(s, amplitude={1: 300e-6, 2: 20e-6}, duration=1.0)
    print(f"\n(d) two-bolt beam, {time.perf_counter() - t0:.1f} s")
    print(c.report().split("  warning:")[0])
    for r in c.modes:
        tc = c.together.mode_curve(r)
        q = models.modal_amplitude_curve(s, mode=r, amplitude=tc.amplitude)
        print(f"    mode {r} with the other against QSMA: f {1e6 * np.max(np.abs(tc.frequency / q.frequency - 1)):.0f} "
              f"ppm, zeta {100 * np.max(np.abs(tc.damping_ratio / q.damping_ratio - 1)):.1f} % at most")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-coupling", action="store_true")
    ap.add_argument("--no-cost", action="store_true")
    ap.add_argument("--no-prediction", action="store_true", help="skip (a) and (b)")
    ap.add_argument("--no-two-bolt", action="store_true", help="skip (d)")
    a = ap.parse_args(argv)
    d = None if a.no_prediction else example.data_dir()
    if a.no_prediction:
        pass
    elif d is None:
        print("../shared/data/brb-hammer not found: (a) and (b) skipped")
    else:
        out = prediction(d, a.duration)
        if not a.no_coupling:
            coupling(out, a.duration)
    if not a.no_two_bolt:
        two_bolt()
    if not a.no_cost:
        floor_cost(a.repeat)


if __name__ == "__main__":
    main()
