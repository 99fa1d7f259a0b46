"""The Brake-Reuss beam as a solid: natural frequencies against the hammer record, and cost.

Run:  python benchmarks/bench_solid.py [--mesh 0.012 0.008 0.006] [--patch 0.0064]
      [--modes 20]

For each mesh size (largest element [m]; the lap faces at 0.6 x the patch size): the two
halves meshed (second-order tetrahedra, ``models.solid_mesh.lap_beam_parts``), patched and
reduced (``models.solid_build.solid_specimen``, ``--modes`` stuck modes + 2 attachment shapes
per patch). Printed:

* mesh and reduction sizes, wall times of meshing (Netgen + exudyn import), reduction, and a
  20-amplitude QSMA curve of mode 1;
* the first six elastic natural frequencies with the interface stuck at the preset's
  calibrated stiffness per area (the 1-D calibration, 6.905e11 N/m^3), each with its family
  (from the reduced mode's full-model displacement: height bending ``z``, in-plane bending
  ``y``) and the nearest hammer peak (80.4, 221.7, 297.7, 845.6 Hz, brb-hammer/acc3);
* the same with the interface released (``interface="none"``);
* the stiffness per area that puts the stuck mode 1 on 80.4 Hz (brentq), and the other
  families' frequencies then (a linear check, not the amplitude calibration);
* mode 1's QSMA curve (frequency drop and joint damping at 5, 20, 60 um) next to the 1-D
  preset's, same interface law and pressure;
* with ``--calibrate`` (needs the GPL record ``../shared/data/brb-hammer/hammer_acc3.csv``,
  read in place): ``models.calibration.calibrate`` on the solid of the first mesh size,
  fitted on mode 1 of the hammer ring-down (k_t, mu, chi, damping floor; wall time), the
  calibrated solid's frequencies by family against the peaks, and the second height-bending
  mode's QSMA curve against the record's 270-330 Hz band at acc3 (its damping floor is the
  one fitted on mode 1: the record gives no floor of its own for that mode).
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import brentq

from pathlib import Path

from iwan_element.models import modal_amplitude_curve, natural_frequencies, preset
from iwan_element.models.calibration import calibrate, measured_amplitude_curve
from iwan_element.models.solid_build import solid_specimen
from iwan_element.models.solid_mesh import lap_beam_parts

PEAKS = np.array([80.4, 221.7, 297.7, 845.6])
RECORD = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "brb-hammer" / "hammer_acc3.csv"


def _families(solid, n):
    """'z' (height bending) or 'y' (in-plane) or 'x'/'t' per elastic stuck mode, from the
    full displacement of the reduced mode shape."""
    full = solid.model.full
    L = solid.linear_system()
    KT = solid.contact_points().KT
    K = L.K0 + L.G.T @ (KT[:, None] * L.G)
    w2, V = np.linalg.eigh(K)          # M = I in the reduced coordinates
    out = []
    for k in range(6, 6 + n):
        u = np.zeros(3 * (full["free"].max() // 3 + 1))
        u[full["free"]] = full["basis"] @ V[:, k]
        u = u.reshape(-1, 3)
        share = np.sum(u * u, axis=0) / np.sum(u * u)
        out.append("xyz"[int(np.argmax(share))] + f"({share.max():.2f})")
    return out


def _line(label, f, fam=None):
    parts = []
    for i, v in enumerate(f):
        j = int(np.argmin(np.abs(PEAKS - v)))
        near = f" [{PEAKS[j]:.1f}: {100 * (v / PEAKS[j] - 1):+.2f}%]" \
            if abs(v / PEAKS[j] - 1) < 0.05 else ""
        parts.append(f"{v:8.2f}{'' if fam is None else ' ' + fam[i]}{near}")
    print(f"  {label:<22s}" + " | ".join(parts))


def run_calibration(solid):
    """Calibrate the solid's interface on mode 1 of the hammer record; predict the others."""
    if not RECORD.exists():
        print(f"--calibrate: {RECORD} absent (GPL data are read from ../shared only); skipped")
        return
    t0 = time.perf_counter()
    res = calibrate(solid, measured_amplitude_curve(RECORD))
    print(f"calibrate on mode 1 ({time.perf_counter() - t0:.1f} s):")
    print("  " + res.report().replace("\n", "\n  "))
    cal = res.specimen
    _line("calibrated, stuck", natural_frequencies(cal, n_modes=12)[6:], _families(cal, 6))
    meas = measured_amplitude_curve(RECORD, band=(270.0, 330.0))
    X = meas.amplitude
    model = modal_amplitude_curve(cal.replace(amplitude_range=(X.min(), X.max()),
                                              calibrated_range=None), mode=3, amplitude=X)
    print("  2nd height bending (QSMA mode 3) vs the record's 270-330 Hz band at acc3:")
    for k in np.linspace(0, X.size - 1, 6).astype(int):
        print(f"    X {X[k]:9.3e} m: f {model.frequency[k]:8.3f} / {meas.frequency[k]:8.3f} Hz, "
              f"zeta {100 * model.damping_ratio[k]:.4f} / {100 * meas.damping_ratio[k]:.4f} %")


