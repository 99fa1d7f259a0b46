"""Which interface makes mode 2 see mode 1's slip: a measured probe on the hammer record.

Run:  python benchmarks/bench_mode2_coupling.py [--candidates baseline,m1,...] [--json out.json]
      python benchmarks/bench_mode2_coupling.py --screen-only [--candidates ...]
      python benchmarks/bench_mode2_coupling.py --from-json out.json [--bound] [--candidates ...]

The Brake-Reuss hammer record's mode 2 (297.7 Hz) rings in its first windows at 297.40 Hz
and 0.155 %, against 297.70 Hz and 0.10 % late: it sees mode 1's slip (mode 1 at 70-87 um at
acc3). The beam calibrated on mode 1 gives mode 2's first window 0.100 % and 297.68 Hz. Each
candidate (:data:`CANDIDATES`) is an interface variant of ``models.preset("brake-reuss")``
(options of ``InterfaceModel``), and each runs the SAME route (``examples/brb_every_mode.py``:
``models.predict_hammer_test``: linear update on the low-amplitude frequencies, the joint
calibrated on mode 1's curve at acc3, each other mode's floor from its lowest amplitudes;
mode 2's curve is never fitted). A variant the route refuses (a stage not usable) is
reported with the reason.

For each candidate it prints

* a linear screen of the calibrated beam: the stuck frequencies' changes for -10 % of the
  tangential and of the normal stiffness per area (how much each mode loads the interface),
  the tangential one's ratio mode 2 / mode 1 ("load"), mode 2's stuck shape ratio acc2/acc1;
* the route's figures: mode 1's largest frequency and damping errors at acc3, mode 2's first
  predicted window at acc2 and acc3 (frequency, damping; its drop and excess against the
  curve at a fifth of that amplitude) against the record's, and mode 2's largest errors;
* an estimate of what an opening lap edge would do (:func:`opening_estimate`: the hosts'
  normal springs are bilateral, no gap opens in any route).

``--screen-only``: the screen and the opening estimate on the uncalibrated variants (seconds).
``--from-json``: the tables of an earlier ``--json`` run; with ``--bound``, what the record's
first windows ask of each mode's interface (:func:`measured_bound`) with the calibrated
interfaces' shares. The data (GPL-3.0) are read in place from ``../shared/data``; nothing runs
without them.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))

import brb_every_mode as hammer_example  # noqa: E402
from iwan_element.models.modal import linear_modes  # noqa: E402
from iwan_element.models.reduced.dispatch import axis_rows  # noqa: E402
from iwan_element.models.simulation import compare_curves  # noqa: E402
from iwan_element.models.specimens.contact import pressure_field  # noqa: E402

from iwan_element import amplitude_curve, models  # noqa: E402
from iwan_element.base.stages import StageFailed  # noqa: E402

#: interface variants of the preset: {name: Specimen.replace changes}
CANDIDATES = {
    "baseline": {},
    "m0.5": {"stiffness_pressure_exponent": 0.5},
    "m1": {"stiffness_pressure_exponent": 1.0},
    "m2": {"stiffness_pressure_exponent": 2.0},
    "uniform30": {"pressure": "uniform-cone"},
    "linear25": {"cone_angle_deg": 25.0},
    "linear45": {"cone_angle_deg": 45.0},
    "uniform45": {"pressure": "uniform-cone", "cone_angle_deg": 45.0},
    "uniform60": {"pressure": "uniform-cone", "cone_angle_deg": 60.0},
    "linear60": {"cone_angle_deg": 60.0},
    "n80": {"n_points": 80},
    "kn0.1": {"normal_stiffness_per_area": 1.0e12},
    "kn10": {"normal_stiffness_per_area": 1.0e14},
    "kn0.03": {"normal_stiffness_per_area": 3.0e11},
    "kn0.01": {"normal_stiffness_per_area": 1.0e11},
    "kn0.1-linear60": {"normal_stiffness_per_area": 1.0e12, "cone_angle_deg": 60.0},
}


def _stuck(spec, n: int = 2) -> np.ndarray:
    """The ``n`` lowest elastic stuck frequencies [Hz]."""
    return np.array([linear_modes(spec, mode=k)[0] for k in range(1, n + 1)]) / (2 * math.pi)


def screen(spec) -> dict:
    """Linear figures of ``spec`` (module docstring): the stuck frequencies' relative changes
    for -10 % of the tangential and of the normal stiffness per area, the tangential one's
    ratio mode 2 / mode 1, and mode 2's stuck shape ratio acc2/acc1 (and acc2/acc3).
    """
    itf = spec.interface
    f0 = _stuck(spec)
    ft = _stuck(spec.replace(stiffness_per_area=0.9 * itf.stiffness_per_area))
    fn = _stuck(spec.replace(normal_stiffness_per_area=0.9 * itf.normal_stiffness_per_area))
    _, phi, _, L, pts = linear_modes(spec, mode=2)
    rows = axis_rows(spec, [hammer_example.SENSORS[n] for n in ("acc1", "acc2", "acc3")])
    w1, w2, w3 = np.abs(rows @ phi)
    dt, dn = ft / f0 - 1, fn / f0 - 1
    return {
        "f_stuck": f0.tolist(),
        "dkt": dt.tolist(),
        "dkn": dn.tolist(),
        "load_ratio": float(dt[1] / dt[0]),
        "shape2_acc2_acc1": float(w2 / w1),
        "shape2_acc2_acc3": float(w2 / w3),
        "n_points": len(pts),
        "kt": itf.stiffness_per_area,
    }


def opening_estimate(spec, amplitudes=(87e-6, 60e-6, 30e-6)) -> dict:
    """What an opening lap edge would do to the stuck frequencies, estimated (the 1-D host's
    normal springs are linear and bilateral: no gap opens in any route).

    On the pressure grid of the lap (``pressure_field``, 600 x 41 cells, so the estimate does
    not hang on where the strips' edges fall): each contact cell's normal spring
    ``k_n dA`` is compressed by the preload, ``delta = p / k_n``; mode 1 at sensor amplitude
    ``X1`` moves the normal gap by ``g = |Gn phi_1 / S phi_1| X1`` (the contact points'
    gaps, linear between them), and where ``g > delta`` the cell opens for part of the cycle.
    Mode 1 on itself: the cell's first-harmonic (describing-function) stiffness of
    ``F = -k min(g, delta)``; mode 2, small and riding on mode 1: the fraction of mode 1's
    cycle the cell is open. Each scales the cell's share of the mode's stiffness,
    ``e = k_n dA (Gn phi)^2 / w^2``: ``df/f = -1/2 sum loss e``.
    """
    m = [linear_modes(spec, mode=r) for r in (1, 2)]
    L, pts = m[0][3], m[0][4]
    x, _, p = pressure_field(spec)
    dA = (spec.overlap / p.shape[0]) * (spec.width / p.shape[1])
    xp = pts.x - spec.lap_start
    on = p > 0
    kn = spec.interface.normal_stiffness_per_area
    delta = p[on] / kn
    xc = np.broadcast_to(x[:, None], p.shape)[on]
    gaps = [np.interp(xc, xp, L.Gn @ phi) for _, phi, *_ in m]
    e = [kn * dA * g**2 / w**2 for (w, *_), g in zip(m, gaps)]
    g1 = np.abs(gaps[0] / (L.S @ m[0][1]))
    s = np.sin(np.linspace(0.0, 2 * np.pi, 721)[:-1])
    out = {"normal_share": [float(e[0].sum()), float(e[1].sum())]}
    for X1 in amplitudes:
        G = g1 * X1
        opens = G > delta
        Go, do = G[opens, None], delta[opens, None]
        own = 1 - np.mean(np.minimum(Go * s, do) * s, axis=1) / (0.5 * Go[:, 0])
        riding = np.mean(Go * s > do, axis=1)
        out[X1] = (
            float(-0.5 * (own * e[0][opens]).sum()),
            float(-0.5 * (riding * e[1][opens]).sum()),
        )
    return out


def interface_shares(spec) -> dict:
    """``{"tangential": (mode 1, mode 2), "normal": (...)}``: the stuck interface's share of
    each mode's stiffness, ``sum k_i (G_i phi)^2 / w^2`` over the contact points' tangential
    (``KT_i``) and normal (``k_n,i``) springs [-]; ``1/2`` of a share is the mode's
    ``d ln f / d ln k`` for that spring set.
    """
    m = [linear_modes(spec, mode=r) for r in (1, 2)]
    L, pts = m[0][3], m[0][4]
    return {
        "tangential": tuple(float((pts.KT * (L.G @ p) ** 2).sum() / w**2) for w, p, *_ in m),
        "normal": tuple(
            float((pts.normal_stiffness * (L.Gn @ p) ** 2).sum() / w**2) for w, p, *_ in m
        ),
    }


def measured_bound(d, specs: dict) -> dict:
    """What the record's first windows ask of each mode's interface (``--bound``), for each
    specimen of ``specs`` ({name: Specimen}).

    The record's mode 1 at acc3 (windows of 20 periods, as the calibration reads it) and
    mode 2 at acc3 and acc2 (windows that follow the decay): the first window's frequency
    drop ``df/f`` and damping excess ``dzeta`` against the curve at a fifth of the first
    window's amplitude (:func:`reference_window`). With ``s`` the mode's interface share
    (:func:`interface_shares`, tangential plus normal), the interface must lose
    ``2 |df/f| / s`` of its stiffness on average over the cycle and dissipate
    ``eta = 4 pi dzeta / s`` of its peak strain energy per cycle (``zeta = D / (4 pi E)``),
    whatever the mechanism.
    """
    recs = hammer_example.records(d)
    i0 = int(np.argmax(np.abs(recs["acc3"][2])))
    curves = {}
    for r, n in ((1, "acc3"), (2, "acc3"), (2, "acc2")):
        _, t, a = recs[n]
        kw = {"window": 20.0 / 80.5} if r == 1 else {}
        band = hammer_example.BANDS[r]
        curves[(r, n)] = amplitude_curve(t[i0:], a[i0:], quantity="acceleration", band=band, **kw)
    out = {}
    for name, spec in specs.items():
        sh = interface_shares(spec)
        out[name] = {}
        for (r, n), c in curves.items():
            _, f, z = first_window(c)
            fl, zl = reference_window(c)
            share = sh["tangential"][r - 1] + sh["normal"][r - 1]
            out[name][(r, n)] = {
                "first_um": 1e6 * float(c.amplitude[0]),
                "drop": f / fl - 1,
                "excess": z - zl,
                "share": share,
                "stiffness_loss": 2 * abs(f / fl - 1) / share,
                "eta": 4 * math.pi * (z - zl) / share,
            }
    return out


def calibrated_variant(base, name: str, calibrated: dict):
    """The candidate ``name`` with the route's updated and calibrated values (``--json``'s
    ``calibrated``): its stuck interface as the route left it.
    """
    return base.replace(
        **CANDIDATES[name],
        stiffness_per_area=calibrated["stiffness_per_area"],
        friction=calibrated["friction"],
        chi=calibrated["chi"],
        youngs_modulus=calibrated["youngs_modulus"],
    )


def first_window(curve) -> tuple:
    """``(amplitude [m], frequency [Hz], damping [-])`` of a curve's first window."""
    return float(curve.amplitude[0]), float(curve.frequency[0]), float(curve.damping_ratio[0])


