"""Every mode from one joint: calibrate the Brake-Reuss beam on mode 1, predict mode 2.

One call, ``models.predict_hammer_test`` (``models/calibration/hammer.py``), which any hammer test
of a beam specimen can go through (records at positions along the axis):

1. The beam model (``models.preset("brake-reuss")``) is calibrated on mode 1 of the hammer
   ring-down at accelerometer 3 (``calibrate``, as ``brb_discrepancy.py`` does); mode 2's
   curve at acc3 (band 270-325 Hz) gives ONLY its linear floor, from its lowest amplitudes
   (``calibrate(floors={2: ...})``): the joint is never fitted on mode 2.
2. The release state of the prediction is read off the measured record: 50 ms after the
   impact, mode 1's and mode 2's displacement amplitudes at acc3 (band-passed Hilbert
   envelopes, ``scipy.signal``, log-linear fits over the next 0.3 s).
3. The multi-mode ring-down (``models.ringdown(amplitude={1: X1, 2: X2}, sensors=...)``)
   rings both modes through the same interface; the predicted records at acc3, acc2 and
   acc1 are read like the measured ones (``RingdownResult.sensor_curve``), and mode 2's
   predicted curves at acc3 and acc2 and the ratio of its amplitudes at the two sensors (a
   mode-shape check) are compared with the measured ones at the same amplitudes.

Sensor positions (``REFERENCE.md`` section 7; the model's axis runs from the end carrying
accelerometer 1): acc3 at 0.72 - 0.0762 m (the preset's ``sensor_position``), acc2 at
0.72 - 0.1651 m, acc1 at 0.0254 m. Data (GPL-3.0, read in place from ``../shared``, never
copied): ``brb-hammer/hammer_acc{1,2,3}.csv`` (Chen et al., MSSP 166:108401, 2022).

    python examples/brb_every_mode.py [--out DIR] [--duration 1.2] [--quick] [--solid]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from iwan_element import models

ROOT = Path(__file__).resolve().parents[1]
SHARED = [ROOT.parent / "shared" / "data", ROOT.parents[1] / "shared" / "data"]
#: sensor positions along the model's axis [m]
SENSORS = {"acc3": 0.72 - 0.0762, "acc2": 0.72 - 0.1651, "acc1": 0.0254}
#: the bands the record's modes are read in [Hz] (mode 1 as brb_discrepancy reads it)
BANDS = {1: (60.0, 120.0), 2: (270.0, 325.0)}


def data_dir():
    """The shared data folder holding ``brb-hammer``, or None."""
    for d in SHARED:
        if (d / "brb-hammer" / "hammer_acc3.csv").exists():
            return d / "brb-hammer"
    return None


def records(d) -> dict:
    """``{name: (position [m], t [s], a [m/s^2])}`` of the three accelerometers."""
    out = {}
    for name, x in SENSORS.items():
        t, a = np.loadtxt(d / f"hammer_{name}.csv", delimiter=",", skiprows=1).T
        out[name] = (x, t, a)
    return out


def predict(d, *, duration=1.2, quick=False, solid=False) -> models.HammerPrediction:
    """Calibrate on mode 1 at acc3, predict mode 2 everywhere (and mode 1 at acc2, acc1).
    ``solid``: the beam as solid bodies (``models.solid_preset``, extra ``[fem]``), whose
    second height-bending mode is its stuck mode 3 (mode 2 bends in-plane).
    """
    if solid:
        spec = models.solid_preset(
            "brake-reuss", mesh_size=0.012, lap_mesh_size=0.0025, patch_size=0.0064
        )
        second = 3
    else:
        spec, second = models.preset("brake-reuss"), 2
    return models.predict_hammer_test(
        spec,
        records(d),
        modes=(1, second),
        bands={1: BANDS[1], second: BANDS[2]},
        release_time=0.05,
        fit_span=0.3,
        duration=0.6 if quick else duration,
    )


def figure(path, out: models.HammerPrediction):
    """Measured and predicted f(X), zeta(X) of mode 1 at acc3 and mode 2 at acc3 and acc2."""
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 3, figsize=(13, 6.5))
    second = max(m for m, _ in out.measured)
    for j, key in enumerate([(1, "acc3"), (second, "acc3"), (second, "acc2")]):
        meas, pred = out.measured[key], out.predicted[key]
        meas.plot((axs[0, j], axs[1, j]), label="measured", ls="none")
        pred.plot(
            (axs[0, j], axs[1, j]), label="predicted (multi-mode ring-down)", marker="", ls="-"
        )
        axs[0, j].set_title(f"mode {key[0]} at {key[1]}")
        axs[0, j].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "brb_every_mode")
    ap.add_argument("--duration", type=float, default=1.2, help="ring-down length [s]")
    ap.add_argument("--quick", action="store_true", help="a 0.6 s ring-down")
    ap.add_argument(
        "--solid",
        action="store_true",
        help="the beam as solid bodies (needs the [fem] extra; 12 mm mesh)",
    )
    a = ap.parse_args(argv)
    d = data_dir()
    if d is None:
        print("../shared/data/brb-hammer not found (GPL data, read in place): nothing to do")
        return 0
    out = predict(d, duration=a.duration, quick=a.quick, solid=a.solid)
    print(out.report())
    a.out.mkdir(parents=True, exist_ok=True)
    figure(a.out / "brb_every_mode.png", out)
    print(f"wrote {a.out / 'brb_every_mode.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
