"""Vibration route benchmark: ring-down -> amplitude curve -> modal Iwan fit.

Part A (synthetic, truth known): a single-mode modal Iwan oscillator is integrated in time
with the exact IwanJoint (core.modal.modal_ringdown, independent of the curve extraction),
its acceleration gets a second, linear mode nearby (1.3 f0, half the peak) and white Gaussian
noise of RMS 1 % of the record's RMS, sampled at 12.8 kHz. Per seeded case the parameters are
drawn at random;
the benchmark reports the extracted curve's frequency and damping errors against the closed
form (first-harmonic stiffness, dashpot floor) at the extracted amplitudes, and whether each
identified parameter lies within 2 standard errors of the truth.

Part B (real): the hammer ring-down of the Brake-Reuss beam in ../shared/data/brb-hammer
(GPL-3.0, read in place): RMS frequency and damping errors of the modal Iwan fit.

    python benchmarks/bench_vibration.py --cases 50 --workers 2
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from iwan_element import (
    IwanParameters,
    amplitude_curve,
    fit_modal_iwan,
    modal_iwan_curve,
    modal_ringdown,
)

FS = 12800.0
F0 = 80.0
BAND = (70.0, 92.0)


def draw_case(seed):
    """Random true parameters of one case (unit modal mass, sensor coordinate)."""
    rng = np.random.default_rng(seed)
    chi = rng.uniform(-0.7, -0.3)
    beta = rng.uniform(0.1, 1.0)
    kappa = rng.uniform(0.03, 0.1)
    zeta0 = rng.uniform(1e-3, 2e-3)
    phimax = 1e-3
    w02 = (2 * math.pi * F0) ** 2
    KT = kappa * w02
    c = beta + (chi + 1) / (chi + 2)
    p = IwanParameters(KT * c * phimax / (1 + beta), KT, chi, beta)
    return p, w02 - KT, zeta0, rng


def run_case(seed, duration=4.0):
    p, k_inf, zeta0, rng = draw_case(seed)
    t = np.arange(0.0, duration, 1 / FS)
    q0 = 0.1 * p.phi_max
    a = modal_ringdown(t, p, K_inf=k_inf, q0=q0, zeta0=zeta0).acceleration
    f2, z2 = 1.3 * F0, 2e-3  # the second mode, outside the band
    w2 = 2 * math.pi * f2
    a = a + 0.5 * np.abs(a).max() * np.exp(-z2 * w2 * t) * np.cos(w2 * t + 0.4)
    a = a + 0.01 * np.std(a) * rng.standard_normal(t.size)  # 1 % of the signal's RMS
    cur = amplitude_curve(t, a, quantity="acceleration", band=BAND)
    f_t, z_t = modal_iwan_curve(
        cur.amplitude, p, K_inf=k_inf, zeta0=zeta0, stiffness="harmonic", floor="dashpot"
    )
    ef = np.abs(cur.frequency / f_t - 1)
    ez = np.abs(cur.damping_ratio / z_t - 1)
    fit = fit_modal_iwan(cur)
    x_ref = fit.conventions["x_ref"]
    truth = {
        "f0": math.sqrt(k_inf + p.KT) / (2 * math.pi),
        "zeta0": zeta0,
        "chi": p.chi,
        "delta": p.KT
        * (x_ref / p.phi_max) ** (p.chi + 1)
        / ((k_inf + p.KT) * (p.chi + 2) * (1 + p.beta)),
    }
    if fit.regime == "macroslip":
        truth.update(
            beta=p.beta,
            phi_max=p.phi_max,
            KT=p.KT,
            K_inf=k_inf,
            Fs=p.Fs,
            kappa=p.KT / (k_inf + p.KT),
        )
    z_scores = {k: (fit.parameters[k] - truth[k]) / fit.stderr[k] for k in fit.parameters}
    return {
        "seed": seed,
        "n": len(cur),
        "ef_max": float(ef.max()),
        "ez_max": float(ez.max()),
        "ef_frac": float(np.mean(ef < 1e-4)),
        "ez_frac": float(np.mean(ez < 0.03)),
        "x_min": float(cur.amplitude.min()),
        "x_max": float(cur.amplitude.max()),
        "regime": fit.regime,
        "success": fit.success,
        "z": z_scores,
    }


def part_a(cases, workers, seed0):
    seeds = [seed0 + i for i in range(cases)]
    if workers > 1:
        with ProcessPoolExecutor(workers) as ex:
            rows = list(ex.map(run_case, seeds))
    else:
        rows = [run_case(s) for s in seeds]
    print(
        f"Part A: {cases} seeded ring-downs, f0 = {F0} Hz, 1 % noise, second mode at "
        f"{1.3 * F0:g} Hz (half the peak), band {BAND}"
    )
    print(
        f"{'seed':>5} {'pts':>4} {'X range [um]':>17} {'max|df/f|':>10} {'max|dz/z|':>10} "
        f"{'regime':>10}  |z| of " + ", ".join(rows[0]["z"])
    )
    for r in rows:
        zs = " ".join(f"{abs(v):5.2f}" for v in r["z"].values())
        print(
            f"{r['seed']:5d} {r['n']:4d} {r['x_min'] * 1e6:8.3f}-{r['x_max'] * 1e6:8.3f} "
            f"{r['ef_max']:10.2e} {r['ez_max']:10.2e} {r['regime']:>10}  {zs}"
        )
    ef = np.array([r["ef_max"] for r in rows])
    ez = np.array([r["ez_max"] for r in rows])
    pts_f = np.mean([r["ef_frac"] for r in rows])
    pts_z = np.mean([r["ez_frac"] for r in rows])
    print(
        f"\ncases with every point |df/f| < 1e-4: {np.mean(ef < 1e-4):.0%}; with every point "
        f"|dzeta/zeta| < 3 %: {np.mean(ez < 0.03):.0%}"
    )
    print(
        f"points within 1e-4 in f: {pts_f:.1%}; within 3 % in zeta: {pts_z:.1%}; "
        f"median of per-case max |df/f| {np.median(ef):.2e}, max |dz/z| {np.median(ez):.2e}"
    )
    names = rows[0]["z"].keys()
    for k in names:
        zk = np.array([r["z"].get(k, np.nan) for r in rows])
        print(
            f"  {k:>6}: within 2 stderr in {np.mean(np.abs(zk) < 2):.0%} of cases "
            f"(RMS z {np.sqrt(np.nanmean(zk**2)):.2f})"
        )
    allin = np.mean([all(abs(v) < 2 for v in r["z"].values()) for r in rows])
    print(
        f"  all identified parameters within 2 stderr together: {allin:.0%}; success in "
        f"{np.mean([r['success'] for r in rows]):.0%}"
    )


def brb_file():
    for parent in Path(__file__).resolve().parents:
        f = parent / "shared" / "data" / "brb-hammer" / "hammer_acc3.csv"
        if f.is_file():
            return f
    return None


def part_b():
    f = brb_file()
    if f is None:
        print("Part B skipped: ../shared/data/brb-hammer is absent")
        return
    d = np.loadtxt(f, delimiter=",", skiprows=1)
    cur = amplitude_curve(d[:, 0], d[:, 1], quantity="acceleration", band=(60.0, 120.0))
    print(
        f"\nPart B: {f.name}, {len(cur)} points, X {cur.amplitude.min() * 1e6:.2f}-"
        f"{cur.amplitude.max() * 1e6:.2f} um"
    )
    for stiffness, floor in (("harmonic", "dashpot"), ("secant", "constant")):
        fit = fit_modal_iwan(cur, stiffness=stiffness, floor=floor)
        e = fit.rms_errors()
        print(
            f"  {stiffness:>8}/{floor:<8}: regime {fit.regime}, RMS error f "
            f"{100 * e['frequency']:.4f} %, zeta {100 * e['damping_ratio']:.2f} %, "
            f"success {fit.success}"
        )
    print(fit_modal_iwan(cur).report())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--skip-real", action="store_true")
    args = ap.parse_args()
    t0 = time.perf_counter()
    part_a(args.cases, args.workers, args.seed)
    if not args.skip_real:
        part_b()
    print(f"\n{time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
