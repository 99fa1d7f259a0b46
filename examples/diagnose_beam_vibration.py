"""Find what the jointed-beam model is missing from a free-decay test, add it, show the gap shrink.

Run:  python examples/diagnose_beam_vibration.py [--effect viscous|pinning] [--quick] [--out DIR]

The "measured" free decay is the Exudyn jointed beam with an effect the plain model lacks,
hidden from the workflow:

* ``viscous``: material damping of the beams (Rayleigh beta, a damping ratio of 1e-6 in the
  first mode), which shows as a damping floor at low amplitude where the joint's hysteresis
  fades;
* ``pinning``: a spring at each contact point that engages after a small clearance (the bolt
  shank bearing on the hole), which stiffens the joint at high amplitude.

The workflow: simulate the plain model at the same release levels, compare the amplitude-
dependent frequency and damping with ``diagnose_vibration``, wrap each contact point's joint in
the named effect (``VibrationDiagnosis.augment``, modal terms converted to joint terms with the
first mode's slip participation), simulate again and report the mismatch before and after.
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from iwan_element import IwanJoint, PinningStiffness, diagnose_vibration  # noqa: E402
from iwan_element.models.jointed_beam import M16_JOINT, JointedBeamConfig  # noqa: E402
from iwan_element.models.scenarios import free_decay  # noqa: E402

# a lightly preloaded bolt, so that the joint's amplitude dependence is clearly visible
BASE = JointedBeamConfig(joint=M16_JOINT.replace(Fs=150.0))


def curves(res):
    """Per-window (amplitude, frequency, damping) of all runs, sorted by amplitude."""
    return res.curves()


def hidden_truth(effect: str):
    """Config and joint factory of the 'measured' structure."""
    if effect == "viscous":
        w1 = 2 * math.pi * 66.146
        return BASE.replace(rayleigh_beta=2 * 1e-6 / w1), None
    if effect == "pinning":
        return BASE, lambda p: PinningStiffness(IwanJoint(p), k_p=2.0 * p.KT, delta=0.5e-6)
    raise ValueError(f"effect must be 'viscous' or 'pinning', got {effect!r}")


def run(effect: str, *, quick: bool):
    levels = np.geomspace(3e-4, 1e-2, 5 if quick else 8)
    kw = dict(levels=tuple(levels), cycles=10 if quick else 16,
              steps_per_period=60 if quick else 80, linear_comparison=False)
    cfg_true, factory_true = hidden_truth(effect)
    measured = free_decay(cfg_true, joint_factory=factory_true, **kw)
    plain = free_decay(BASE, **kw)
    # one estimate per run (median over its windows): amplitude barely changes within a run
    def per_run(res):
        a = np.array([np.median(r.amplitude) for r in res.runs])
        f = np.array([np.median(r.frequency) for r in res.runs])
        z = np.array([np.median(r.damping) for r in res.runs])
        return a, f, z
    a_m, f_m, z_m = per_run(measured)
    a_p, f_p, z_p = per_run(plain)
    # the simulation at the measured amplitudes (log-log interpolation between runs)
    fp = np.exp(np.interp(np.log(a_m), np.log(a_p), np.log(f_p)))
    zp = np.exp(np.interp(np.log(a_m), np.log(a_p), np.log(z_p)))
    diag = diagnose_vibration(a_m, f_m, z_m, predicted_frequency=fp, predicted_damping_ratio=zp,
                              frequency_noise=2e-7, damping_noise=0.01)
    result = {"effect_hidden": effect, "diagnosis": diag}
    if diag.effect != "none":
        modal = plain.modal
        g = modal.slip_per_q[:, 0]
        tip = abs(modal.tip[0])
        m_tip = 1.0 / tip ** 2                     # modal mass for the tip-amplitude coordinate
        r = float(np.sqrt(np.sum(g * g))) / tip    # joint slip per tip amplitude (rms of points)
        augmented = free_decay(BASE, joint_factory=lambda p: diag.augment(
            IwanJoint(p), modal_mass=m_tip, slip_per_amplitude=r), **kw)
        a_a, f_a, z_a = per_run(augmented)
        fa = np.exp(np.interp(np.log(a_m), np.log(a_a), np.log(f_a)))
        za = np.exp(np.interp(np.log(a_m), np.log(a_a), np.log(z_a)))
        result["augmented"] = (fa, za)
    result["curves"] = (a_m, f_m, z_m, fp, zp)
    return result


def mismatch(f, z, fm, zm):
    """RMS log mismatch of frequency [ppm] and damping [%] against the measurement."""
    return (1e6 * float(np.sqrt(np.mean(np.log(f / fm) ** 2))),
            100 * float(np.sqrt(np.mean(np.log(z / zm) ** 2))))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--effect", choices=("viscous", "pinning"), default="viscous")
    ap.add_argument("--quick", action="store_true", help="small settings (used by the tests)")
    ap.add_argument("--out", type=Path, default=Path("out/diagnose_beam"))
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    res = run(args.effect, quick=args.quick)
    diag = res["diagnosis"]
    a_m, f_m, z_m, fp, zp = res["curves"]
    print(diag.report())
    before = mismatch(fp, zp, f_m, z_m)
    summary = {"effect_hidden": args.effect, "effect_named": diag.effect,
               "effects": list(diag.effects), "mismatch_before_ppm_percent": before}
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    a1.semilogx(a_m * 1e3, 1e6 * (f_m / fp[0] - 1), "o", label="measured (hidden effect)")
    a1.semilogx(a_m * 1e3, 1e6 * (fp / fp[0] - 1), "-", label="plain model")
    a2.loglog(a_m * 1e3, z_m, "o", label="measured (hidden effect)")
    a2.loglog(a_m * 1e3, zp, "-", label="plain model")
    if "augmented" in res:
        fa, za = res["augmented"]
        after = mismatch(fa, za, f_m, z_m)
        summary["mismatch_after_ppm_percent"] = after
        a1.semilogx(a_m * 1e3, 1e6 * (fa / fp[0] - 1), "--", label=f"with {diag.effect}")
        a2.loglog(a_m * 1e3, za, "--", label=f"with {diag.effect}")
        print(f"\nmismatch before: frequency {before[0]:.2f} ppm, damping {before[1]:.1f} %")
        print(f"mismatch after:  frequency {after[0]:.2f} ppm, damping {after[1]:.1f} %")
    a1.set(xlabel="tip amplitude of mode 1 [mm]", ylabel="frequency change [ppm]")
    a2.set(xlabel="tip amplitude of mode 1 [mm]", ylabel="damping ratio")
    for a in (a1, a2):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out / f"diagnose_beam_{args.effect}.png", dpi=110)
    plt.close(fig)
    (args.out / f"diagnose_beam_{args.effect}.json").write_text(json.dumps(summary, indent=2))
    print(f"wrote {args.out}/diagnose_beam_{args.effect}.png and .json")
    return summary


if __name__ == "__main__":
    main()