def run(mesh, patch, modes):
    s = preset("brake-reuss")
    t0 = time.perf_counter()
    parts = lap_beam_parts(s, mesh_size=mesh, lap_mesh_size=0.6 * patch)
    t_mesh = time.perf_counter() - t0
    solid = solid_specimen(s, parts, patch_size=patch, n_modes=modes, keep_full=True)
    info = solid.model.info
    t0 = time.perf_counter()
    modal_amplitude_curve(solid)
    t_qsma = time.perf_counter() - t0
    print(f"mesh {mesh * 1e3:.1f} mm (lap {0.6 * patch * 1e3:.2f} mm), patches {patch * 1e3:.2f} mm:"
          f" {info['n_full']} coordinates -> {info['n_reduced']} ({modes} modes + "
          f"{2 * info['n_patches']} attachment shapes, {info['n_patches']} patches); meshing "
          f"{t_mesh:.1f} s, reduction {info['reduction_s']:.1f} s, QSMA (20 amplitudes) "
          f"{t_qsma:.2f} s")
    fs = natural_frequencies(solid, n_modes=12)[6:]
    _line("stuck (preset k_t)", fs, _families(solid, 6))
    _line("released", natural_frequencies(solid, interface="none", n_modes=15)[9:15])
    kt0 = s.interface.stiffness_per_area

    def f1(k):
        return natural_frequencies(solid.replace(stiffness_per_area=k), n_modes=7)[6] - PEAKS[0]
    try:
        k = brentq(f1, 0.05 * kt0, 50 * kt0, rtol=1e-6)
        _line(f"stuck k_t={k:.3g}", natural_frequencies(
            solid.replace(stiffness_per_area=k), n_modes=12)[6:])
    except ValueError:
        print("  no stiffness per area in [0.05, 50] x the preset's puts mode 1 on 80.4 Hz")
    X = np.array([5e-6, 2e-5, 6e-5])
    for label, sp_ in (("solid", solid), ("1-D", s)):
        c = modal_amplitude_curve(sp_, amplitude=X)
        n_rigid = 6 if sp_ is solid else 3
        f0 = natural_frequencies(sp_, n_modes=n_rigid + 1)[-1]
        drop = 100 * (1 - c.frequency / f0)
        zj = 100 * (c.damping_ratio - s.floor(1))
        print(f"  QSMA mode 1 {label:<6s} f0 {f0:7.3f} Hz; drop % {np.round(drop, 4)}; "
              f"joint zeta % {np.round(zj, 4)} at X = 5, 20, 60 um")
    return solid


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=float, nargs="+", default=[0.012, 0.008, 0.006])
    ap.add_argument("--patch", type=float, default=0.0064)
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument("--calibrate", action="store_true")
    a = ap.parse_args()
    print(f"hammer peaks (brb-hammer acc3): {PEAKS} Hz")
    solids = [run(m, a.patch, a.modes) for m in a.mesh]
    if a.calibrate:
        run_calibration(solids[0])


if __name__ == "__main__":
    main()