def reference_window(curve, factor: float = 5.0) -> tuple:
    """``(frequency [Hz], damping [-])`` at ``1/factor`` of the curve's first amplitude
    (linear in log amplitude, its last window left out: the read-out's end effects; clipped
    to the rest of its range): the mode once the coupled start has decayed. Not the lowest
    windows: the record's mode 2 keeps drifting up in frequency at its smallest amplitudes
    (297.70 Hz at 0.06 um, 297.74 Hz at 0.01 um, acc3), and the predicted ring-down (1.2 s)
    reaches a sixth of its first amplitude. ``curve``: an ``AmplitudeCurve`` or
    :func:`curve_dict`'s dict.
    """
    c = curve if isinstance(curve, dict) else curve_dict(curve)
    a, f, z = (np.asarray(c[k][:-1]) for k in ("amplitude", "frequency", "damping_ratio"))
    order = np.argsort(a)
    x = math.log(max(a[0] / factor, a.min()))
    la = np.log(a[order])
    return float(np.interp(x, la, f[order])), float(np.interp(x, la, z[order]))


def curve_dict(curve) -> dict:
    """A curve's amplitude [m], frequency [Hz] and damping [-] as lists (for ``--json``)."""
    return {
        "amplitude": curve.amplitude.tolist(),
        "frequency": curve.frequency.tolist(),
        "damping_ratio": curve.damping_ratio.tolist(),
    }


