"""The Brake-Reuss beam as a solid: natural frequencies against the hammer record, and cost.

Run:  python benchmarks/bench_solid.py [--mesh 0.012 0.008 0.006] [--patch 0.0064]
      [--modes 20] [--lap 0.0025] [--normal-ratio 1.22 1 2 5 14] [--exponent 0 1] [--scan]
      [--no-holes] [--wave-speed 1 1.01 1.02] [--calibrate]

For each mesh size (largest element [m]; the lap faces at ``--lap``, default 0.6 x the patch
size; the patches' tied limit needs 2.5 mm there, docs/solid.md): the two halves meshed
(second-order tetrahedra, ``models.solid.lap_beam_parts``; the bolt holes cut unless
``--no-holes``), patched and reduced
(``models.solid.solid_specimen``, ``--modes`` stuck modes + 3 attachment shapes per
patch). Printed:

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
* with ``--normal-ratio R ...`` (for each mesh): the normal contact stiffness tied to the
  tangential one, ``k_n = R k_t`` (Mindlin's elastic ratio ``k_t/k_n = 2(1-nu)/(2-nu)`` =
  0.82 at nu = 0.3 gives R = 1.22; the preset's independent ``k_n`` = 1e13 is R = 14 at
  its calibrated ``k_t``), ONE scale ``k_t`` found by brentq so that the stuck mode 1 is on
  80.4 Hz, and then the first in-plane, second and fourth height-bending frequencies against
  the peaks, with each family's sensitivities ``d ln f / d ln k_t`` and
  ``d ln f / d ln k_n`` there (``--exponent m ...``: the same with the tangential stiffness
  following the pressure, ``KT_i ~ A_i (p_i/p_mean)^m``; the normal springs stay ``k_n A``);
* with ``--scan``: any uniform interface stiffness per area, direction by direction
  (``k_x`` along the beam, ``k_y`` across it, ``k_n`` normal): ``k_y`` and ``k_n`` on a grid
  of decades 1e11-1e16 N/m^3, ``k_x`` by brentq on the stuck mode 1 = 80.4 Hz, and the five
  settings whose largest error of the other three families is smallest; with the tied limit;
* with ``--wave-speed c ...``: the material's wave speed ``sqrt(E / rho)`` times ``c`` (the
  thin beam's E and density are not verified: E is the classic beam's, the density assumed),
  the interface recalibrated on the stuck mode 1, the other families' errors;
* with ``--calibrate`` (needs the GPL record ``../shared/data/brb-hammer/hammer_acc3.csv``,
  read in place): ``models.calibration.calibrate`` on the solid of the first mesh size,
  fitted on mode 1 of the hammer ring-down (k_t, mu, chi, damping floor; wall time), the
  second height-bending mode's floor from its own lowest-amplitude points of the record's
  270-330 Hz band (``floors={3: ...}``, ``calibration.modal_floor``; the solid's elastic
  mode 2 bends in-plane), the calibrated solid's frequencies by family against the peaks,
  and that mode's QSMA curve against the band's measured one at acc3.
"""

from __future__ import annotations

import argparse
import math
import time
from functools import lru_cache
from pathlib import Path

import numpy as np
from iwan_element.models import modal_amplitude_curve, natural_frequencies, preset
from iwan_element.models.calibration import calibrate, measured_amplitude_curve
from iwan_element.models.solid import lap_beam_parts, solid_specimen
from scipy.optimize import brentq

PEAKS = np.array([80.4, 221.7, 297.7, 845.6])
RECORD = (
    Path(__file__).resolve().parents[1]
    / ".."
    / "shared"
    / "data"
    / "brb-hammer"
    / "hammer_acc3.csv"
)


def _direction_forms(solid):
    """``Q[d] = T^T P_d T`` (d = x, y, z): ``v^T Q[d] v`` is the share of direction d in the
    full displacement ``T v`` of a reduced vector ``v``.
    """
    return _forms(solid.model)


@lru_cache(maxsize=4)
def _forms(model):
    T, d = model.full["basis"], model.full["free"] % 3
    return [T[d == k].T @ T[d == k] for k in range(3)]


def _classify(Q, V):
    """'x', 'y' or 'z' (the largest share of the full displacement) per column of V."""
    share = np.array([np.einsum("ik,ij,jk->k", V, q, V) for q in Q])
    return ["xyz"[k] for k in np.argmax(share, axis=0)], share.max(axis=0) / share.sum(axis=0)


