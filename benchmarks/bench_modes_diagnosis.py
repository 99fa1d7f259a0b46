"""The discrepancy workflow across modes on the Brake-Reuss hammer record, with a held-out test.

Run:  python benchmarks/bench_modes_diagnosis.py [--duration 1.2] [--json out.json]
      python benchmarks/bench_modes_diagnosis.py --generated

``--generated``: first on a generated two-mode hammer test with a hidden interface effect of
the benchmark's own making (:func:`generated`): the records are an Exudyn ring-down of the
beam with the hidden patch, read like the measured ones; the workflow (QSMA) must name it.

1. The hammer route (``examples/brb_every_mode.py``: ``models.predict_hammer_test``, joint
   calibrated on mode 1 at acc3, mode 2's floor from its lowest amplitudes, the two-mode
   ring-down from the measured release).
2. ``models.diagnose_hammer_test``: ``diagnose_modes`` on modes 1 and 2 at acc3, each over
   the amplitudes the prediction covers (each mode's diagnosis, every named effect in the
   joint at every placement, every mode read again by QSMA), then the best candidates rung
   down again from the measured release and read like the record, which names.
3. The hammer test through the named joint: every curve at every sensor against the record,
   plain and augmented (mode 2's curve informed the effect: on mode 2 this is a fit; mode 1
   and the held-out test are its check).
4. Held out: the force-controlled stepped-sine sweeps (``brb-steppedsine-fc``, never read by
   steps 1-3), predicted by harmonic balance at the measured frequencies and forces
   (``examples/brb_stepped_sine.py``'s comparison) with the plain and the augmented joint.

Data (GPL-3.0) are read in place from ``../shared/data``; nothing runs without them.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import bench_cross_test as cross  # noqa: E402
import brb_every_mode as hammer_example  # noqa: E402
import brb_stepped_sine as sweeps_example  # noqa: E402
from iwan_element.models.simulation import compare_curves  # noqa: E402

from iwan_element import models  # noqa: E402


def held_out(plain, augmented, quick: bool) -> dict:
    """Every stepped-sine level by harmonic balance, plain and augmented: rms log amplitude
    and rms phase errors.
    """
    d = sweeps_example.data_dir()
    levels = sweeps_example.read_levels(d / "brb-steppedsine-fc" / "fc_sweeps.csv", quick=quick)
    out = {}
    for lev, (f, F, X, ph) in levels.items():
        out[lev] = {}
        for name, s in (("plain", plain), ("augmented", augmented)):
            _, row = sweeps_example.compare(s, f, F, X, ph)
            out[lev][name] = row
        p, a = out[lev]["plain"], out[lev]["augmented"]
        print(
            f"| {lev} | {X.max() * 1e6:.0f} um | {p['rms_log_amplitude']:.3f}, "
            f"{p['rms_phase']:.3f} | {a['rms_log_amplitude']:.3f}, {a['rms_phase']:.3f} |"
        )
    return out


#: The hidden effect of ``--generated`` (tests/test_mode_diagnosis.py's, there on QSMA curves):
#: a patch under the middle bolt that slides from 20 nm, 0.8 of its points' stuck stiffness.
HIDDEN = {"k_2": 1.1e8, "u_s": 2.0e-8, "shape": 0.25}
#: Time steps per period of the highest mode in the generated records: the trapezoidal rule
#: lengthens a period by (w h)^2 / 12, 0.08 % at 64 steps, which QSMA (the workflow's
#: reading) does not have; 0.005 % at 256.
STEPS = 256


def generated(duration: float) -> None:
    """The workflow on a two-mode hammer test made by the beam with a hidden patch: records
    at acc3 and acc2 of a ``duration`` [s] ring-down from 40 um (mode 1) and 5 um (mode 2),
    long enough for mode 2 to fall below the patch's onset (its floor is read from its
    lowest amplitudes); the hammer route from the beam without the patch (chi wrong, fitted
    on mode 1); ``diagnose_modes`` on both modes over the amplitudes the prediction covers;
    the test rung down again through the named joint.
    """
    from iwan_element.models.specimens.effects import InterfaceEffect

    base = models.preset("brake-reuss").replace(
        n_points=16, modal_damping=(1.3e-3, 1e-3), calibrated_range=None
    )
    truth = base.replace(
        interface_effects=(InterfaceEffect("macroslip_onset", values=HIDDEN, where="bolt2"),)
    )
    x2 = hammer_example.SENSORS["acc2"]
    t0 = time.perf_counter()
    rd = models.ringdown(
        truth,
        amplitude={1: 40e-6, 2: 5e-6},
        sensors=(truth.sensor_position, x2),
        duration=duration,
        steps_per_period=STEPS,
    )
    recs = {
        "acc3": (truth.sensor_position, rd.t, rd.sensor_acceleration[0]),
        "acc2": (x2, rd.t, rd.sensor_acceleration[1]),
    }
    out = models.predict_hammer_test(
        base.replace(chi=-0.3),
        recs,
        fit=("chi",),
        release_time=0.02,
        fit_span=0.2,
        duration=duration - 0.1,
        calibration_periods=10,
        update=None,
    )
    print(f"generated record and hammer route ({time.perf_counter() - t0:.0f} s)")
    print(
        f"chi: truth {truth.interface.chi:.4f}, calibrated on mode 1 "
        f"{out.calibration.specimen.interface.chi:.4f}"
    )
    diag = models.diagnose_hammer_test(
        out,
        # noise-free records: the noise is the two routes' agreement (a transient's curve
        # against QSMA, docs/multi_mode.md section 1), not a scatter the records lack
        frequency_noise=1e-4,
        damping_ratio_noise=0.02,
    )
    print(diag.report())
    print(f"hidden: macroslip_onset at bolt2 {HIDDEN}")
    cross.table(out, out.predicted, "plain joint")
    for c in diag.checked[1:]:
        cross.table(out, c.predicted, f"joint + {c.label} ({c.probability:.3g})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=1.2, help="ring-down length [s]")
    ap.add_argument("--quick-sweeps", action="store_true", help="level 4, every 4th point")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--generated", action="store_true", help="the generated record only")
    a = ap.parse_args(argv)
    if a.generated:
        generated(1.6)
        return 0
    d = hammer_example.data_dir()
    if d is None or sweeps_example.data_dir() is None:
        print("../shared/data (GPL data, read in place) not found: nothing to do")
        return 0
    t0 = time.perf_counter()
    out = hammer_example.predict(d, duration=a.duration)
    print(f"1. hammer route ({time.perf_counter() - t0:.0f} s)")
    spec = out.calibration.specimen
    t1 = time.perf_counter()
    diag = models.diagnose_hammer_test(out)
    print(f"2. diagnose_hammer_test ({time.perf_counter() - t1:.1f} s)")
    print(diag.report())
    cross.table(out, out.predicted, "plain joint (route of step 1)")
    for c in diag.checked[1:]:  # every candidate the ring-down read, at every sensor
        cross.table(out, c.predicted, f"joint + {c.label} ({c.probability:.3g})")
    res: dict = {"diagnosis": diag.to_dict()}
    if diag.named is not None:
        curves = diag.named.predicted
        print(f"3. the named joint: {diag.named.label}")
        for sensor in ("acc3", "acc2"):
            cross.early_windows(out, curves, sensor)
        res["augmented_summary"] = {
            f"mode {r} at {n}": compare_curves(c, out.measured[(r, n)])
            for (r, n), c in curves.items()
        }
        print("\n4. held out: force-controlled sweeps (rms log amplitude, rms phase [rad])")
        print("| level | peak | plain joint | augmented |\n|---|---|---|---|")
        res["held_out"] = held_out(spec, diag.specimen, a.quick_sweeps)
    if a.json:
        from iwan_element.base.serialize import json_safe

        a.json.write_text(json.dumps(json_safe(res), indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