def max_errors(out, key) -> tuple:
    """Largest |df/f| and |dzeta/zeta| [-] of the predicted curve ``key`` against the record."""
    e = compare_curves(out.predicted[key], out.measured[key])
    if not len(e["amplitude"]):
        return math.nan, math.nan
    return float(np.abs(e["frequency_shift"]).max()), float(np.abs(e["damping_ratio"] - 1).max())


def route(spec, d, duration: float) -> dict:
    """The hammer route on ``spec`` (``brb_every_mode.predict``'s call) and its figures."""
    out = models.predict_hammer_test(
        spec,
        hammer_example.records(d),
        modes=(1, 2),
        bands=hammer_example.BANDS,
        release_time=0.05,
        fit_span=0.3,
        duration=duration,
    )
    res = {"success": bool(out.success), "release_um": {k: 1e6 * v for k, v in out.release.items()}}
    res["mode1_acc3"] = max_errors(out, (1, "acc3"))
    for n in ("acc2", "acc3"):
        res[f"mode2_{n}"] = max_errors(out, (2, n))
        res[f"first2_{n}_pred"] = first_window(out.predicted[(2, n)])
        res[f"first2_{n}_meas"] = first_window(out.measured[(2, n)])
        res[f"ref2_{n}_pred"] = reference_window(out.predicted[(2, n)])
        res[f"ref2_{n}_meas"] = reference_window(out.measured[(2, n)])
        res[f"curve2_{n}_pred"] = curve_dict(out.predicted[(2, n)])
        res[f"curve2_{n}_meas"] = curve_dict(out.measured[(2, n)])
        res[f"ratio2_{n}"] = out.ratios.get((2, n))
    res["ratio2_acc1"] = out.ratios.get((2, "acc1"))
    cal = out.calibration.specimen
    res["calibrated"] = {
        "stiffness_per_area": cal.interface.stiffness_per_area,
        "friction": cal.friction,
        "chi": cal.interface.chi,
        "floors": [cal.floor(1), cal.floor(2)],
        "youngs_modulus": cal.youngs_modulus,
    }
    res["screen"] = screen(cal)
    res["opening"] = {str(k): v for k, v in opening_estimate(cal).items()}
    return res