def _families(solid, n):
    """'z' (height bending) or 'y' (in-plane) or 'x' per elastic stuck mode, with its
    share of the full displacement.
    """
    L = solid.linear_system()
    KT = solid.contact_points().KT
    K = L.K0 + L.G.T @ (KT[:, None] * L.G)
    w2, V = np.linalg.eigh(K)  # M = I in the reduced coordinates
    fam, share = _classify(_direction_forms(solid), V[:, 6 : 6 + n])
    return [f"{f}({v:.2f})" for f, v in zip(fam, share)]


def _direction_targets(solid):
    """``targets(kx, ky, kn)``: the stuck frequencies [Hz] of the first height, first
    in-plane, second and fourth height bending modes with a uniform interface stiffness per
    area in each direction (pressure exponent 0).
    """
    L, Q = solid.linear_system(), _direction_forms(solid)
    A, Gn = solid.model.patches.area, solid.model.normal_gaps
    Gx, Gy = L.G[0::2], L.G[1::2]

    def targets(kx, ky, kn):
        K = L.Kb + sum(G.T @ ((k * A)[:, None] * G) for G, k in ((Gx, kx), (Gy, ky), (Gn, kn)))
        w2, V = np.linalg.eigh(K)
        f = np.sqrt(np.abs(w2[6:14])) / (2 * math.pi)
        fam, _ = _classify(Q, V[:, 6:14])
        z, y = f[[c == "z" for c in fam]], f[[c == "y" for c in fam]]
        return np.array([z[0], y[0], z[1], z[3]])

    return targets


def run_wave_speed(solid, factors):
    """The material's wave speed ``sqrt(E / rho)`` times ``c``: every body frequency scales
    by ``c`` when ``E`` and the interface stiffnesses scale by ``c^2``, so the calibration on
    the stuck mode 1 = 80.4 Hz is the unscaled model's on ``80.4 / c`` (``k_t = k_x = k_y`` by
    brentq, ``k_n`` the specimen's); the other families' errors then.
    """
    targets = _direction_targets(solid)
    kn = solid.interface.normal_stiffness_per_area
    print(
        "  wave speed x c (E / rho x c^2), k_t on the stuck mode 1 = 80.4 Hz: errors of "
        "in-plane, 2nd and 4th height bending against 221.7, 297.7, 845.6 Hz"
    )
    for c in factors:
        lk = brentq(
            lambda lk, c=c: targets(10**lk, 10**lk, kn)[0] - PEAKS[0] / c, 10.0, 16.0, xtol=1e-6
        )
        err = 100 * (c * targets(10**lk, 10**lk, kn)[1:] / PEAKS[1:] - 1)
        print(
            f"    c = {c:.3f} (E / rho x {c * c:.4f}): k_t {10**lk:.3g} N/m^3 (x c^2: "
            f"{c * c * 10**lk:.3g}); in-plane {err[0]:+.2f} %, 2nd {err[1]:+.2f} %, "
            f"4th {err[2]:+.2f} %"
        )


def run_stiffness_scan(solid, decades=(11, 16)):
    """Any uniform interface stiffness per area, direction by direction: ``k_y`` and ``k_n``
    on a grid of decades, ``k_x`` by brentq on the stuck mode 1 = 80.4 Hz; the settings with
    the smallest largest error of the other three families (pressure exponent 0).
    """
    targets = _direction_targets(solid)

    rows = []
    for ky in 10.0 ** np.arange(decades[0], decades[1] + 1):
        for kn in 10.0 ** np.arange(decades[0], decades[1] + 1):

            def g(lk, ky=ky, kn=kn):
                return targets(10**lk, ky, kn)[0] - PEAKS[0]

            if g(8.0) > 0 or g(18.0) < 0:
                continue
            kx = 10 ** brentq(g, 8.0, 18.0, xtol=1e-6)
            err = 100 * (targets(kx, ky, kn)[1:] / PEAKS[1:] - 1)
            rows.append((np.max(np.abs(err)), kx, ky, kn, err))
    print(
        f"  tied limit (k = 1e16 every direction): "
        f"{np.round(targets(1e16, 1e16, 1e16), 2)} Hz (z1, y1, z2, z4)"
    )
    print("  k_x on mode 1, k_y and k_n on a grid: the five smallest largest errors of y1, z2, z4")
    for e, kx, ky, kn, err in sorted(rows, key=lambda r: r[0])[:5]:
        print(
            f"    {e:.2f} %: k_x {kx:.3g}, k_y {ky:.0e}, k_n {kn:.0e} N/m^3; y1, z2, z4 "
            f"{np.round(err, 2)} %"
        )


