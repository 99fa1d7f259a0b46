"""The main job: from a (synthetic) joint test to the vibrating bolted beam.

Run:  python examples/jointed_beam.py [--out out/jointed_beam] [--quick] [--forced]

1. Loads the shipped example test record (SYNTHETIC, see models/README.md) and identifies the
   four Iwan parameters with ``fit_loops``.
2. Builds the two-beam lap-joint model in Exudyn with them and runs the paper's quasi-static
   test (machine amplitude set so that the joint slips 0.1 mm), overlaid on the test record
   (the paper's Fig. 8).
3. Runs free decays of the first bending mode at several levels, with the identified joint and
   with the bolt's slip force reduced to a loose bolt (preload 0.5 kN), each next to the
   closed-form prediction and to a linear joint of stiffness KT.
4. With ``--forced``, a stepped-sine forced response through the first resonance.

Writes PNG plots and ``summary.json`` to the output folder and prints a short table.
"""
from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from iwan_element import fit_loops, load_test  # noqa: E402
from iwan_element.models import example_test_path  # noqa: E402
from iwan_element.models.jointed_beam import JointedBeamConfig  # noqa: E402
from iwan_element.models.scenarios import (forced_response, free_decay,  # noqa: E402
                                           quasi_static_test)

T0 = time.perf_counter()


def progress(msg: str) -> None:
    print(f"[{time.perf_counter() - T0:6.1f} s] {msg}", flush=True)


def identify(path: Path):
    data = load_test(path, displacement_unit="mm", force_unit="kN")
    fit = fit_loops(data.t, data.u, data.F, smooth=15, seed=0)
    return data, fit


def measured_cycle(data, amplitude: float):
    """Samples (u, F) of the last usable cycle whose amplitude is closest to ``amplitude``."""
    cycles = data.usable_cycles()
    best = min(cycles, key=lambda c: (abs(c.u0 - amplitude), -c.index))
    same = [c for c in cycles if abs(c.u0 - best.u0) < 1e-3 * best.u0]
    c = same[-1]
    return data.u[c.start:c.stop], data.F[c.start:c.stop]


def quasi_static(cfg, target_slip: float, *, cycles: int, steps: int):
    """Two runs: the first finds the machine amplitude that gives the target joint slip."""
    r = quasi_static_test(cfg, amplitude=target_slip, cycles=1, steps_per_cycle=steps)
    slip = r.summary()["joint_slip_amplitude_m"]
    amp = target_slip * target_slip / float(np.mean(slip))
    return quasi_static_test(cfg, amplitude=amp, cycles=cycles, steps_per_cycle=steps)


