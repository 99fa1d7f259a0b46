"""From geometry to a calibrated, amplitude-dependent model of a bolted beam, in one script.

1. The Brake-Reuss beam's two halves meshed from the preset's dimensions (Netgen, second-
   order tetrahedra; ``pip install "iwan-element[fem]"``), joined by the exact Iwan interface
   on contact patches under the bolts' pressure cones, reduced (``models.solid_preset``).
2. Its stuck natural frequencies against the hammer record's peaks.
3. The interface calibrated on mode 1 of the hammer ring-down (``calibrate``: stiffness per
   area, friction, chi, floor; the second height-bending mode's floor from its own
   lowest-amplitude points), then the calibrated solid's frequencies, and its first and
   second height-bending modes' amplitude dependence by EPMC (``models.nonlinear_mode``).

Data: ``../shared/data/brb-hammer/hammer_acc3.csv`` (GPL-3.0, read in place, never copied);
without it the calibration step uses the 1D preset's QSMA curve as the "test".

    python examples/solid_beam.py [--mesh 0.012] [--out DIR]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from iwan_element.models.calibration import calibrate, measured_amplitude_curve

from iwan_element import models

RECORD = (
    Path(__file__).resolve().parents[1]
    / ".."
    / "shared"
    / "data"
    / "brb-hammer"
    / "hammer_acc3.csv"
)
PEAKS = (80.4, 221.7, 297.7, 845.6)  # the hammer record's spectral peaks [Hz]


def _frequencies(label, spec):
    f = models.natural_frequencies(spec, n_modes=12)[6:]  # six rigid-body modes first
    near = [
        f"{fk:.1f}"
        + "".join(f" ({100 * (fk / p - 1):+.1f} % of {p})" for p in PEAKS if abs(fk / p - 1) < 0.05)
        for fk in f
    ]
    print(f"{label}: " + ", ".join(near) + " Hz")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=float, default=0.012, help="mesh size [m]")
    ap.add_argument("--out", type=Path, default=Path("out") / "solid_beam")
    a = ap.parse_args(argv)
    t0 = time.perf_counter()
    solid = models.solid_preset("brake-reuss", mesh_size=a.mesh)
    print(
        f"solid Brake-Reuss beam: meshed and reduced in {time.perf_counter() - t0:.1f} s "
        f"({solid.model.info['n_full']} -> {solid.model.info['n_reduced']} coordinates, "
        f"{solid.model.info['n_patches']} patches)"
    )
    _frequencies("stuck, as built", solid)
    floors = {}
    if RECORD.exists():
        test = measured_amplitude_curve(RECORD)
        source = "the hammer record (mode 1, acc3)"
        # the second height-bending mode (the solid's elastic mode 3: mode 2 bends in-plane)
        # sets only its own floor, from its lowest-amplitude points
        floors = {3: measured_amplitude_curve(RECORD, band=(270.0, 330.0))}
    else:
        one_d = models.preset("brake-reuss")
        test = models.modal_amplitude_curve(one_d, amplitude=np.geomspace(2e-6, 60e-6, 12))
        source = "the 1D preset's QSMA curve (the record is absent)"
    t0 = time.perf_counter()
    cal = calibrate(solid, test, floors=floors)
    print(f"calibrated on {source} in {time.perf_counter() - t0:.1f} s: {cal.verdict()}")
    print("  " + cal.params.report().replace("\n", "\n  "))
    spec = cal.specimen
    _frequencies("stuck, calibrated", spec)
    X = np.geomspace(2e-6, 60e-6, 8)
    m1 = models.nonlinear_mode(spec, amplitude=X, mode=1)
    print(
        "mode 1 (EPMC) at the sensor: "
        + ", ".join(
            f"{1e6 * x:.0f} um: {f:.3f} Hz {100 * z:.3f} %"
            for x, f, z in zip(m1.amplitude[::2], m1.frequency[::2], m1.damping_ratio[::2])
        )
    )
    # the second height-bending mode
    if RECORD.exists():
        meas3 = floors[3]
        X3 = meas3.amplitude[np.linspace(0, meas3.amplitude.size - 1, 4).astype(int)]
        ref = dict(zip(meas3.amplitude, zip(meas3.frequency, meas3.damping_ratio)))
    else:
        X3, ref = np.geomspace(1e-8, 3e-6, 4), {}
    m3 = models.nonlinear_mode(spec, amplitude=X3, mode=3)
    for x, f, z in zip(m3.amplitude, m3.frequency, m3.damping_ratio):
        seen = f" (record {ref[x][0]:.2f} Hz, {100 * ref[x][1]:.3f} %)" if x in ref else ""
        print(f"2nd height bending at {x:.2e} m: {f:.2f} Hz, {100 * z:.3f} %{seen}")
    a.out.mkdir(parents=True, exist_ok=True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
    m1.plot(axs, label="solid, calibrated (EPMC)")
    test.plot(axs, label=source.split(" (")[0])
    axs[0].legend(fontsize=8)
    fig.savefig(a.out / "solid_beam.png", dpi=120)
    print(f"wrote {a.out / 'solid_beam.png'}")


if __name__ == "__main__":
    main()