def _targets(solid):
    """Stuck frequencies [Hz] of the first height, first in-plane, second and fourth height
    bending modes (the families of the hammer peaks), from the lowest 8 elastic modes.
    """
    fam = {}
    for fk, lab in zip(natural_frequencies(solid, n_modes=14)[6:], _families(solid, 8)):
        fam.setdefault(lab[0], []).append(fk)
    return np.array([fam["z"][0], fam["y"][0], fam["z"][1], fam["z"][3]])


def run_normal_ratio(solid, ratios, exponents, h=1e-3):
    """One stiffness scale on mode 1 with ``k_n = R k_t``: the other families (docstring)."""
    print(
        "  k_n = R k_t, k_t by brentq on the stuck mode 1 = 80.4 Hz; frequencies [Hz] and "
        "% against 221.7, 297.7, 845.6; d ln f / d ln k_t and d ln k_n of (z1, y1, z2, z4)"
    )
    for m in exponents:
        for r in ratios:

            def at(kt, kn, m=m):
                return solid.replace(
                    stiffness_per_area=kt,
                    normal_stiffness_per_area=kn,
                    stiffness_pressure_exponent=m,
                )

            k = brentq(
                lambda v, r=r: natural_frequencies(at(v, r * v), n_modes=7)[6] - PEAKS[0],
                1e10,
                1e15,
                rtol=1e-9,
            )
            f = _targets(at(k, r * k))
            st = np.log(_targets(at(k * (1 + h), r * k)) / f) / math.log1p(h)
            sn = np.log(_targets(at(k, r * k * (1 + h))) / f) / math.log1p(h)
            err = 100 * (f[1:] / PEAKS[1:] - 1)
            print(
                f"  m {m:g} R {r:6.3f}: k_t {k:.4g}, k_n {r * k:.4g} N/m^3 | z1 {f[0]:.2f} "
                f"y1 {f[1]:.2f} ({err[0]:+.2f} %) z2 {f[2]:.2f} ({err[1]:+.2f} %) z4 "
                f"{f[3]:.2f} ({err[2]:+.2f} %) | k_t {np.round(st, 4)} k_n {np.round(sn, 4)}"
            )


def _line(label, f, fam=None):
    parts = []
    for i, v in enumerate(f):
        j = int(np.argmin(np.abs(PEAKS - v)))
        near = (
            f" [{PEAKS[j]:.1f}: {100 * (v / PEAKS[j] - 1):+.2f}%]"
            if abs(v / PEAKS[j] - 1) < 0.05
            else ""
        )
        parts.append(f"{v:8.2f}{'' if fam is None else ' ' + fam[i]}{near}")
    print(f"  {label:<22s}" + " | ".join(parts))


def run_calibration(solid):
    """Calibrate the solid's interface on mode 1 of the hammer record; predict the others."""
    if not RECORD.exists():
        print(f"--calibrate: {RECORD} absent (GPL data are read from ../shared only); skipped")
        return
    meas = measured_amplitude_curve(RECORD, band=(270.0, 330.0))
    t0 = time.perf_counter()
    res = calibrate(solid, measured_amplitude_curve(RECORD), floors={3: meas})
    print(
        f"calibrate on mode 1, the 2nd height bending's floor from its own curve "
        f"({time.perf_counter() - t0:.1f} s):"
    )
    print("  " + res.report().replace("\n", "\n  "))
    cal = res.specimen
    _line("calibrated, stuck", natural_frequencies(cal, n_modes=12)[6:], _families(cal, 6))
    X = meas.amplitude
    model = modal_amplitude_curve(
        cal.replace(amplitude_range=(X.min(), X.max()), calibrated_range=None), mode=3, amplitude=X
    )
    print("  2nd height bending (QSMA mode 3) vs the record's 270-330 Hz band at acc3:")
    for k in np.linspace(0, X.size - 1, 6).astype(int):
        print(
            f"    X {X[k]:9.3e} m: f {model.frequency[k]:8.3f} / {meas.frequency[k]:8.3f} Hz, "
            f"zeta {100 * model.damping_ratio[k]:.4f} / {100 * meas.damping_ratio[k]:.4f} %"
        )


