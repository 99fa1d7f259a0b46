"""Ring-down to joint parameters: signal -> amplitude curve -> modal Iwan fit with band.

1. A synthetic ring-down of the project's own transient model (a single-mode modal Iwan
   oscillator integrated with the exact IwanJoint), where the truth is known: the extracted
   curve against the closed form, the fit against the true parameters.
2. The real hammer ring-down of a Brake-Reuss beam (three-bolt lap joint), accelerometer 3
   at the drive point, first bending mode near 80.4 Hz: ../shared/data/brb-hammer
   (Chen et al., MSSP 166:108401, 2022; GPL-3.0: read in place, never copied).

PNGs go to out/ (or --out DIR). Run:  python examples/ringdown.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from iwan_element import (
    IwanParameters,
    amplitude_curve,
    fit_modal_iwan,
    modal_iwan_curve,
    modal_ringdown,
)


def find_brb(name="hammer_acc3.csv"):
    for parent in Path(__file__).resolve().parents:
        f = parent / "shared" / "data" / "brb-hammer" / name
        if f.is_file():
            return f
    return None


def figure(t, y, cur, fit, title, path, truth=None):
    fig, ax = plt.subplots(3, 1, figsize=(7, 9))
    ax[0].plot(t, y, lw=0.4)
    ax[0].set_xlabel("time [s]")
    ax[0].set_ylabel("acceleration [m/s$^2$]")
    ax[0].set_title(title)
    fit.plot(ax=(ax[1], ax[2]), label=f"modal Iwan fit ({fit.regime})")
    if truth is not None:
        X = np.geomspace(cur.amplitude.min(), cur.amplitude.max(), 100)
        f, z = truth(X)
        ax[1].plot(X, f, "g--", label="truth")
        ax[2].plot(X, z, "g--", label="truth")
        ax[1].legend(fontsize="small")
    ax[2].set_xlabel("displacement amplitude at the sensor [m]")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def synthetic(out, duration):
    f0, kappa, chi, beta, phimax = 80.0, 0.06, -0.5, 0.5, 1e-3
    w02 = (2 * math.pi * f0) ** 2
    KT = kappa * w02
    c = beta + (chi + 1) / (chi + 2)
    p = IwanParameters(KT * c * phimax / (1 + beta), KT, chi, beta)
    k_inf, zeta0 = w02 - KT, 1.5e-3
    t = np.arange(0.0, duration, 1 / 12800.0)
    a = modal_ringdown(t, p, K_inf=k_inf, q0=0.1 * phimax, zeta0=zeta0).acceleration
    a = a + 0.01 * np.std(a) * np.random.default_rng(0).standard_normal(t.size)
    cur = amplitude_curve(t, a, quantity="acceleration", band=(70.0, 92.0))
    fit = fit_modal_iwan(cur)
    x_ref = fit.conventions["x_ref"]
    delta = KT * (x_ref / phimax) ** (chi + 1) / (w02 * (chi + 2) * (1 + beta))
    print(
        "Synthetic ring-down (truth: f0 = 80 Hz, zeta0 = 1.5e-3, chi = -0.5, "
        f"delta = {delta:.4g} at X_ref = {x_ref:.3g} m)"
    )
    print(fit.report())

    def truth(X):
        return modal_iwan_curve(
            X, p, K_inf=k_inf, zeta0=zeta0, stiffness="harmonic", floor="dashpot"
        )

    return figure(
        t,
        a,
        cur,
        fit,
        "synthetic modal Iwan ring-down, 1 % noise",
        out / "ringdown_synthetic.png",
        truth,
    )


def real(out):
    f = find_brb()
    if f is None:
        print(
            "The real ring-down ../shared/data/brb-hammer/hammer_acc3.csv is absent; "
            "skipping it (the data are GPL-3.0 and are read from ../shared only)."
        )
        return None
    d = np.loadtxt(f, delimiter=",", skiprows=1)
    t, a = d[:, 0], d[:, 1]
    cur = amplitude_curve(t, a, quantity="acceleration", band=(60.0, 120.0))
    print("\nBrake-Reuss beam hammer ring-down, acc3 (drive point), mode 1")
    print(cur.report())
    fit = fit_modal_iwan(cur)
    print(fit.report())
    e = fit.rms_errors()
    print(
        f"RMS error of the fit: frequency {100 * e['frequency']:.4f} %, damping ratio "
        f"{100 * e['damping_ratio']:.2f} %"
    )
    return figure(
        t, a, cur, fit, "Brake-Reuss beam, hammer ring-down (acc3)", out / "ringdown_brb.png"
    )


def main():
    ap = argparse.ArgumentParser(description="ring-down -> amplitude curve -> modal Iwan fit")
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent.parent / "out")
    ap.add_argument("--quick", action="store_true", help="a 2 s synthetic record")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    paths = [synthetic(args.out, 2.0 if args.quick else 4.0), real(args.out)]
    for p in paths:
        if p is not None:
            print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
