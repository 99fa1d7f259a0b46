"""How much one mode's slip raises another mode's joint damping: one exact Iwan joint.

Run:  python benchmarks/bench_masing_coupling.py [--chi -0.47] [--beta 0.1]

One Iwan joint (``phi_max = 1``, the given ``chi`` and ``beta``; the package's exact Masing
kernel, ``core.masing.masing_history``) is driven by the slip of two modes at once,

    u(t) = A1 sin(w1 t) + A2 sin(w2 t),     w2 / w1 = 3.7,

as a joint between two modes of a structure sees it (the modal slips of a lap joint add).
The energy the joint takes from mode 2 per mode-2 cycle is ``W2 = oint F du2`` over whole
periods of both (10 periods of mode 1 = 37 of mode 2, after 2 periods of settling; with
``w2 / w1`` not a ratio of small integers a partial window leaves terms linear in ``A2``
from the harmonics of mode 1's force). Printed: ``W2`` with mode 1 moving over ``W2`` alone
(``A1 = 0``), the coupling factor of mode 2's joint damping, for mode-1 amplitudes from
microslip to macroslip and mode-2 amplitudes down to 0.3 % of mode 1's; and the log-log
slopes of ``W2`` in ``A2`` alone (the closed form: ``3 + chi``) and with mode 1 at
``A1 = 0.1`` (an equivalent viscous damping has slope 2).

What it says (docs/multi_mode.md section 3): below macroslip the factor depends only on
``A2 / A1`` (a power-law joint has no length scale), it grows as mode 2 gets smaller, and the
energy taken from a small mode 2 riding on mode 1's slip goes as ``A2^2``: mode 1's motion
adds a linear (amplitude-independent) damping to mode 2, where mode 2 alone has the
microslip law ``A2^(3 + chi)``.
"""

from __future__ import annotations

import argparse

import numpy as np

from iwan_element.core.history import unit_params
from iwan_element.core.masing import masing_history

RATIO = 3.7
SETTLE, PERIODS, SAMPLES_PER_PERIOD = 2, 10, 40000


def mode2_work(A1: float, A2: float, params) -> float:
    """Energy the joint takes from mode 2 per mode-2 cycle [J per unit phi_max and KT]."""
    t = np.arange((SETTLE + PERIODS) * SAMPLES_PER_PERIOD + 1) / SAMPLES_PER_PERIOD
    u1 = A1 * np.sin(2 * np.pi * t)
    u2 = A2 * np.sin(2 * np.pi * RATIO * t)
    F = masing_history(u1 + u2, params)[0]
    k = slice(SETTLE * SAMPLES_PER_PERIOD, None)
    Fk, u2k = F[k], u2[k]
    return float(np.sum(0.5 * (Fk[1:] + Fk[:-1]) * np.diff(u2k))) / (RATIO * PERIODS)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chi", type=float, default=-0.47)
    ap.add_argument("--beta", type=float, default=0.1)
    args = ap.parse_args(argv)
    p = unit_params(1.0, args.chi, args.beta)
    print(f"one Iwan joint, phi_max = 1, chi = {args.chi}, beta = {args.beta}, w2/w1 = {RATIO}")
    print("coupling factor W2(A1, A2) / W2(0, A2) of mode 2's joint damping:")
    A1s = (0.03, 0.1, 0.3, 0.6, 1.0, 2.0)
    print("  A2 \\ A1 " + "".join(f"{a:>8.2f}" for a in A1s))
    for A2 in (0.003, 0.01, 0.03):
        alone = mode2_work(0.0, A2, p)
        print(f"  {A2:7.3f} " + "".join(f"{mode2_work(A1, A2, p) / alone:8.2f}" for A1 in A1s))
    print("same ratio A2/A1 at two mode-1 amplitudes (microslip: scale-free):")
    for r in (0.003, 0.01, 0.03, 0.1):
        f = [mode2_work(A1, r * A1, p) / mode2_work(0.0, r * A1, p) for A1 in (0.1, 0.3)]
        print(f"  A2/A1 = {r:5.3f}: {f[0]:6.3f} (A1 = 0.1), {f[1]:6.3f} (A1 = 0.3)")
    A2s = np.array([0.001, 0.003, 0.01])
    alone = [mode2_work(0.0, a, p) for a in A2s]
    ridden = [mode2_work(0.1, a, p) for a in A2s]
    s_alone = np.polyfit(np.log(A2s), np.log(alone), 1)[0]
    s_ridden = np.polyfit(np.log(A2s), np.log(ridden), 1)[0]
    print(
        f"log-log slope of W2 in A2 (0.001-0.01): alone {s_alone:.3f} "
        f"(closed form 3 + chi = {3 + args.chi:.3f}); on mode 1's slip (A1 = 0.1) "
        f"{s_ridden:.3f} (viscous: 2)"
    )


if __name__ == "__main__":
    main()