def run(mesh, patch, modes, ratios=(), exponents=(0.0,), lap=None, scan=False, holes=True):
    s = preset("brake-reuss")
    lap = 0.6 * patch if lap is None else lap
    t0 = time.perf_counter()
    parts = lap_beam_parts(s, mesh_size=mesh, lap_mesh_size=lap, holes=holes)
    t_mesh = time.perf_counter() - t0
    solid = solid_specimen(s, parts, patch_size=patch, n_modes=modes, keep_full=True)
    info = solid.model.info
    t0 = time.perf_counter()
    modal_amplitude_curve(solid)
    t_qsma = time.perf_counter() - t0
    print(
        f"mesh {mesh * 1e3:.1f} mm (lap {lap * 1e3:.2f} mm, bolt holes "
        f"{'cut' if holes else 'not cut'}), patches {patch * 1e3:.2f} mm:"
        f" {info['n_full']} coordinates -> {info['n_reduced']} ({modes} modes + "
        f"{3 * info['n_patches']} attachment shapes, {info['n_patches']} patches); meshing "
        f"{t_mesh:.1f} s, reduction {info['reduction_s']:.1f} s, QSMA (20 amplitudes) "
        f"{t_qsma:.2f} s"
    )
    fs = natural_frequencies(solid, n_modes=12)[6:]
    _line("stuck (preset k_t)", fs, _families(solid, 6))
    _line("released", natural_frequencies(solid, interface="none", n_modes=15)[9:15])
    kt0 = s.interface.stiffness_per_area

    def f1(k):
        return natural_frequencies(solid.replace(stiffness_per_area=k), n_modes=7)[6] - PEAKS[0]

    try:
        k = brentq(f1, 0.05 * kt0, 50 * kt0, rtol=1e-6)
        _line(
            f"stuck k_t={k:.3g}",
            natural_frequencies(solid.replace(stiffness_per_area=k), n_modes=12)[6:],
        )
    except ValueError:
        print("  no stiffness per area in [0.05, 50] x the preset's puts mode 1 on 80.4 Hz")
    X = np.array([5e-6, 2e-5, 6e-5])
    for label, sp_ in (("solid", solid), ("1-D", s)):
        c = modal_amplitude_curve(sp_, amplitude=X)
        n_rigid = 6 if sp_ is solid else 3
        f0 = natural_frequencies(sp_, n_modes=n_rigid + 1)[-1]
        drop = 100 * (1 - c.frequency / f0)
        zj = 100 * (c.damping_ratio - s.floor(1))
        print(
            f"  QSMA mode 1 {label:<6s} f0 {f0:7.3f} Hz; drop % {np.round(drop, 4)}; "
            f"joint zeta % {np.round(zj, 4)} at X = 5, 20, 60 um"
        )
    if ratios:
        run_normal_ratio(solid, ratios, exponents)
    if scan:
        run_stiffness_scan(solid)
    return solid


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=float, nargs="+", default=[0.012, 0.008, 0.006])
    ap.add_argument("--patch", type=float, default=0.0064)
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument(
        "--lap",
        type=float,
        default=None,
        help="lap face mesh size [m] (default 0.6 x the patch size)",
    )
    ap.add_argument("--normal-ratio", type=float, nargs="*", default=[])
    ap.add_argument("--exponent", type=float, nargs="+", default=[0.0])
    ap.add_argument("--scan", action="store_true", help="scan k_x, k_y, k_n separately")
    ap.add_argument("--no-holes", action="store_true", help="mesh the bolt holes solid")
    ap.add_argument("--calibrate", action="store_true")
    ap.add_argument(
        "--wave-speed",
        type=float,
        nargs="*",
        default=[],
        help="material wave-speed factors c to try on the first mesh",
    )
    a = ap.parse_args()
    print(f"hammer peaks (brb-hammer acc3): {PEAKS} Hz")
    solids = [
        run(m, a.patch, a.modes, a.normal_ratio, a.exponent, a.lap, a.scan, not a.no_holes)
        for m in a.mesh
    ]
    if a.wave_speed:
        run_wave_speed(solids[0], a.wave_speed)
    if a.calibrate:
        run_calibration(solids[0])


if __name__ == "__main__":
    main()
