"""Diagnose a real friction damper with backlash (ARTS Laboratory record, CC BY-SA 4.0).

The record (``examples/data/ds1_1Hz_25lb.csv``, see ``examples/data/README.md`` for source,
licence and citation) is a banded rotary friction damper driven through a sinusoidal
displacement with a tapered envelope. The workflow:

1. the rig's structural ringing after each break-away (40-50 Hz, a property of the test rig,
   not of the damper) is removed by a zero-phase 20 Hz low-pass (``lowpass=20``); the test
   frequency is 1 Hz, so the joint's own response is untouched;
2. ``diagnose`` fits the Iwan model with the sensor offsets and the joint's starting state
   (the record begins where the previous test left the joint) as nuisance parameters, estimates
   the noise from the record itself (the envelope never repeats an amplitude), and names what
   the model misses;
3. force vs displacement and the residual vs time, before and after, are saved as PNGs, and a
   third figure overlays the force after every reversal against the travel since that
   reversal (measured and fitted): the measured curves collapse onto one shape per
   direction. Two pieces of the device's physics show there: the plateau of the backlash
   (the free play of the linkage), which sits a little on the side of the motion (the
   loose part drags as it crosses the gap: ``Backlash(..., drag=...)``), and a sliding
   force that differs with the direction (a band brake is self-energising one way:
   ``asymmetric_slip``). When neither alone explains a quarter of the misfit, the selection
   rule tries the best one together with each other candidate (its pair step): the open gap
   hides the asymmetry, which alone explains less than a dashpot does. Break-away (static
   friction above sliding friction) and the asymmetry are laws of the same sliders and
   compose (``BreakAway(AsymmetricSlip(joint))``): on some records all three are named. A
   stiffening (Hertz) contact closing the gap was tried and rejected: refitted with the
   joint, its compliance goes to zero.

    python examples/real_damper.py [--record PATH] [--out out/]
"""

import argparse
from pathlib import Path

import numpy as np

from iwan_element import diagnose

HERE = Path(__file__).resolve().parent
ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("--record", default=str(HERE / "data" / "ds1_1Hz_25lb.csv"))
ap.add_argument("--out", default="out", help="folder for the PNGs")
ap.add_argument("--lowpass", type=float, default=20.0, help="rig low-pass [Hz]")
args = ap.parse_args()

t, u, F = np.loadtxt(args.record, delimiter=",", skiprows=1).T
result = diagnose(t, u, F, lowpass=args.lowpass)
print(result.report())
band = np.abs(result.F) < 0.25 * np.abs(result.F).max()
rms = lambda r: float(np.sqrt(np.mean(r[band] ** 2)))  # noqa: E731
before, after = rms(result.F - result.force_before), rms(result.F - result.force_after)
print(
    f"named: {', '.join(result.effects) or 'none'}; RMS misfit where |F| < 0.25 max|F|: "
    f"{before:.0f} N -> {after:.0f} N (ratio {after / before:.2f})"
)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
from matplotlib.figure import Figure  # noqa: E402

out = Path(args.out)
out.mkdir(parents=True, exist_ok=True)
name = Path(args.record).stem
fig = Figure(figsize=(6.5, 4.8))
ax = fig.add_subplot(1, 1, 1)
ax.plot(u * 1e3, result.F * 1e-3, ".", ms=1, color="0.6", label="measured (20 Hz low-pass)")
ax.plot(u * 1e3, result.force_before * 1e-3, "-", lw=0.8, color="C0", label="Iwan fit")
ax.plot(
    u * 1e3,
    result.force_after * 1e-3,
    "--",
    lw=0.8,
    color="C3",
    label="+ " + (" + ".join(result.effects) or "nothing"),
)
ax.set_xlabel("displacement [mm]")
ax.set_ylabel("force [kN]")
ax.grid(True, alpha=0.3)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out / f"{name}_loops.png", dpi=120)
fig = Figure(figsize=(9, 3.8))
ax = fig.add_subplot(1, 1, 1)
ax.plot(t, (result.F - result.force_before) * 1e-3, lw=0.6, color="C0", label="residual before")
ax.plot(t, (result.F - result.force_after) * 1e-3, lw=0.6, color="C3", label="residual after")
ax.set_xlabel("time [s]")
ax.set_ylabel("residual [kN]")
ax.grid(True, alpha=0.3)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(out / f"{name}_residual.png", dpi=120)
from scipy.signal import find_peaks  # noqa: E402

fig = Figure(figsize=(9, 3.8))
axes = fig.subplots(1, 2, sharey=True)
span = 0.4 * float(np.ptp(u))  # travel shown after each reversal
for sgn, ax in zip((1, -1), axes):
    for k in find_peaks(sgn * u, prominence=0.02 * np.ptp(u))[0]:
        x = -sgn * (u[k:] - u[k])
        back = x < np.maximum.accumulate(x) - 0.005 * span  # the next reversal
        stop = np.flatnonzero((x > span) | back)
        m = np.arange(x.size) < (stop[0] if stop.size else x.size)
        F0 = result.offsets["force"]
        ax.plot(x[m] * 1e3, -sgn * (result.F[k:][m] - F0) * 1e-3, color="0.5", lw=0.6)
        ax.plot(x[m] * 1e3, -sgn * (result.force_after[k:][m] - F0) * 1e-3, color="C3", lw=0.6)
    ax.set_xlabel("travel since the reversal [mm]")
    ax.set_title("after a maximum of u" if sgn > 0 else "after a minimum of u", fontsize=8)
    ax.grid(True, alpha=0.3)
axes[0].set_ylabel("force toward the new direction [kN]\n(grey measured, red fitted)")
fig.tight_layout()
fig.savefig(out / f"{name}_reversals.png", dpi=120)
print(
    f"wrote {out / (name + '_loops.png')}, {out / (name + '_residual.png')} and "
    f"{out / (name + '_reversals.png')}"
)