def plot_quasi_static(qs, u_meas, F_meas, path: Path):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.5))
    m = qs.last_cycle()
    a1.plot(u_meas * 1e3, F_meas * 1e-3, ".", ms=2, color="0.5", label="test record (synthetic)")
    a1.plot(qs.mean_slip[m] * 1e3, qs.total_joint_force[m] * 1e-3, "-", color="C3",
            label="beam model: joint force vs slip")
    a1.set(xlabel="joint slip [mm]", ylabel="joint force [kN]",
           title="Fig. 8: joint loop, test vs model")
    a2.plot(qs.machine_displacement[m] * 1e3, qs.machine_force[m] * 1e-3, "-", color="C0")
    a2.set(xlabel="machine displacement [mm]", ylabel="machine force [kN]",
           title="machine loop (joint + beam compliance)")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_decay(results: dict, path: Path):
    fig, axes = plt.subplots(len(results), 3, figsize=(14, 4 * len(results)), squeeze=False)
    for row, (label, res) in zip(axes, results.items()):
        run = res.runs[-1]
        row[0].plot(run.t, run.tip * 1e3, lw=0.6)
        row[0].set(xlabel="t [s]", ylabel="tip [mm]", title=f"{label}: largest level")
        a, f, z = res.curves()
        al, fl, zl = res.curves("linear")
        grid = np.geomspace(a.min(), a.max(), 50)
        fp, zp = res.modal.predict(grid)
        # shifts relative to the linear joint: the simulation against its own linear-joint run
        # (this removes the integrator's period error), the prediction against the eigenvalue
        f0_sim, f0_eig = np.median(fl), res.modal.frequencies[0]
        row[1].semilogx(a * 1e3, 100 * (f / f0_sim - 1), "o", ms=3, label="Iwan joint (simulated)")
        row[1].semilogx(grid * 1e3, 100 * (fp / f0_eig - 1), "-", label="closed-form prediction")
        row[1].semilogx(al * 1e3, 100 * (fl / f0_sim - 1), "x", ms=3, label="linear joint KT")
        row[1].set(xlabel="tip amplitude of mode 1 [mm]",
                   ylabel=f"frequency shift from {f0_eig:.2f} Hz [%]")
        row[2].loglog(a * 1e3, z, "o", ms=3, label="Iwan joint (simulated)")
        row[2].loglog(grid * 1e3, zp, "-", label="closed-form prediction")
        row[2].set(xlabel="tip amplitude of mode 1 [mm]", ylabel="joint damping ratio")
        for ax in row:
            ax.grid(True, which="both", alpha=0.3)
        row[1].legend(fontsize=8)
        row[2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_forced(fr, path: Path):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for F0, amp in zip(fr.force_levels, fr.amplitude):
        ax.plot(fr.frequencies, amp / F0 * 1e3, "o-", ms=3, label=f"F = {F0:g} N")
    ax.set(xlabel="frequency [Hz]", ylabel="tip amplitude / force [mm/N]",
           title="stepped-sine forced response")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/jointed_beam"), help="output folder")
    ap.add_argument("--quick", action="store_true", help="small settings (used by the tests)")
    ap.add_argument("--forced", action="store_true", help="also run the forced response")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    quick = args.quick

    progress("identifying the joint from the example test record (SYNTHETIC data)")
    data, fit = identify(example_test_path())
    p = fit.params
    progress(f"identified Fs = {p.Fs:.1f} N, KT = {p.KT:.4g} N/m, chi = {p.chi:.4f}, "
             f"beta = {p.beta:.4f} (NRMSE {fit.nrmse:.2e})")

    cfg = JointedBeamConfig(joint=p, n_elements=8 if quick else 16)
    progress("quasi-static test in Exudyn (0.02 Hz, joint slip 0.1 mm)")
    qs = quasi_static(cfg, 1e-4, cycles=1 if quick else 2, steps=80 if quick else 200)
    u_m, F_m = measured_cycle(data, 1e-4)
    plot_quasi_static(qs, u_m, F_m, args.out / "fig8_quasi_static.png")

    levels = (1e-3, 4e-3) if quick else (5e-4, 2e-3, 8e-3)
    cycles = 12 if quick else 30
    decays = {}
    for label, c in [("identified joint (30 kN preload)", cfg),
                     ("loose bolt (0.5 kN preload)", cfg.replace(joint=p.replace(Fs=p.Fs * 0.5 / 30)))]:
        decays[label] = free_decay(c, levels=levels, cycles=cycles, steps_per_period=60 if quick else 100,
                                   progress=progress)
    plot_decay(decays, args.out / "free_decay.png")

    forced = None
    if args.forced:
        # a loose bolt plus 0.5 % material damping of mode 1 (beta = 2 zeta / w1), so that the
        # stepped sine settles within the cycles given
        w1 = 2 * np.pi * decays["identified joint (30 kN preload)"].modal.frequencies[0]
        forced = forced_response(cfg.replace(joint=p.replace(Fs=p.Fs * 0.5 / 30),
                                             rayleigh_beta=2 * 5e-3 / w1),
                                 force_levels=(0.2, 1.0), settle_cycles=20 if quick else 60,
                                 progress=progress)
        plot_forced(forced, args.out / "forced_response.png")

    summary = {
        "data": {"file": example_test_path().name, "synthetic": True,
                 "samples": int(len(data.t))},
        "identified": fit.to_dict(),
        "quasi_static": qs.summary(),
        "free_decay": {k: v.summary() for k, v in decays.items()},
        "forced_response": None if forced is None else forced.summary(),
        "wall_time_s": time.perf_counter() - T0,
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2))

    print("\n  case                               tip [mm]   f [Hz]    f pred    zeta       zeta pred")
    for label, res in decays.items():
        for run in res.runs:
            i = len(run.amplitude) // 2
            fp, zp = res.modal.predict(run.amplitude[i])
            print(f"  {label:34s} {run.amplitude[i] * 1e3:7.3f}  {run.frequency[i]:8.3f}  "
                  f"{fp[0]:8.3f}  {run.damping[i]:.3e}  {zp[0]:.3e}")
    qsum = summary["quasi_static"]
    print(f"\n  quasi-static: machine amplitude {qsum['amplitude_m'] * 1e3:.4f} mm, machine force "
          f"{qsum['machine_force_amplitude_N'] * 1e-3:.3f} kN, joint dissipation per cycle "
          f"{sum(qsum['joint_dissipation_per_cycle_J']):.4g} J")
    progress(f"wrote {args.out}/fig8_quasi_static.png, free_decay.png"
             f"{', forced_response.png' if forced else ''} and summary.json")
    return summary


if __name__ == "__main__":
    main()
