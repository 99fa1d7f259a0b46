"""Every mode from one joint on the Brake-Reuss hammer record.

Run:  python benchmarks/bench_every_mode.py [--duration 1.2] [--no-coupling]
      [--no-prediction] [--no-two-bolt]

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

The data (GPL-3.0) are read in place from ``../shared/data/brb-hammer``; (a) and (b) are
skipped when it is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import brb_every_mode as example  # noqa: E402

from iwan_element import models  # noqa: E402


def prediction(d, duration: float):
    t0 = time.perf_counter()
    out = example.predict(d, duration=duration)
    wall = time.perf_counter() - t0
    print(out.report())
    rd = out.ringdown
    print(
        f"\n(a) wall time: {wall:.1f} s in all, {rd.wall_time:.1f} s in SolveDynamic for "
        f"{rd.metadata['steps']} steps ({1e3 * rd.wall_time / rd.metadata['steps']:.2f} ms "
        "per step)"
    )
    meas, pred = out.measured[(2, "acc3")], out.predicted[(2, "acc3")]
    print(
        f"    mode 2's first (coupled) measured window: {1e6 * meas.amplitude[0]:.3g} um, "
        f"f {meas.frequency[0]:.3f} Hz, zeta {100 * meas.damping_ratio[0]:.4f} %; the "
        f"prediction's first window: {1e6 * pred.amplitude[0]:.3g} um, f "
        f"{pred.frequency[0]:.3f} Hz ({100 * (pred.frequency[0] / meas.frequency[0] - 1):+.3f} %), "
        f"zeta {100 * pred.damping_ratio[0]:.4f} % "
        f"({100 * (pred.damping_ratio[0] / meas.damping_ratio[0] - 1):+.1f} %)"
    )
    return out


def coupling(out, duration: float):
    t0 = time.perf_counter()
    c = models.mode_coupling(out.calibration.specimen, amplitude=out.release, duration=duration)
    print(f"\n(b) {time.perf_counter() - t0:.1f} s")
    print(c.report().split("  warning:")[0])
    for r, s in c.summary().items():
        print(
            f"    mode {r}: largest damping raise by the other mode x{s['max_damping_ratio']:.3f} "
            f"at {1e6 * s['at_amplitude']:.3g} um (frequency {1e6 * s['frequency_shift']:+.0f} ppm)"
        )


def two_bolt():
    s = models.preset("two-bolt-aluminium").replace(modal_damping=(1e-3, 5e-4))
    t0 = time.perf_counter()
    c = models.mode_coupling(s, amplitude={1: 300e-6, 2: 20e-6}, duration=1.0)
    print(f"\n(d) two-bolt beam, {time.perf_counter() - t0:.1f} s")
    print(c.report().split("  warning:")[0])
    for r in c.modes:
        tc = c.together.mode_curve(r)
        q = models.modal_amplitude_curve(s, mode=r, amplitude=tc.amplitude)
        df = np.max(np.abs(tc.frequency / q.frequency - 1))
        dz = np.max(np.abs(tc.damping_ratio / q.damping_ratio - 1))
        print(
            f"    mode {r} with the other against QSMA: f {1e6 * df:.0f} ppm, "
            f"zeta {100 * dz:.1f} % at most"
        )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.2)
    ap.add_argument("--no-coupling", action="store_true")
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


if __name__ == "__main__":
    main()
