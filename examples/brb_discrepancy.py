"""The discrepancy workflow on the bolted Brake-Reuss beam's vibration.

1. The beam model (``models.preset("brake-reuss")``) is calibrated on the hammer ring-down
   (2-60 um at accelerometer 3); its QSMA curve is compared with that curve.
2. The force-controlled stepped-sine sweeps (94-275 um, same beam, same point) become an
   amplitude curve with :func:`iwan_element.sweep_curve` (single nonlinear mode per point)
   and expose the high-amplitude disagreement; the model warns that it extrapolates there.
3. :func:`iwan_element.diagnose_vibration` compares the sweeps with the model's QSMA at the
   same amplitudes, locates the disagreement and names what the data support; the named
   effects are added to the beam model (``d.augment(specimen)``).
4. The augmented beam model runs QSMA (with bands from ``d.predict``) and an Exudyn
   ring-down; one figure shows measured points, the model before and after, and the band.

Data (GPL-3.0, read from ``../shared`` only, never copied): ``brb-hammer/hammer_acc3.csv``
and ``brb-steppedsine-fc/fc_sweeps.csv`` (Chen et al., MSSP 166:108401, 2022; Jin et al.,
MSSP 166:108402, 2022; github.com/mattiacenedese/BRBtesting).

The sweeps come from another test than the hammer calibration, so the diagnosis runs with
``between_tests=True`` (constant relative offsets of frequency and damping fitted as
nuisances); the augmented model's predictions at 20-315 um are printed with their change
from the plain model.

    python examples/brb_discrepancy.py [--out DIR] [--quick]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from iwan_element.models.calibration import measured_amplitude_curve

import iwan_element as ie
from iwan_element import models

ROOT = Path(__file__).resolve().parents[1]

SHARED = [ROOT.parent / "shared" / "data", ROOT.parents[1] / "shared" / "data"]


def data_dir():
    for d in SHARED:
        if (d / "brb-steppedsine-fc" / "fc_sweeps.csv").exists():
            return d
    return None


def sweeps_curve(path):
    """The sweeps as one amplitude curve (``iwan_element.sweep_curve``)."""
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    level, f, F, A, phase = d.T
    return ie.sweep_curve(f, F, A, phase, level=level.astype(int), quantity="acceleration")


def diagnose_sweeps(spec, sweeps):
    """``(QSMA at the sweeps' amplitudes, diagnosis of the sweeps against it)``.

    The sweeps are another test than the hammer calibration (shaker attached): the
    between-test relative frequency and damping offsets are fitted as nuisances, not named.
    """
    before = models.modal_amplitude_curve(spec, amplitude=sweeps.amplitude)
    diag = ie.diagnose_vibration(
        sweeps,
        predicted_frequency=before.frequency,
        predicted_damping_ratio=before.damping_ratio,
        predicted_zeta0=spec.interface.damping_floor,
        between_tests=True,
    )
    return before, diag


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "brb_discrepancy")
    ap.add_argument("--quick", action="store_true", help="shorter ring-down")
    a = ap.parse_args(argv)
    d = data_dir()
    if d is None:
        print("../shared/data (brb-hammer, brb-steppedsine-fc) not found: nothing to do")
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    spec = models.preset("brake-reuss")
    hammer = measured_amplitude_curve(d / "brb-hammer" / "hammer_acc3.csv")
    sweeps = sweeps_curve(d / "brb-steppedsine-fc" / "fc_sweeps.csv")
    print(
        f"hammer: {len(hammer)} points {1e6 * hammer.amplitude.min():.3g}-"
        f"{1e6 * hammer.amplitude.max():.3g} um; sweeps: {len(sweeps)} points "
        f"{1e6 * sweeps.amplitude.min():.3g}-{1e6 * sweeps.amplitude.max():.3g} um"
    )
    before, diag = diagnose_sweeps(spec, sweeps)
    for w in before.warnings:
        print("model:", w)
    print(diag.report())
    aug = diag.augment(spec)
    Xp = np.array([20e-6, 100e-6, 200e-6, 300e-6, 315e-6])
    qb = models.modal_amplitude_curve(spec, amplitude=Xp)
    qa = models.modal_amplitude_curve(aug, amplitude=Xp)
    band = diag.predict(Xp, base=qb)
    print("\nprediction of the augmented beam model (QSMA; 1-sigma band from the diagnosis)")
    print(
        "  X [um]  f before [Hz]  f after [Hz]       change   zeta before [%]  "
        "zeta after [%]   ratio"
    )
    for i, x in enumerate(Xp):
        print(
            f"  {1e6 * x:6.0f}  {qb.frequency[i]:13.3f}  {qa.frequency[i]:8.3f} +- "
            f"{band.frequency_std[i]:.3f}  {100 * (qa.frequency[i] / qb.frequency[i] - 1):+.3f} %"
            f"  {100 * qb.damping_ratio[i]:15.3f}  {100 * qa.damping_ratio[i]:8.3f} +- "
            f"{100 * band.damping_ratio_std[i]:.3f}  "
            f"{qa.damping_ratio[i] / qb.damping_ratio[i]:5.2f}"
        )
    X0 = float(sweeps.amplitude.max())
    rd = models.ringdown(aug, amplitude=X0, cycles=20 if a.quick else 60)
    print(
        f"\nExudyn ring-down of the augmented beam from {1e6 * X0:.3g} um "
        f"({rd.wall_time:.1f} s): effects {rd.metadata['effects']}, {len(rd.curve)} points "
        f"{1e6 * rd.curve.amplitude.min():.3g}-{1e6 * rd.curve.amplitude.max():.3g} um"
    )
    figure(a.out / "brb_discrepancy.png", spec, aug, diag, hammer, sweeps, rd)
    print(f"wrote {a.out / 'brb_discrepancy.png'}")
    return 0


def figure(path, spec, aug, diag, hammer, sweeps, rd):
    import matplotlib.pyplot as plt

    X = np.geomspace(2e-6, 3.15e-4, 60)
    qb = models.modal_amplitude_curve(spec, amplitude=X)
    qa = models.modal_amplitude_curve(aug, amplitude=X)
    band = diag.predict(X, base=qb)
    # the sweeps in the calibration test's frame: divided by the fitted between-test ratios
    bt = diag.details["between_tests"]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, yb, ya, sd, ym, ys, yr, scale, off in (
        (
            a1,
            qb.frequency,
            qa.frequency,
            band.frequency_std,
            hammer.frequency,
            sweeps.frequency,
            rd.curve.frequency,
            1.0,
            bt["frequency_offset"],
        ),
        (
            a2,
            qb.damping_ratio,
            qa.damping_ratio,
            band.damping_ratio_std,
            hammer.damping_ratio,
            sweeps.damping_ratio,
            rd.curve.damping_ratio,
            100.0,
            bt["damping_offset"],
        ),
    ):
        ax.semilogx(
            hammer.amplitude,
            scale * ym,
            "o",
            mfc="none",
            color="k",
            ms=4,
            label="hammer ring-down (calibration)",
        )
        ax.semilogx(
            sweeps.amplitude,
            scale * ys,
            "s",
            mfc="none",
            color="C2",
            ms=4,
            label="stepped-sine sweeps, as measured",
        )
        ax.semilogx(
            sweeps.amplitude,
            scale * ys / (1 + off),
            "s",
            color="C2",
            ms=4,
            label="sweeps / between-test ratio",
        )
        ax.semilogx(X, scale * yb, "-", color="C0", label="beam model (QSMA)")
        ax.semilogx(
            X, scale * ya, "--", color="C3", label="+ " + (" + ".join(diag.effects) or "nothing")
        )
        ax.fill_between(
            X,
            scale * (ya - 2 * sd),
            scale * (ya + 2 * sd),
            color="C3",
            alpha=0.2,
            label="2-sigma band",
        )
        ax.semilogx(
            rd.curve.amplitude,
            scale * yr,
            "-",
            color="C1",
            lw=3,
            alpha=0.6,
            label="augmented, Exudyn ring-down",
        )
        ax.axvspan(*spec.calibrated_range, color="0.9", zorder=0)
        ax.set_xlabel("amplitude at accelerometer 3 [m]")
        ax.grid(True, which="both", alpha=0.3)
    a1.set_ylabel("frequency [Hz]")
    a2.set_ylabel("damping ratio [%]")
    a2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
