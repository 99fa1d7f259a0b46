"""The Brake-Reuss beam's linear structure updated on the hammer record's low-amplitude
modes, then the joint calibrated on mode 1, then the held-out modes predicted.

1. Linear targets (``iwan_element.free_decay_modes``): every band's latest linear window of
   the three accelerometers (docs/modal_targets.md).
2. ``models.linear_update`` of Young's modulus and the stuck interface's stiffness per area
   on the first and second height-bending frequencies only, for the 1-D Timoshenko beam and
   (``--solid``) the solid bodies; the in-plane bending (solid only) and the fourth height
   bending are predictions with their stated band.
3. ``models.calibration.calibrate`` of the joint (friction, chi, floor, and the stiffness
   per area again: how far the shared parameter moves) on mode 1's amplitude curve at acc3.

    python benchmarks/bench_linear_update.py [--solid] [--mesh 0.012] [--lap 0.0025]

Data: ``../shared/data/brb-hammer`` (GPL-3.0, read in place; Chen et al., MSSP 166:108401,
2022).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from iwan_element.models.calibration import calibrate, measured_amplitude_curve

import iwan_element as ie
from iwan_element import models

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "brb-hammer"
POSITIONS = {"acc1": 0.0254, "acc2": 0.5549, "acc3": 0.6438}
DIRECTIONS = {"acc1": 1, "acc2": -1, "acc3": -1}  # top face +y, bottom faces -y
BANDS = {"h1": (70.0, 90.0), "ip1": (205.0, 238.0), "h2": (275.0, 320.0), "h4": (800.0, 890.0)}


def hammer_targets():
    """The record's linear modal targets (ModalTargets) and the raw acc3 record."""
    rec, t = {}, None
    for name, x in POSITIONS.items():
        d = np.loadtxt(DATA / f"hammer_{name}.csv", delimiter=",", skiprows=1)
        t = d[:, 0]
        rec[name] = (x, d[:, 1])
    keep = t >= 0.0
    return ie.free_decay_modes(
        t[keep], {k: (x, a[keep]) for k, (x, a) in rec.items()}, directions=DIRECTIONS, bands=BANDS
    )


def target_table(tg):
    print("linear targets from the hammer record (free_decay_modes):")
    for m in tg.modes:
        print(
            f"  {m.label:4s} {m.frequency:10.4f} +- {tg.frequency_stderr[m.index]:.4f} Hz  zeta "
            f"{100 * m.damping_ratio:.4f} %  window {m.window[0]:.2f}-{m.window[1]:.2f} s  "
            f"linear {m.linear}"
        )


def update(spec, freqs, label, targets_modes, predict):
    t0 = time.perf_counter()
    r = models.linear_update(
        spec,
        frequencies=freqs,
        parameters=("youngs_modulus", "stiffness_per_area"),
        predict=predict,
    )
    print(f"\n{label}: linear update on modes {targets_modes} ({time.perf_counter() - t0:.1f} s)")
    print(r.report())
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--solid", action="store_true")
    ap.add_argument("--mesh", type=float, default=0.012)
    ap.add_argument("--lap", type=float, default=0.0025)
    ap.add_argument("--no-calibrate", action="store_true")
    a = ap.parse_args(argv)
    if not DATA.is_dir():
        print(f"{DATA} (GPL data, read in place) not found: nothing to do")
        return 0
    tg = hammer_targets()
    target_table(tg)
    f = {m.label: (tg.frequencies[m.index], tg.frequency_stderr[m.index]) for m in tg.modes}
    spec = models.preset("brake-reuss")
    # 1-D planar beam: modes 1, 2, 3, 4 = height bending 1..4
    r1 = update(spec, {1: f["h1"], 2: f["h2"]}, "1-D Timoshenko beam", (1, 2), (3, 4))
    fp, se = r1.predict(4)
    print(
        f"  4th height bending: predicted {fp:.2f} +- {se:.2f} Hz, measured "
        f"{f['h4'][0]:.2f}: {100 * (fp / f['h4'][0] - 1):+.2f} %"
    )
    if not a.no_calibrate:
        cal(r1.specimen)
    if a.solid:
        t0 = time.perf_counter()
        solid = models.solid_preset("brake-reuss", mesh_size=a.mesh, lap_mesh_size=a.lap)
        print(
            f"\nsolid built in {time.perf_counter() - t0:.0f} s: "
            f"{solid.model.info['n_full']} -> {solid.model.info['n_reduced']} coordinates"
        )
        print(
            "  nominal stuck frequencies:",
            np.round(models.natural_frequencies(solid, n_modes=12)[6:], 2),
        )
        # solid: 1 height 1, 2 in-plane 1, 3 height 2, 4 height 3, 5 in-plane 2, 6 height 4
        r2 = update(solid, {1: f["h1"], 3: f["h2"]}, "solid bodies", (1, 3), (2, 4, 5, 6))
        for m, key in ((2, "in-plane"), (6, "4th height")):
            fp, se = r2.predict(m)
            meas = f["ip1" if m == 2 else "h4"][0]
            print(
                f"  {key} (mode {m}): predicted {fp:.2f} +- {se:.2f} Hz, measured {meas:.2f}:"
                f" {100 * (fp / meas - 1):+.2f} % ({abs(fp - meas) / se:.2f} stderr)"
            )
        if not a.no_calibrate:
            c2 = cal(r2.specimen, solid=True)
            fs = models.natural_frequencies(c2.specimen, n_modes=12)[6:]
            print(
                "  calibrated solid, stuck: "
                + ", ".join(
                    f"{key} {fs[m - 1]:.2f} Hz ({100 * (fs[m - 1] / f[lab][0] - 1):+.2f} %)"
                    for key, m, lab in (
                        ("height 1", 1, "h1"),
                        ("in-plane", 2, "ip1"),
                        ("height 2", 3, "h2"),
                        ("height 4", 6, "h4"),
                    )
                )
            )
    return 0


def cal(spec, *, solid=False):
    """The joint on mode 1's amplitude curve at acc3 (the preset's calibration route),
    starting from the updated specimen: how far the shared stiffness per area moves.
    """
    curve = measured_amplitude_curve(DATA / "hammer_acc3.csv", start=0.2)
    t0 = time.perf_counter()
    k0 = spec.interface.stiffness_per_area
    c = calibrate(spec, curve, fit=("stiffness_per_area", "friction", "chi", "damping_floor"))
    k = c.params["stiffness_per_area"]
    print(
        f"\njoint calibrated on mode 1 ({time.perf_counter() - t0:.1f} s)"
        f"{' (solid)' if solid else ''}:"
    )
    print(c.report())
    print(
        f"  shared parameter stiffness_per_area: {k0:.4g} (linear update) -> {k.value:.4g} "
        f"+- {k.stderr:.2g} (calibration): {100 * (k.value / k0 - 1):+.1f} %"
    )
    return c


if __name__ == "__main__":
    sys.exit(main())
