"""The Brake-Reuss force-controlled sweeps predicted with the shaker setup in the model:
the setup updated on the lowest level only, the joint the hammer-calibrated one.

1. Level 1's linear targets (``iwan_element.sweep_modes``: single-mode least squares of its
   41 points: natural frequency, damping, drive-point modal constant with stderr).
2. Its frequency is taken at the level's amplitudes, where the joint already softens the
   mode: the hammer-calibrated joint's softening at the level's peak amplitude (QSMA of the
   preset against its stuck frequency) is added back, so that the target is the linear
   structure's (the joint stays as the hammer test calibrated it).
3. ``models.linear_update(preset("brake-reuss", setup="shaker"), ..., parameters=
   "attachments")``: what the level can see of the setup (the masses at the drive point; the
   shaker's moving parts are behind the measured force and cannot be seen).
4. Harmonic balance (harmonics 1, 3, 5; 8 modes) of every level at its measured f and F, for
   (a) the preset on its hammer setup, (b) the nominal shaker setup, (c) the updated one:
   rms of log(predicted / measured amplitude) and rms phase error per level.

    python benchmarks/bench_sweep_setup.py

Data: ``../shared/data/brb-steppedsine-fc/fc_sweeps.csv`` (GPL-3.0, read in place; Chen et
al., MSSP 166:108401, 2022).
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

import iwan_element as ie
from iwan_element import models

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "brb-steppedsine-fc"


def read_levels():
    d = np.loadtxt(DATA / "fc_sweeps.csv", delimiter=",", skiprows=1)
    return {int(k): d[d[:, 0] == k, 1:].T for k in np.unique(d[:, 0])}


def errors(spec, f, F, A, ph):
    X = A / (2 * math.pi * f) ** 2
    r = models.harmonic_balance(spec, frequency=f, force=F, harmonics=(1, 3, 5), n_modes=8)
    ok = r.converged
    e = np.log(r.amplitude[ok] / X[ok])
    dph = np.angle(np.exp(1j * (r.phase[ok] - ph[ok])))
    return float(np.sqrt(np.mean(e**2))), float(np.sqrt(np.mean(dph**2)))


def main():
    if not DATA.is_dir():
        print(f"{DATA} (GPL data, read in place) not found: nothing to do")
        return 0
    levels = read_levels()
    f, F, A, ph = levels[1]
    tg = ie.sweep_modes(f, F, A, ph)
    m = tg.modes[0]
    f1, sf1 = tg.frequencies[m.index], tg.frequency_stderr[m.index]
    c1, sc1 = tg.modal_constants[m.index], tg.modal_constant_stderr[m.index]
    print(
        f"level 1 linear fit: f {f1:.4f} +- {sf1:.4f} Hz, zeta {100 * m.damping_ratio:.4f} %, "
        f"c {c1:.4f} +- {sc1:.4f} 1/kg; warnings: {list(tg.warnings)}"
    )
    hammer = models.preset("brake-reuss")
    shaker = models.preset("brake-reuss", setup="shaker")
    X_peak = float(np.max(A / (2 * math.pi * f) ** 2))
    soft = (
        models.modal_amplitude_curve(hammer, amplitude=[X_peak]).frequency[0]
        / models.natural_frequencies(hammer, n_modes=4)[3]
    )
    f_lin = f1 / soft
    print(
        f"the hammer-calibrated joint softens mode 1 by {100 * (1 - soft):.3f} % at the "
        f"level's peak {1e6 * X_peak:.0f} um: linear target {f_lin:.4f} Hz"
    )
    t0 = time.perf_counter()
    upd = models.linear_update(
        shaker,
        frequencies={1: (f_lin, sf1)},
        modal_constants={1: (c1, sc1)},
        parameters="attachments",
    )
    print(f"\nupdate of the shaker setup on level 1 ({time.perf_counter() - t0:.1f} s):")
    print(upd.report())
    specs = {
        "(a) hammer setup": hammer,
        "(b) shaker setup, nominal": shaker,
        "(c) shaker setup, updated on level 1": upd.specimen,
    }
    print(
        "\nharmonic balance at the measured f and F: rms log(X_pred / X_meas), rms phase "
        "error [rad]"
    )
    print(f"  {'model':40s}" + "".join(f"   level {k}       " for k in levels))
    for name, s in specs.items():
        t0 = time.perf_counter()
        row = [errors(s, *levels[k]) for k in levels]
        print(
            f"  {name:40s}"
            + "".join(f"  {a:6.3f} / {p:5.3f} " for a, p in row)
            + f"  ({time.perf_counter() - t0:.1f} s)"
        )
    print(
        "  measured peak of |X/F| per level [Hz]: "
        + ", ".join(f"{k}: {v[0][np.argmax(v[2] / v[1])]:.2f}" for k, v in levels.items())
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
