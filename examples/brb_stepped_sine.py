"""The Brake-Reuss beam's force-controlled stepped-sine sweeps predicted point by point.

At each measured point (frequency ``f`` [Hz], fundamental force ``F`` [N]) the beam model's
harmonic balance (:func:`iwan_element.models.harmonic_balance`: exact Iwan kernel, harmonics
1, 3, 5, 8 kept modes) gives the fundamental displacement amplitude and phase at the drive
point (accelerometer 3, co-located with the shaker). They are compared with the measured
``X = A / (2 pi f)^2`` and phase for

(a) the calibrated preset as it ships (``models.preset("brake-reuss")``, calibrated on the
    hammer ring-down at 2-60 um only): a prediction;
(b) the augmented model, built as ``examples/brb_discrepancy.py`` builds it
    (``diagnose_vibration`` of these sweeps against the preset's QSMA, then
    ``diag.augment(spec)``). The sweeps informed the augmentation, so (b) on these sweeps is
    a consistency check, not a held-out prediction.

Printed: the phase convention of the records (checked, not assumed) and one table, per
level, of the rms of ``log(predicted / measured amplitude)``, the rms phase error [rad] and
the wall time of each model's harmonic balance. Figure: amplitude and phase against
frequency per level, measured points and both predictions. ``DIR/brb_stepped_sine.json``
holds the table. The full run also solves every level in the reverse frequency order: the
same answer means the point-by-point prediction does not depend on the (unrecorded) sweep
direction along these paths.

Data (GPL-3.0, read from ``../shared`` only, never copied): ``brb-steppedsine-fc/
fc_sweeps.csv`` (Chen et al., MSSP 166:108401, 2022; Jin et al., MSSP 166:108402, 2022;
github.com/mattiacenedese/BRBtesting). Figures and the discussion: ``docs/
harmonic_balance_measured.md``.

    python examples/brb_stepped_sine.py [--out DIR] [--quick]

``--quick``: level 4 only, every fourth frequency, no reverse sweep.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from brb_discrepancy import data_dir, diagnose_sweeps, sweeps_curve

from iwan_element import models
from iwan_element.base.result_shape import table_lines

HARMONICS = (1, 3, 5)
N_MODES = 8


def read_levels(path, *, quick=False):
    """``{level: (f [Hz], F [N], X [m], phase [rad])}``, ``X = A / (2 pi f)^2``."""
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    out = {}
    for lev in np.unique(d[:, 0]).astype(int):
        f, F, A, ph = d[d[:, 0] == lev, 1:].T
        out[int(lev)] = (f, F, A / (2 * math.pi * f) ** 2, ph)
    if quick:
        f, F, X, ph = out[4]
        out = {4: (f[::4], F[::4], X[::4], ph[::4])}
    return out


def phase_convention(levels):
    """Lines stating what the records' phase is, from the records themselves.

    At a co-located drive point the modal constant is positive, so a passive structure's
    receptance ``X e^{i phi} / F`` (``x = Re X e^{i W t}``) has ``Im(F e^{-i phi} / X) > 0``,
    i.e. ``-pi < phi < 0`` (``docs/sweeps.md``): the phase of the displacement. The
    acceleration's own phase would lie in ``(0, pi)``.
    """
    ph = np.concatenate([v[3] for v in levels.values()])
    inside = int(np.sum((ph > -math.pi) & (ph < 0)))
    peak = {k: int(np.argmax(v[2] / v[1])) for k, v in levels.items()}
    peaks = ", ".join(
        f"level {k}: {v[3][peak[k]]:+.2f} rad at {v[0][peak[k]]:.2f} Hz" for k, v in levels.items()
    )
    return [
        f"phase convention: {inside} of {ph.size} measured phases lie in (-pi, 0), "
        f"{ph.min():+.3f} .. {ph.max():+.3f} rad: a passive receptance with x = Re X e^(iWt), "
        "the model's convention (the acceleration's phase is this + pi)",
        f"  phase at the largest measured |X/F| (-pi/2 = -1.571 at a resonance): {peaks}",
    ]


def linear_receptance(spec, curve, *, f=80.3):
    """The drive point's linear receptance split as in ``docs/sweeps.md`` (1), model against
    records: mode 1's modal constant and the real residual of the rest at ``f`` [Hz].
    """
    red = models.reduced_model(spec, n_modes=N_MODES)
    sysm, r = red.system, red.mode_index(1)
    nz, W = sysm.n_z, 2 * math.pi * f
    c = float(sysm.modes[nz, r] * sysm.modes[nz + 1, r])
    B = float(sysm.receptance(W, exclude=r)[nz, nz + 1].real)
    return [
        f"linear receptance at the drive point: model mode 1 modal constant c = {c:.4g} 1/kg, "
        f"residual of the other modes at {f} Hz B = {B:.4g} m/N (stuck interface)",
        f"  the records by sweep_curve (independent of the model): {curve.notes}",
    ]


def compare(spec, f, F, X, ph):
    """Harmonic balance of ``spec`` at the measured ``f`` and ``F``, and its errors."""
    t0 = time.perf_counter()
    r = models.harmonic_balance(spec, frequency=f, force=F, harmonics=HARMONICS, n_modes=N_MODES)
    wall = time.perf_counter() - t0
    ok = r.converged
    e_amp = np.log(r.amplitude / X)
    e_ph = np.angle(np.exp(1j * (r.phase - ph)))  # wrapped into (-pi, pi]
    # off resonance (more than 0.5 Hz from the measured peak of |X/F|) the joint barely
    # matters: a bias there is the linear receptance's (modal constant, residual)
    f_peak = f[np.argmax(X / F)]
    below, above = ok & (f < f_peak - 0.5), ok & (f > f_peak + 0.5)
    return r, {
        "rms_log_amplitude": float(np.sqrt(np.mean(e_amp[ok] ** 2))),
        "rms_phase": float(np.sqrt(np.mean(e_ph[ok] ** 2))),
        "wall_time": wall,
        "converged": int(ok.sum()),
        "points": int(ok.size),
        "max_energy_error": float(np.nanmax(np.abs(r.energy_error))),
        "peak_frequency": float(f[ok][np.argmax(r.amplitude[ok] / F[ok])]),
        "mean_log_amplitude_below": float(np.mean(e_amp[below])) if below.any() else None,
        "mean_log_amplitude_above": float(np.mean(e_amp[above])) if above.any() else None,
    }


def reverse_difference(spec, f, F, r):
    """Largest relative amplitude difference when the same points are solved downwards."""
    q = models.harmonic_balance(
        spec, frequency=f[::-1], force=F[::-1], harmonics=HARMONICS, n_modes=N_MODES
    )
    return float(np.max(np.abs(q.amplitude[::-1] / r.amplitude - 1)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "brb_stepped_sine")
    ap.add_argument(
        "--quick",
        action="store_true",
        help="level 4 only, every fourth frequency, no reverse sweep",
    )
    a = ap.parse_args(argv)
    d = data_dir()
    if d is None:
        print(
            "../shared/data/brb-steppedsine-fc (GPL data, read in place) not found: nothing to do"
        )
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    path = d / "brb-steppedsine-fc" / "fc_sweeps.csv"
    levels = read_levels(path, quick=a.quick)
    print("\n".join(phase_convention(levels)))
    spec = models.preset("brake-reuss")
    t0 = time.perf_counter()
    curve = sweeps_curve(path)
    _, diag = diagnose_sweeps(spec, curve)
    aug = diag.augment(spec)
    bt = diag.details["between_tests"]
    print(
        f"augmented model ({time.perf_counter() - t0:.1f} s): + {' + '.join(diag.effects)}; "
        "the between-test nuisances fitted with it (frequency "
        f"{100 * bt['frequency_offset']:+.3f} %, damping {100 * bt['damping_offset']:+.1f} % "
        "for the sweeps) are not part of the model"
    )
    models_ = {"preset": spec, "augmented": aug}
    t0 = time.perf_counter()
    for s in models_.values():  # built once and cached: not in the table's times
        models.reduced_model(s, n_modes=N_MODES)
    print(f"reduced models ({N_MODES} modes) built in {time.perf_counter() - t0:.1f} s")
    print("\n".join(linear_receptance(spec, curve)))
    results, table = {}, {}
    for lev, (f, F, X, ph) in levels.items():
        results[lev] = {}
        table[lev] = {
            "points": int(f.size),
            "force": [float(F.min()), float(F.max())],
            "peak_amplitude": float(X.max()),
            "peak_frequency": float(f[np.argmax(X / F)]),
        }
        for name, s in models_.items():
            r, row = compare(s, f, F, X, ph)
            if not a.quick:
                row["reverse_max_rel_difference"] = reverse_difference(s, f, F, r)
            results[lev][name] = r
            table[lev][name] = row
            for w in r.warnings:
                print(f"level {lev} {name}: {w}")
    print_table(table, quick=a.quick)
    (a.out / "brb_stepped_sine.json").write_text(
        json.dumps(
            {
                "quick": a.quick,
                "harmonics": list(HARMONICS),
                "n_modes": N_MODES,
                "effects": list(diag.effects),
                "levels": table,
            },
            indent=1,
        )
    )
    figure(a.out / "brb_stepped_sine.png", levels, results, diag.effects)
    print(f"wrote {a.out / 'brb_stepped_sine.png'} and {a.out / 'brb_stepped_sine.json'}")
    return 0


def print_table(table, *, quick):
    print(
        "\nmeasured sweeps against harmonic balance at the measured f and F "
        f"(harmonics {', '.join(map(str, HARMONICS))}, {N_MODES} modes)"
        + (" [--quick: level 4, every fourth point]" if quick else "")
    )
    print(
        "  (a) preset as shipped (hammer-calibrated: a prediction); (b) augmented "
        "(the sweeps informed it: a consistency check)"
    )
    cols = [
        ("level", "5d"),
        ("points", "6d"),
        ("F [N]", "^11"),
        ("peak X [um]", "11.0f"),
        ("(a) rms log X", "13.3f"),
        ("(a) rms ph [rad]", "16.3f"),
        ("(a) s", "6.2f"),
        ("(b) rms log X", "13.3f"),
        ("(b) rms ph [rad]", "16.3f"),
        ("(b) s", "6.2f"),
    ]
    rows = []
    for lev, t in table.items():
        p, g = t["preset"], t["augmented"]
        rows.append(
            (
                lev,
                t["points"],
                f"{t['force'][0]:.3f}-{t['force'][1]:.3f}",
                1e6 * t["peak_amplitude"],
                p["rms_log_amplitude"],
                p["rms_phase"],
                p["wall_time"],
                g["rms_log_amplitude"],
                g["rms_phase"],
                g["wall_time"],
            )
        )
    print("\n".join(table_lines(cols, rows)))
    print(
        "  peak of |X/F| [Hz]; mean log(predicted/measured X) more than 0.5 Hz below and "
        "above the measured peak; convergence, energy balance, sweep direction:"
    )
    for lev, t in table.items():
        for name in ("preset", "augmented"):
            r = t[name]
            rev = r.get("reverse_max_rel_difference")
            bias = " ".join(
                "  n/a " if b is None else f"{b:+.3f}"
                for b in (r["mean_log_amplitude_below"], r["mean_log_amplitude_above"])
            )
            print(
                f"  level {lev} {name:9s}: peak {r['peak_frequency']:.2f} (measured "
                f"{t['peak_frequency']:.2f}); off-resonance {bias}; {r['converged']}/"
                f"{r['points']} converged, energy error <= {r['max_energy_error']:.1e}"
                + ("" if rev is None else f", downward sweep differs by <= {rev:.1e}")
            )


def figure(path, levels, results, effects):
    import matplotlib.pyplot as plt

    n = len(levels)
    fig, axes = plt.subplots(2, n, figsize=(3.6 * n + 1, 6), sharex="col", squeeze=False)
    for j, (lev, (f, F, X, ph)) in enumerate(levels.items()):
        a1, a2 = axes[0, j], axes[1, j]
        a1.plot(f, 1e6 * X, "o", mfc="none", color="k", ms=4, label="measured")
        a2.plot(f, ph, "o", mfc="none", color="k", ms=4)
        for name, style, label in (
            ("preset", ".-", "(a) preset (hammer-calibrated)"),
            ("augmented", ".--", "(b) + " + " + ".join(effects)),
        ):
            r = results[lev][name]
            a1.plot(r.frequency, 1e6 * r.amplitude, style, label=label)
            a2.plot(r.frequency, r.phase, style)
        a1.set_title(f"level {lev}: F {F.min():.2f}-{F.max():.2f} N", fontsize=9)
        a2.set_xlabel("frequency [Hz]")
        for ax in (a1, a2):
            ax.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("displacement amplitude at acc. 3 [um]")
    axes[1, 0].set_ylabel("phase (receptance-like) [rad]")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
