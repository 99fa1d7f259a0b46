"""Brake-Reuss beam: raw force-controlled stepped-sine sweeps against the hammer ring-down.

Reads, in place, the GPL-3.0 data in ../shared/data (never copied into this project):

* ``brb-steppedsine-fc/fc_sweeps.csv``: four force-controlled sweeps (79.2-81.2 Hz, force
  dropping near resonance), drive point = Accel 3; read by ``read_sweep_csv`` (columns by
  unit) and turned into f(X), zeta(X) by ``sweep_curve`` (single nonlinear mode, one modal
  constant and residual for all points);
* ``brb-hammer/hammer_acc3.csv``: the hammer ring-down at the same point, through
  ``models.calibration.measured_amplitude_curve`` (band-pass, Hilbert, windowed fits).

Prints both curves, compares them where their amplitudes overlap (the sweep curve
interpolated in ln X at the hammer amplitudes) and draws them side by side in
``out/sweeps/brb_sweeps_vs_hammer.png``. Also checks how much the sweep curve depends on the
method's choices (``peak_fraction``, ``degree``, the residual term). Runs in a few seconds:

    PYTHONPATH=. python benchmarks/bench_sweeps.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from iwan_element.models.calibration import measured_amplitude_curve

from iwan_element import read_sweep_csv, sweep_curve


def shared_file(*parts):
    for parent in Path(__file__).resolve().parents:
        f = parent.joinpath("shared", "data", *parts)
        if f.is_file():
            return f
    return None


def compare(sweep, hammer):
    """Relative differences sweep/hammer - 1 at the hammer amplitudes inside the sweep's range."""
    X = hammer.amplitude
    inside = (X >= sweep.amplitude.min()) & (X <= sweep.amplitude.max())
    lx = np.log(sweep.amplitude)
    f_s = np.interp(np.log(X[inside]), lx, sweep.frequency)
    z_s = np.interp(np.log(X[inside]), lx, sweep.damping_ratio)
    return X[inside], f_s, z_s, hammer.frequency[inside], hammer.damping_ratio[inside]


def variants(data):
    """The sweep curve's spread over the method's choices, at three amplitudes."""
    at = np.array([30e-6, 80e-6, 200e-6])
    rows = []
    for label, kw in (
        ("default", {}),
        ("peak_fraction=0.4", {"peak_fraction": 0.4}),
        ("degree=2", {"degree": 2}),
        ("degree=5", {"degree": 5}),
        ("no residual", {"residual": False}),
    ):
        c = sweep_curve(**data, **kw)
        lx = np.log(c.amplitude)
        out = (np.log(at) < lx.min()) | (np.log(at) > lx.max())  # no extrapolation
        rows.append(
            (
                label,
                np.where(out, np.nan, np.interp(np.log(at), lx, c.frequency)),
                np.where(out, np.nan, np.interp(np.log(at), lx, c.damping_ratio)),
            )
        )
    print("\nSensitivity to the method's choices (f [Hz] / zeta [%] at 30, 80, 200 um):")
    for label, f, z in rows:
        print(f"  {label:18s} " + "  ".join(f"{a:8.3f} / {100 * b:.3f}" for a, b in zip(f, z)))
    f_all = np.array([r[1] for r in rows])
    z_all = np.array([r[2] for r in rows])
    f_sp = (np.nanmax(f_all, 0) - np.nanmin(f_all, 0)) / np.nanmean(f_all, 0)
    z_sp = (np.nanmax(z_all, 0) - np.nanmin(z_all, 0)) / np.nanmean(z_all, 0)
    print(
        "  spread (max-min)/mean where defined: f "
        + ", ".join(f"{v:.1e}" for v in f_sp)
        + "; zeta "
        + ", ".join(f"{v:.1%}" for v in z_sp)
    )


def figure(sweep, hammer, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 1, sharex=True, figsize=(7, 6.5))
    hammer.plot(ax, label="hammer ring-down (Hilbert)", ms=3)
    sweep.plot(ax, label="force-controlled sweeps (single nonlinear mode)", ms=4, capsize=2)
    ax[0].set_title("Brake-Reuss beam, mode 1 at Accel 3")
    ax[0].legend(fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    fs, fh = (
        shared_file("brb-steppedsine-fc", "fc_sweeps.csv"),
        shared_file("brb-hammer", "hammer_acc3.csv"),
    )
    if fs is None or fh is None:
        print("skipped: ../shared/data/brb-steppedsine-fc or brb-hammer is absent")
        return
    t0 = time.perf_counter()
    data = read_sweep_csv(fs)
    sweep = sweep_curve(**data)
    t1 = time.perf_counter()
    hammer = measured_amplitude_curve(fh)
    print(sweep.report())
    print(f"  ({t1 - t0:.2f} s)\n")
    print(hammer.sorted().report())
    X, f_s, z_s, f_h, z_h = compare(sweep, hammer)
    print(
        f"\nOverlap {X.min() * 1e6:.1f}-{X.max() * 1e6:.1f} um (sweep curve interpolated in "
        "ln X at the hammer amplitudes):"
    )
    print(
        f"  {'X [um]':>8} {'f sweep':>9} {'f hammer':>9} {'df [%]':>7} {'z sweep %':>10} "
        f"{'z hammer %':>10} {'dz [%]':>7}"
    )
    for row in zip(X, f_s, f_h, z_s, z_h):
        x, a, b, c, d = row
        print(
            f"  {x * 1e6:8.1f} {a:9.3f} {b:9.3f} {100 * (a / b - 1):7.3f} {100 * c:10.4f} "
            f"{100 * d:10.4f} {100 * (c / d - 1):7.1f}"
        )
    variants(data)
    out = Path(__file__).resolve().parents[1] / "out" / "sweeps" / "brb_sweeps_vs_hammer.png"
    figure(sweep, hammer, out)
    print(f"\nfigure: {out}")


if __name__ == "__main__":
    main()
