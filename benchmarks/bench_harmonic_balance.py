"""Cost and accuracy of the frequency-domain routes on the Brake-Reuss beam, in one run.

Run:  python benchmarks/bench_harmonic_balance.py [--time-stepped N] [--levels 0.05 0.5 2]

(a) One 41-point level (79.2-81.2 Hz, the measured sweeps' grid) by harmonic balance
    (``models.harmonic_balance``, harmonics 1, 3, 5, 64 samples per period, 8 elastic modes
    kept), per force level, after a warm-up call (numba compilation, the reduced model):
    wall and CPU time, Newton iterations, largest energy error per period. Target: at most
    1 s per level on one core.
(b) A 20-amplitude nonlinear mode (``models.nonlinear_mode``, 2-60 um) and the QSMA curve
    at the same amplitudes: wall time, and the largest differences in frequency and damping
    (targets: 2 s; 0.02 % and 5 %).
(c) The time-stepped route for the same points: ``models.forced_response`` (Exudyn,
    60 settling + 10 measured periods per frequency, lock-in read-out, the trapezoidal rule)
    on the first ``--time-stepped`` frequencies of the same grid at the middle force level,
    its wall time, and its wall time scaled to the 41 points; the amplitudes and phases of
    both routes there (harmonic balance at the integrator's warped frequency
    ``(2/h) tan(W h/2)``). At the preset's 0.13 % floor 60 periods are not a steady state (the
    settling time 1/(zeta w) is about 100 periods): the differences are the time route's.
(d) The reduction: the kept modes' stuck frequencies and the largest port-receptance error
    against every mode of the full model, 0-400 Hz, for 2, 4, 8 and 16 kept modes.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from iwan_element.models.reduced import reduced_model, reduction_error

from iwan_element import models

GRID = np.round(np.arange(79.2, 81.2001, 0.05), 4)


def _timed(fn, *a, **k):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn(*a, **k)
    return out, time.perf_counter() - t0, time.process_time() - c0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", type=float, nargs="+", default=[0.05, 0.2, 0.5, 2.0])
    ap.add_argument(
        "--time-stepped",
        type=int,
        default=5,
        help="frequencies of the time-stepped comparison (0: skip)",
    )
    a = ap.parse_args(argv)
    s = models.preset("brake-reuss")
    models.harmonic_balance(s, frequency=GRID[:3], force=0.1)  # warm-up: compile, reduce
    models.nonlinear_mode(s, amplitude=[1e-5, 2e-5])
    print("(a) harmonic balance, one 41-point level (79.2-81.2 Hz)")
    print(
        f"{'F [N]':>7} {'wall [s]':>9} {'cpu [s]':>8} {'Newton':>7} {'peak [Hz]':>10} "
        f"{'peak X [um]':>12} {'energy err':>11} {'success':>8}"
    )
    for F in a.levels:
        r, wall, cpu = _timed(models.harmonic_balance, s, GRID, F)
        k = int(np.argmax(r.amplitude))
        print(
            f"{F:7.3g} {wall:9.3f} {cpu:8.3f} {int(r.iterations.sum()):7d} "
            f"{r.frequency[k]:10.3f} {1e6 * r.amplitude[k]:12.3f} "
            f"{np.abs(r.energy_error).max():11.1e} {str(r.success):>8}"
        )
    X = np.geomspace(2e-6, 60e-6, 20)
    c, wall, cpu = _timed(models.nonlinear_mode, s, X)
    q, wq, _ = _timed(models.modal_amplitude_curve, s, amplitude=X)
    df = np.abs(c.frequency / q.frequency - 1).max()
    dz = np.abs(c.damping_ratio / q.damping_ratio - 1).max()
    print(
        f"\n(b) nonlinear mode (EPMC), 20 amplitudes 2-60 um: {wall:.3f} s wall, {cpu:.3f} s "
        f"cpu (QSMA {wq:.3f} s); largest difference from QSMA: frequency {100 * df:.4f} %, "
        f"damping {100 * dz:.2f} %"
    )
    for i in range(0, 20, 4):
        print(
            f"    X {1e6 * X[i]:7.2f} um  f {c.frequency[i]:.5f} / {q.frequency[i]:.5f} Hz  "
            f"zeta {100 * c.damping_ratio[i]:.4f} / {100 * q.damping_ratio[i]:.4f} %"
        )
    if a.time_stepped:
        F = a.levels[len(a.levels) // 2]
        f = GRID[: a.time_stepped]
        ts, wall_ts, _ = _timed(
            models.forced_response,
            s,
            force_levels=(F,),
            frequencies=f,
            steps_per_period=64,
            spectral_radius=1.0,
        )
        _, wall_hb, _ = _timed(models.harmonic_balance, s, f, F)
        h = 1.0 / (f * 64)
        hb = models.harmonic_balance(s, frequency=np.tan(np.pi * f * h) / (np.pi * h), force=F)
        print(
            f"\n(c) time-stepped stepped sine (Exudyn, 60 + 10 periods a point) at F = {F} N, "
            f"{f.size} frequencies: {wall_ts:.1f} s ({wall_ts / f.size:.2f} s a point, "
            f"{41 * wall_ts / f.size:.0f} s for 41); harmonic balance, same points: "
            f"{wall_hb:.3f} s"
        )
        for fk, xt, pt, xh, ph in zip(f, ts.amplitude[0], ts.phase[0], hb.amplitude, hb.phase):
            print(
                f"    {fk:.3f} Hz  time-stepped {1e6 * xt:9.4f} um {pt:+.4f} rad  harmonic "
                f"balance {1e6 * xh:9.4f} um {ph:+.4f} rad  ({100 * (xt / xh - 1):+.2f} %)"
            )
    print("\n(d) reduction: port receptance error against all modes, 0-400 Hz")
    for n in (2, 4, 8, 16):
        red = reduced_model(s, n_modes=n)
        e = reduction_error(s, n_modes=n, frequencies=np.linspace(0.0, 400.0, 401))
        print(
            f"    {n:2d} elastic modes kept (up to {red.frequency(n):8.1f} Hz) of "
            f"{red.omega_all.size}: largest error {e['max_relative_error']:.2e}, static "
            f"{e['static_relative_error']:.1e}"
        )


if __name__ == "__main__":
    main()
