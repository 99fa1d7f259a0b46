"""The main job: from a (synthetic) joint test to bolted beams whose modes soften and damp.

Run:  python examples/jointed_beam.py [--out out/jointed_beam] [--quick] [--forced] [--data CSV]

1. Loads the shipped example test record (SYNTHETIC, see models/README.md) and identifies the
   four Iwan parameters with ``fit_loops``.
2. Maps the identified joint onto the example specimen's distributed interface (two bars
   with one M16 bolt; friction and contact stiffness per area from Fs and KT) and runs the
   paper's quasi-static test on it in Exudyn (beam B's end driven axially in the machine
   grip), overlaid on the test record (the paper's Fig. 8).
3. Amplitude-dependent modal properties f(X), zeta(X) by quasi-static modal analysis of
   three lap-jointed specimens with a distributed contact interface (pressure cones from the
   bolt preloads, one Iwan element per contact point): the example specimen with the
   identified joint mapped onto its interface, the two-bolt aluminium cantilever and the
   Brake-Reuss beam calibrated on its measured hammer ring-down (plotted against the
   measurement when ``../shared/data/brb-hammer`` is present; GPL-3.0, read only).
4. A transient ring-down of the Brake-Reuss beam in Exudyn from 60 um at the sensor: the
   decay you can see, and its f(X), zeta(X) next to the QSMA curve.
5. With ``--forced``, a stepped-sine forced response of the example specimen (bolt
   loosened to 0.5 kN, 0.5 % damping floor) through its first resonance at two force levels.

Writes PNG plots and ``summary.json`` to the output folder and prints a short table.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from iwan_element.models import (
    example_test_path,
    forced_response,
    modal_amplitude_curve,
    preset,
    quasi_static_test,
    ringdown,
)
from iwan_element.models.calibration import interface_from_joint, measured_amplitude_curve
from iwan_element.models.modal import linear_modes
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
from scipy.signal import hilbert

from iwan_element import fit_loops, load_test

ROOT = Path(__file__).resolve().parents[1]
BRB_DATA = [
    ROOT.parent / "shared" / "data" / "brb-hammer" / "hammer_acc3.csv",
    ROOT.parents[1] / "shared" / "data" / "brb-hammer" / "hammer_acc3.csv",
]

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
    return data.u[c.start : c.stop], data.F[c.start : c.stop]


def quasi_static(specimen, target_slip: float, *, cycles: int, steps: int):
    """Two runs: the first finds the machine amplitude that gives the target mean slip."""
    r = quasi_static_test(specimen, amplitude=target_slip, cycles=1, steps_per_cycle=steps)
    amp = target_slip * target_slip / r.summary()["mean_slip_amplitude_m"]
    return quasi_static_test(specimen, amplitude=amp, cycles=cycles, steps_per_cycle=steps)


def plot_quasi_static(qs, u_meas, F_meas, path: Path):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.5))
    m = qs.last_cycle()
    a1.plot(u_meas * 1e3, F_meas * 1e-3, ".", ms=2, color="0.5", label="test record (synthetic)")
    a1.plot(
        qs.mean_slip[m] * 1e3,
        qs.joint_force[m] * 1e-3,
        "-",
        color="C3",
        label="beam model: lap force vs mean slip",
    )
    a1.set(
        xlabel="joint slip [mm]",
        ylabel="joint force [kN]",
        title="Fig. 8: joint loop, test vs model",
    )
    a2.plot(qs.machine_displacement[m] * 1e3, qs.machine_force[m] * 1e-3, "-", color="C0")
    a2.set(
        xlabel="machine displacement [mm]",
        ylabel="machine force [kN]",
        title="machine loop (joint + beam compliance)",
    )
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    a1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def log_axis(axis, *, scale=1.0):
    """Readable log axis: ticks at 1, 2, 5 x 10^k only, plain numbers, no minor labels."""
    axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=12))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v * scale:g}"))
    axis.set_minor_formatter(NullFormatter())


def plot_modal(curves: dict, measured, path: Path):
    """f(X) and zeta(X): one column per specimen, frequency change on top, damping below."""
    fig, axes = plt.subplots(2, len(curves), figsize=(5.0 * len(curves), 7.5), squeeze=False)
    for col, (name, entries) in enumerate(curves.items()):
        af, az = axes[0, col], axes[1, col]
        for label, curve, f_lin in entries:
            X = curve.amplitude * 1e6
            ls = "--" if "identified" in label else "-"
            af.plot(
                X,
                100 * (curve.frequency / f_lin - 1),
                ls,
                lw=1.8,
                label=f"{label} ({f_lin:.1f} Hz)",
            )
            az.plot(X, 100 * curve.damping_ratio, ls, lw=1.8, label=label)
        if name == "brake-reuss" and measured is not None:
            f_lin = entries[0][2]
            lo, hi = entries[0][1].amplitude[[0, -1]]
            m = measured.sorted()
            keep = (m.amplitude >= 0.8 * lo) & (m.amplitude <= 1.1 * hi)
            af.plot(
                m.amplitude[keep] * 1e6,
                100 * (m.frequency[keep] / f_lin - 1),
                "o",
                ms=4,
                color="k",
                label="measured (Chen et al. 2022)",
            )
            az.plot(
                m.amplitude[keep] * 1e6,
                100 * m.damping_ratio[keep],
                "o",
                ms=4,
                color="k",
                label="measured",
            )
        af.set(title=name, ylabel="frequency change from stuck interface [%]")
        az.set(xlabel="displacement amplitude at the sensor [um]", ylabel="damping ratio [%]")
        zs = np.concatenate([c.damping_ratio for _, c, _ in entries])
        if zs.max() > 3 * zs.min():  # log only where the range spans a decade or so
            az.set_yscale("log")
            log_axis(az.yaxis)
        for ax in (af, az):
            ax.set_xscale("log")
            log_axis(ax.xaxis)
            ax.grid(True, which="both", alpha=0.3)
        af.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_ringdown(rd, qsma_curve, path: Path):
    fig = plt.figure(figsize=(13, 4.5))
    gs = fig.add_gridspec(2, 3)
    a0 = fig.add_subplot(gs[:, :2])
    a0.plot(
        rd.t,
        rd.modal * 1e6,
        lw=0.5,
        color="C0",
        label="mode 1 at the sensor (acc3 position), modal filtering",
    )
    env = np.abs(hilbert(rd.modal))
    trim = (rd.t > rd.t[-1] * 0.03) & (rd.t < rd.t[-1] * 0.97)  # Hilbert end effects
    a0.plot(rd.t[trim], env[trim] * 1e6, lw=1.5, color="C3", label="mode 1 envelope")
    a0.set(
        xlabel="time [s]",
        ylabel="displacement [um]",
        title="Brake-Reuss beam: Exudyn ring-down from 60 um (distributed Iwan interface)",
    )
    a0.grid(True, alpha=0.3)
    a0.legend(fontsize=8, loc="upper right")
    a1, a2 = fig.add_subplot(gs[0, 2]), fig.add_subplot(gs[1, 2])
    c = rd.curve
    a1.plot(c.amplitude * 1e6, c.frequency, ".", ms=3, label="ring-down")
    a1.plot(qsma_curve.amplitude * 1e6, qsma_curve.frequency, "-", label="QSMA")
    a2.plot(c.amplitude * 1e6, 100 * c.damping_ratio, ".", ms=3, label="ring-down")
    a2.plot(qsma_curve.amplitude * 1e6, 100 * qsma_curve.damping_ratio, "-", label="QSMA")
    a1.set(ylabel="f [Hz]")
    a2.set(ylabel="zeta [%]", xlabel="amplitude at the sensor [um]")
    for ax in (a1, a2):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_forced(fr, path: Path):
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for F0, amp in zip(fr.force_levels, fr.amplitude):
        ax.plot(fr.frequencies, amp / F0 * 1e3, "o-", ms=3, label=f"F = {F0:g} N")
    ax.set(
        xlabel="frequency [Hz]",
        ylabel="amplitude at the tip / force [mm/N]",
        title="stepped-sine forced response",
    )
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
    ap.add_argument(
        "--data",
        type=Path,
        default=None,
        help="measured BRB ring-down CSV (default: ../shared/data/brb-hammer/hammer_acc3.csv)",
    )
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    quick = args.quick

    progress("identifying the joint from the example test record (SYNTHETIC data)")
    data, fit = identify(example_test_path())
    p = fit.joint
    progress(
        f"identified Fs = {p.Fs:.1f} N, KT = {p.KT:.4g} N/m, chi = {p.chi:.4f}, "
        f"beta = {p.beta:.4f} (NRMSE {fit.nrmse:.2e})"
    )

    # the identified (loop-fitted) joint mapped onto the example's interface: mu = Fs / sum P,
    # k_t = KT / contact area
    example = interface_from_joint(preset("example"), p)
    progress("quasi-static test in Exudyn (0.02 Hz, mean slip 0.1 mm)")
    qs = quasi_static(
        example.replace(n_elements=8) if quick else example,
        1e-4,
        cycles=1 if quick else 2,
        steps=80 if quick else 200,
    )
    u_m, F_m = measured_cycle(data, 1e-4)
    plot_quasi_static(qs, u_m, F_m, args.out / "fig8_quasi_static.png")

    n_amp = 10 if quick else 20
    progress("quasi-static modal analysis of three lap-jointed specimens (distributed interface)")
    specimens = {
        "example": (preset("example"), (1, 2)),
        "two-bolt-aluminium": (preset("two-bolt-aluminium"), (1, 2)),
        "brake-reuss": (preset("brake-reuss"), (1,)),
    }
    curves = {}
    for name, (spec, modes) in specimens.items():
        amps = np.geomspace(*spec.amplitude_range, n_amp)
        curves[name] = []
        for mode in modes:
            f_lin = linear_modes(spec, mode=mode)[0] / (2 * np.pi)
            curves[name].append(
                (f"mode {mode}", modal_amplitude_curve(spec, mode=mode, amplitude=amps), f_lin)
            )
    amps = np.geomspace(*example.amplitude_range, n_amp)
    curves["example"].append(
        (
            "mode 2, identified joint",
            modal_amplitude_curve(example, mode=2, amplitude=amps),
            linear_modes(example, mode=2)[0] / (2 * np.pi),
        )
    )
    data_path = args.data or next((q for q in BRB_DATA if q.exists()), None)
    measured = None
    if data_path is not None and Path(data_path).exists():
        measured = measured_amplitude_curve(data_path)
        progress(f"measured BRB ring-down read from {data_path} (GPL-3.0, not copied)")
    else:
        progress("measured BRB ring-down not found (../shared absent): model curves only")
    plot_modal(curves, measured, args.out / "modal_amplitude.png")

    brb = specimens["brake-reuss"][0]
    progress(
        f"transient ring-down of the Brake-Reuss beam in Exudyn "
        f"({len(curves['brake-reuss'][0][1])} QSMA points for comparison)"
    )
    rd = ringdown(brb, amplitude=60e-6, cycles=16 if quick else 60, steps_per_period=48)
    q_rd = modal_amplitude_curve(
        brb, amplitude=np.geomspace(rd.curve.amplitude.min(), rd.curve.amplitude.max(), 20)
    )
    plot_ringdown(rd, q_rd, args.out / "free_decay.png")

    forced = None
    if args.forced:
        # a loose bolt (0.5 kN) plus a 0.5 % damping floor, so that the stepped sine settles
        # within the cycles given
        progress("stepped-sine forced response of the example specimen, bolt at 0.5 kN")
        loose = example.replace(preload=500.0, damping_floor=5e-3)
        if quick:
            loose = loose.replace(n_elements=8, n_points=8)
        forced = forced_response(
            loose,
            force_levels=(0.2, 1.0),
            frequencies=None
            if not quick
            else np.linspace(0.97, 1.01, 9) * linear_modes(loose)[0] / (2 * np.pi),
            settle_cycles=15 if quick else 60,
            measure_cycles=5 if quick else 10,
            steps_per_period=32 if quick else 60,
        )
        plot_forced(forced, args.out / "forced_response.png")

    summary = {
        "data": {"file": example_test_path().name, "synthetic": True, "samples": int(len(data.t))},
        "identified": fit.to_dict(),
        "quasi_static": qs.summary(),
        "modal_curves": {
            name: {label: c.to_dict() for label, c, _ in entries}
            for name, entries in curves.items()
        },
        "example_interface": {
            "friction": example.friction,
            "stiffness_per_area": example.interface.stiffness_per_area,
            "chi": example.interface.chi,
            "beta": example.interface.beta,
        },
        "measured_brb": None if measured is None else measured.to_dict(),
        "ringdown_brb": {
            "curve": rd.curve.to_dict(),
            "wall_time_s": rd.wall_time,
            "n_points": rd.metadata["n_points"],
        },
        "forced_response": None if forced is None else forced.summary(),
        "wall_time_s": time.perf_counter() - T0,
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2))

    print("\n  f(X), zeta(X) by QSMA (first and last amplitude of each curve)")
    width = max(len(label) for entries in curves.values() for label, _, _ in entries)
    print(f"  {'specimen':20s} {'curve':{width}s}   X [um]      f [Hz]  zeta [%]")
    for name, entries in curves.items():
        for label, c, _ in entries:
            for i in (0, -1):
                print(
                    f"  {name:20s} {label:{width}s} {c.amplitude[i] * 1e6:8.2f} "
                    f"{c.frequency[i]:11.4f}  {100 * c.damping_ratio[i]:8.4f}"
                )
    print("\n  Brake-Reuss ring-down vs QSMA")
    print("  X [um]    f ring [Hz]  f pred [Hz]  zeta ring [%]  zeta pred [%]")
    qp = modal_amplitude_curve(brb, amplitude=rd.curve.amplitude)
    for i in np.unique(np.linspace(0, len(qp) - 1, 5).astype(int)):
        print(
            f"  {rd.curve.amplitude[i] * 1e6:7.2f}  {rd.curve.frequency[i]:11.4f}  "
            f"{qp.frequency[i]:11.4f}  {100 * rd.curve.damping_ratio[i]:13.4f}  "
            f"{100 * qp.damping_ratio[i]:13.4f}"
        )
    qsum = summary["quasi_static"]
    print(
        f"\n  quasi-static: machine amplitude {qsum['amplitude_m'] * 1e3:.4f} mm, machine force "
        f"{qsum['machine_force_amplitude_N'] * 1e-3:.3f} kN, joint dissipation per cycle "
        f"{qsum['dissipation_per_cycle_J']:.4g} J"
    )
    progress(
        f"wrote {args.out}/fig8_quasi_static.png, modal_amplitude.png, free_decay.png"
        f"{', forced_response.png' if forced else ''} and summary.json"
    )
    return summary


if __name__ == "__main__":
    main()