def print_screen(rows: dict) -> None:
    print(
        "\n| candidate | points | f1, f2 stuck [Hz] | df1, df2 for -10 % k_t | ratio 2/1 "
        "| df1, df2 for -10 % k_n | mode 2 acc2/acc1 |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, s in rows.items():
        print(
            f"| {name} | {s['n_points']} | {s['f_stuck'][0]:.2f}, {s['f_stuck'][1]:.2f} | "
            f"{100 * s['dkt'][0]:+.3f}, {100 * s['dkt'][1]:+.3f} % | {s['load_ratio']:.3f} | "
            f"{100 * s['dkn'][0]:+.3f}, {100 * s['dkn'][1]:+.3f} % | "
            f"{s['shape2_acc2_acc1']:.3f} |"
        )


def _coupled(r: dict, n: str, what: str) -> tuple:
    """Mode 2's first window at sensor ``n`` against a fifth of its amplitude: frequency drop
    [-] and damping excess [-] (``what``: "pred" or "meas").
    """
    _, f, z = r[f"first2_{n}_{what}"]
    fl, zl = r[f"ref2_{n}_{what}"]
    return f / fl - 1, z - zl


def _window_cell(r: dict, n: str, what: str) -> str:
    x, f, z = r[f"first2_{n}_{what}"]
    d, e = _coupled(r, n, what)
    return f"{1e6 * x:.2f}, {f:.3f}, {100 * z:.4f} ({100 * d:+.3f} %, {100 * e:+.4f})"


def print_route(rows: dict) -> None:
    meas = next(iter(rows.values()))
    print(
        "\nrecord, mode 2's first window: um, Hz, % (drop, excess against a fifth of its "
        "amplitude): " + "; ".join(f"{n} {_window_cell(meas, n, 'meas')}" for n in ("acc2", "acc3"))
    )
    print(
        "\n| candidate | mode 1 acc3 max df/f, dzeta/zeta | mode 2 first window acc2: um, Hz, % "
        "(drop, excess) | acc3 | mode 2 max errors acc2; acc3 | load ratio 2/1 | k_t, mu, chi |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, r in rows.items():
        e2 = "; ".join(
            f"{100 * r[f'mode2_{n}'][0]:.3f} %, {100 * r[f'mode2_{n}'][1]:.1f} %"
            for n in ("acc2", "acc3")
        )
        c = r["calibrated"]
        print(
            f"| {name} | {100 * r['mode1_acc3'][0]:.3f} %, {100 * r['mode1_acc3'][1]:.1f} % | "
            f"{_window_cell(r, 'acc2', 'pred')} | {_window_cell(r, 'acc3', 'pred')} | {e2} | "
            f"{r['screen']['load_ratio']:.3f} | "
            f"{c['stiffness_per_area']:.3g}, {c['friction']:.3f}, {c['chi']:.3f} |"
        )


def print_bound(rows: dict) -> None:
    print(
        "\n| candidate | curve | first window | df/f, dzeta (against a fifth of its amplitude) "
        "| interface share | stiffness lost | energy dissipated per cycle |"
    )
    print("|---|---|---|---|---|---|---|")
    for name, b in rows.items():
        for (r, n), v in b.items():
            print(
                f"| {name} | mode {r} at {n} | {v['first_um']:.2f} um | {100 * v['drop']:+.3f} %, "
                f"{100 * v['excess']:+.4f} points | {100 * v['share']:.2f} % | "
                f"{100 * v['stiffness_loss']:.1f} % | {100 * v['eta']:.1f} % |"
            )


def print_opening(rows: dict) -> None:
    print(
        "\nan opening lap edge, estimated (opening_estimate): stuck df/f of mode 1 on itself, "
        "of mode 2 riding on mode 1, at mode 1's amplitude at acc3"
    )
    for name, o in rows.items():
        cells = "; ".join(
            f"{1e6 * float(k):.0f} um: {100 * v[0]:+.3f} %, {100 * v[1]:+.3f} %"
            for k, v in o.items()
            if k != "normal_share"
        )
        share = o["normal_share"]
        print(f"  {name} (normal springs' share {share[0]:.4f}, {share[1]:.4f}): {cells}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", default=",".join(CANDIDATES))
    ap.add_argument("--screen-only", action="store_true")
    ap.add_argument(
        "--bound", action="store_true", help="what the record's first windows ask of the interface"
    )
    ap.add_argument("--duration", type=float, default=1.2)
    ap.add_argument("--json", type=Path, default=None, help="append each route's figures here")
    ap.add_argument(
        "--from-json", type=Path, default=None, help="print the tables of an earlier --json run"
    )
    a = ap.parse_args(argv)
    names = [c.strip() for c in a.candidates.split(",") if c.strip()]
    unknown = set(names) - set(CANDIDATES)
    if unknown:
        raise SystemExit(f"unknown candidates {sorted(unknown)}; known: {list(CANDIDATES)}")
    base = models.preset("brake-reuss")
    if a.bound:
        d = hammer_example.data_dir()
        if d is None:
            print("../shared/data/brb-hammer not found (GPL data, read in place): nothing to do")
            return
        if a.from_json is not None:  # the shares of the stuck interface the route calibrated
            done = json.loads(a.from_json.read_text())
            specs = {
                n: calibrated_variant(base, n, done[n]["calibrated"]) for n in names if n in done
            }
        else:
            specs = {n: base.replace(**CANDIDATES[n]) for n in names}
        print_bound(measured_bound(d, specs))
        return
    if a.from_json is not None:
        rows = json.loads(a.from_json.read_text())
        rows = {n: rows[n] for n in names if n in rows}
        for r in rows.values():  # the reference windows as this version reads them
            for n in ("acc2", "acc3"):
                for what in ("pred", "meas"):
                    if f"curve2_{n}_{what}" in r:
                        r[f"ref2_{n}_{what}"] = reference_window(r[f"curve2_{n}_{what}"])
        print_screen({n: r["screen"] for n, r in rows.items()})
        print_route(rows)
        print_opening({n: r["opening"] for n, r in rows.items()})
        return
    if a.screen_only:
        specs = {n: base.replace(**CANDIDATES[n]) for n in names}
        print_screen({n: screen(v) for n, v in specs.items()})
        print_opening({n: opening_estimate(v) for n, v in specs.items()})
        return
    d = hammer_example.data_dir()
    if d is None:
        print("../shared/data/brb-hammer not found (GPL data, read in place): nothing to do")
        return
    rows, failed = {}, {}
    for n in names:
        t0 = time.perf_counter()
        try:
            rows[n] = route(base.replace(**CANDIDATES[n]), d, a.duration)
        except StageFailed as exc:  # a variant the route refuses is a finding too
            failed[n] = str(exc)
            print(f"{n}: {exc}", flush=True)
            continue
        rows[n]["seconds"] = time.perf_counter() - t0
        print(f"{n}: {rows[n]['seconds']:.0f} s", flush=True)
        if a.json is not None:
            done = json.loads(a.json.read_text()) if a.json.exists() else {}
            done[n] = rows[n]
            a.json.write_text(json.dumps(done, indent=1, default=str))
    print_screen({n: r["screen"] for n, r in rows.items()})
    print_route(rows)
    print_opening({n: r["opening"] for n, r in rows.items()})
    for n, why in failed.items():
        print(f"\n{n}: the route stopped: {why}")


if __name__ == "__main__":
    main()
