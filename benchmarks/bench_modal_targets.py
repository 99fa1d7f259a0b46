"""Brake-Reuss beam: linear modal targets from the hammer ring-down and the lowest sweep level.

Reads, in place, the GPL-3.0 data in ../shared/data (never copied into this project):

* ``brb-hammer/hammer_acc{1,2,3}.csv``: the three-accelerometer ring-down, through
  ``free_decay_modes`` with one band per mode the data README lists (80.4, 221.7, 297.7,
  845.6 and 1527 Hz) and with the automatic bands; acc1 (top face) is taken as measuring
  +y, acc2 and acc3 (bottom face) as measuring -y (``directions``), so that the shapes share
  one axis;
* ``brb-steppedsine-fc/fc_sweeps.csv``: the force-controlled sweeps' lowest level through
  ``sweep_modes`` (linear single mode, real modal constant), against ``sweep_curve``'s
  modal constant fitted over all levels.

Prints the targets with their standard errors, windows and drifts, and the wall times:

    PYTHONPATH=. python benchmarks/bench_modal_targets.py [--auto]
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from iwan_element import free_decay_modes, read_sweep_csv, sweep_curve, sweep_modes

POSITIONS = {"acc1": 0.0254, "acc2": 0.5549, "acc3": 0.6438}
BANDS = {
    "80.4": (70.0, 90.0),
    "221.7": (205.0, 238.0),
    "297.7": (275.0, 320.0),
    "845.6": (800.0, 890.0),
    "1527": (1450.0, 1600.0),
}


def shared_file(*parts):
    for parent in Path(__file__).resolve().parents:
        f = parent.joinpath("shared", "data", *parts)
        if f.is_file():
            return f
    return None


def hammer_records():
    recs, n = {}, 0
    for name, x in POSITIONS.items():
        a = np.loadtxt(shared_file("brb-hammer", f"hammer_{name}.csv"), delimiter=",", skiprows=1)
        recs[name] = (x, a[:, 1])
        n = a.shape[0]
    return -0.01 + np.arange(n) / 12800.0, recs  # exact sample instants (README)


def print_targets(r):
    print(
        f"{'mode':>4} {'f [Hz]':>10} {'+-':>8} {'zeta [%]':>9} {'+-':>7} {'window [s]':>13} "
        f"{'X [um]':>15} {'drift f [Hz]':>14} linear  shape acc1 : acc2 : acc3 (+-)"
    )
    for m in r.modes:
        v = m.shape.real / m.shape.real[np.argmax(np.abs(m.shape.real))]
        e = m.shape_std[:, 0] / abs(m.shape.real[np.argmax(np.abs(m.shape.real))])
        shape = " : ".join(f"{a:+.4f}({b:.1g})" for a, b in zip(v, e))
        print(
            f"{m.index:4d} {m.frequency:10.4f} {m.frequency_stderr:8.2g} "
            f"{100 * m.damping_ratio:9.4f} {100 * m.damping_ratio_stderr:7.2g} "
            f"{m.window[0]:6.3f}-{m.window[1]:<6.3f} "
            f"{1e6 * m.amplitude_range[0]:7.3g}-{1e6 * m.amplitude_range[1]:<7.3g} "
            f"{m.frequency_drift:+9.4f}+-{m.frequency_drift_std:<4.1g} "
            f"{'yes' if m.linear else 'no':>6}  {shape}"
        )


def main():
    if shared_file("brb-hammer", "hammer_acc1.csv") is None:
        print("../shared/data/brb-hammer not found: nothing to measure")
        return
    t, recs = hammer_records()
    directions = {"acc1": 1, "acc2": -1, "acc3": -1}
    runs = [("bands of the data README", BANDS)]
    if "--auto" in sys.argv:  # about 90 s: the record's spectrum has ~50 small peaks
        runs.append(("automatic bands", None))
    for label, bands in runs:
        t0 = time.perf_counter()
        r = free_decay_modes(t, recs, directions=directions, bands=bands)
        dt = time.perf_counter() - t0
        print(f"\nHammer ring-down, {label} ({dt:.2f} s): {len(r.modes)} modes")
        if bands is None:  # the spectrum of the real record has many small peaks
            print("  frequencies [Hz]:", ", ".join(f"{f:.1f}" for f in r.frequencies.values()))
            continue
        print_targets(r)
        for w in r.warnings:
            print("  warning:", w)
        print("  notes:", r.notes)
    path = shared_file("brb-steppedsine-fc", "fc_sweeps.csv")
    if path is None:
        return
    d = read_sweep_csv(path)
    low = np.asarray(d["level"]) == np.min(d["level"])
    t0 = time.perf_counter()
    s = sweep_modes(
        d["f"][low], d["F"][low], d["response"][low], d["phase"][low], quantity=d["quantity"]
    )
    dt = time.perf_counter() - t0
    m = s.modes[0]
    print(f"\nForce-controlled sweeps, level 1 alone, linear single mode ({dt:.3f} s):")
    print(
        f"  f = {m.frequency:.4f} +- {m.frequency_std:.2g} Hz, zeta = "
        f"{100 * m.damping_ratio:.4f} +- {100 * m.damping_ratio_std:.2g} %, c = "
        f"{m.modal_constant:.4f} +- {m.modal_constant_std:.2g} 1/kg; points X "
        f"{1e6 * m.amplitude_range[0]:.3g}-{1e6 * m.amplitude_range[1]:.3g} um"
    )
    print("  ", s.notes)
    for w in s.warnings:
        print("  warning:", w)
    c = sweep_curve(**d)
    import re

    print("  sweep_curve over all levels:", re.search(r"modal constant c = [^;]*", c.notes)[0])


if __name__ == "__main__":
    main()
