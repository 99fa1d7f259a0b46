"""Every mode from one joint: calibrate the Brake-Reuss beam on mode 1, predict mode 2.

1. The beam model (``models.preset("brake-reuss")``) is calibrated on mode 1 of the hammer
   ring-down at accelerometer 3 (``calibrate``, as ``brb_discrepancy.py`` does); mode 2's
   curve at acc3 (band 270-325 Hz) gives ONLY its linear floor, from its lowest amplitudes
   (``calibrate(floors={2: ...})``): the joint is never fitted on mode 2.
2. The release state of the prediction is read off the measured record: 50 ms after the
   impact, mode 1's and mode 2's displacement amplitudes at acc3 (band-passed Hilbert
   envelopes, ``scipy.signal``, log-linear fits over the next 0.3 s).
3. The multi-mode ring-down (``models.ringdown(amplitude={1: X1, 2: X2}, sensors=...)``)
   rings both modes through the same interface; the predicted records at acc3, acc2 and
   acc1 are read like the measured ones (``RingdownResult.sensor_curve``), and mode 2's
   predicted curves at acc3 and acc2 and the ratio of its amplitudes at the two sensors (a
   mode-shape check) are compared with the measured ones at the same amplitudes.

Sensor positions (``REFERENCE.md`` section 7; the model's axis runs from the end carrying
accelerometer 1): acc3 at 0.72 - 0.0762 m (the preset's ``sensor_position``), acc2 at
0.72 - 0.1651 m, acc1 at 0.0254 m. Data (GPL-3.0, read in place from ``../shared``, never
copied): ``brb-hammer/hammer_acc{1,2,3}.csv`` (Chen et al., MSSP 166:108401, 2022).

    python examples/brb_every_mode.py [--out DIR] [--duration 1.2] [--quick]
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from scipy import signal

import iwan_element as ie
from iwan_element import models
from iwan_element.models.calibration import calibrate, measured_amplitude_curve
from iwan_element.models.coupling import compare_curves

ROOT = Path(__file__).resolve().parents[1]
SHARED = [ROOT.parent / "shared" / "data", ROOT.parents[1] / "shared" / "data"]
#: sensor positions along the model's axis [m]
SENSORS = {"acc3": 0.72 - 0.0762, "acc2": 0.72 - 0.1651, "acc1": 0.0254}
BANDS = {1: (60.0, 120.0), 2: (270.0, 325.0)}


def data_dir():
    """The shared data folder holding ``brb-hammer``, or None."""
    for d in SHARED:
        if (d / "brb-hammer" / "hammer_acc3.csv").exists():
            return d / "brb-hammer"
    return None


def record(d, name):
    """``(t, a)`` of a hammer record from the impact on (t [s], a [m/s^2])."""
    t, a = np.loadtxt(d / f"hammer_{name}.csv", delimiter=",", skiprows=1).T
    keep = t >= 0.0
    return t[keep], a[keep]


def envelope(t, a, band):
    """Displacement envelope [m] of the mode in ``band`` [Hz]: zero-phase Butterworth
    band-pass (order 4), Hilbert magnitude over ``(2 pi f_c)^2``."""
    fs = 1.0 / (t[1] - t[0])
    sos = signal.butter(4, band, btype="bandpass", fs=fs, output="sos")
    w = 2 * math.pi * 0.5 * (band[0] + band[1])
    return np.abs(signal.hilbert(signal.sosfiltfilt(sos, a))) / (w * w)


def measured_curves(d):
    """Mode 1 at acc3 (as the calibration reads it) and mode 2 at acc3 and acc2."""
    out = {(1, "acc3"): measured_amplitude_curve(d / "hammer_acc3.csv")}
    for name in ("acc3", "acc2"):
        t, a = record(d, name)
        out[(2, name)] = ie.amplitude_curve(t, a, quantity="acceleration", band=BANDS[2])
    return out


def release_state(d, *, t_r=0.05, span=0.3):
    """``{1: X1, 2: X2}``: both modes' displacement amplitudes at acc3 [m] at ``t_r`` [s]
    after the impact, each from a straight-line fit of its log envelope over
    ``[t_r, t_r + span]``. Right after the impact the envelopes hold the band-pass filters'
    response to it (mode 1 reads about 200 um at 20 ms, mode 2 swings between 2 and 4 um in
    the first 50 ms), so ``t_r`` is 50 ms, past about two of the 270-325 Hz filter's time
    constants, and the fit smooths the beating."""
    t, a = record(d, "acc3")
    fit = (t >= t_r) & (t <= t_r + span)
    out = {}
    for mode, band in BANDS.items():
        slope, icpt = np.polyfit(t[fit], np.log(envelope(t, a, band)[fit]), 1)
        out[mode] = float(math.exp(icpt + slope * t_r))
    return out


def amplitude_ratio(t, a2, a3, band, span):
    """Median of mode ``band``'s envelope at acc2 over that at acc3 over ``span`` [s]."""
    m = (t >= span[0]) & (t <= span[1])
    return float(np.median(envelope(t, a2, band)[m] / envelope(t, a3, band)[m]))


def predict(d, *, duration=1.2, quick=False):
    """Calibration, measured curves, release and the multi-mode prediction (a dict)."""
    meas = measured_curves(d)
    spec = models.preset("brake-reuss")
    cal = calibrate(spec, meas[(1, "acc3")], floors={2: meas[(2, "acc3")]})
    t_r = 0.05
    amp = release_state(d, t_r=t_r)
    rd = models.ringdown(cal.specimen, amplitude=amp, sensors=tuple(SENSORS.values()),
                         duration=0.6 if quick else duration)
    # mode 1 in the calibration curve's windows (0.25 s, about 20 periods)
    pred = {(1, "acc3"): rd.sensor_curve(0, BANDS[1], n_periods=20.0),
            (2, "acc3"): rd.sensor_curve(0, BANDS[2]),
            (2, "acc2"): rd.sensor_curve(1, BANDS[2])}
    span = (0.05, rd.t[-1] - 0.05)
    t, a3 = record(d, "acc3")
    _, a2 = record(d, "acc2")
    m_ratio = amplitude_ratio(t, a2, a3, BANDS[2], (t_r + span[0], t_r + span[1]))
    p_ratio = amplitude_ratio(rd.t, rd.sensor_acceleration[1], rd.sensor_acceleration[0],
                              BANDS[2], span)
    return {"calibration": cal, "measured": meas, "release_time": t_r, "amplitude": amp,
            "ringdown": rd, "predicted": pred, "ratio": (m_ratio, p_ratio),
            "errors": {k: compare_curves(pred[k], meas[k]) for k in pred}}


def report(out) -> str:
    """The prediction's account: each curve against the measured one at the same
    amplitudes, the first (coupled) window, and the mode-shape check."""
    rd, cal = out["ringdown"], out["calibration"]
    lines = [cal.report(), "",
             f"release {1e3 * out['release_time']:.1f} ms after the impact: mode 1 "
             f"{1e6 * out['amplitude'][1]:.3g} um, mode 2 {1e6 * out['amplitude'][2]:.3g} um "
             "at acc3", rd.report(), "",
             "prediction against the measured curve at the same amplitudes "
             "(first = the first measured window inside the predicted range)"]
    for (mode, name), e in out["errors"].items():
        if not len(e["amplitude"]):
            lines.append(f"  mode {mode} at {name}: no common amplitudes")
            continue
        lines.append(
            f"  mode {mode} at {name}: {len(e['amplitude'])} points "
            f"{1e6 * e['amplitude'].min():.3g}-{1e6 * e['amplitude'].max():.3g} um; "
            f"max |df/f| {100 * np.max(np.abs(e['frequency_shift'])):.3f} %, "
            f"max |dzeta/zeta| {100 * np.max(np.abs(e['damping_ratio'] - 1)):.1f} %; first: "
            f"f {e['frequency'][0]:.3f} vs {e['frequency_reference'][0]:.3f} Hz, zeta "
            f"{100 * e['damping'][0]:.4f} vs {100 * e['damping_reference'][0]:.4f} %")
    m, p = out["ratio"]
    lines.append(f"  mode 2 amplitude acc2/acc3: measured {m:.3f}, predicted {p:.3f} "
                 f"({100 * (p / m - 1):+.1f} %)")
    return "\n".join(lines)


def figure(path, out):
    """Measured and predicted f(X), zeta(X) of mode 2 at acc3 and acc2 (and mode 1 at acc3)."""
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(2, 3, figsize=(13, 6.5))
    for j, key in enumerate([(1, "acc3"), (2, "acc3"), (2, "acc2")]):
        meas, pred = out["measured"][key], out["predicted"][key]
        meas.plot((axs[0, j], axs[1, j]), label="measured", ls="none")
        pred.plot((axs[0, j], axs[1, j]), label="predicted (multi-mode ring-down)",
                  marker="", ls="-")
        axs[0, j].set_title(f"mode {key[0]} at {key[1]}")
        axs[0, j].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out") / "brb_every_mode")
    ap.add_argument("--duration", type=float, default=1.2, help="ring-down length [s]")
    ap.add_argument("--quick", action="store_true", help="a 0.6 s ring-down")
    a = ap.parse_args(argv)
    d = data_dir()
    if d is None:
        print("../shared/data/brb-hammer not found (GPL data, read in place): nothing to do")
        return 0
    out = predict(d, duration=a.duration, quick=a.quick)
    print(report(out))
    a.out.mkdir(parents=True, exist_ok=True)
    figure(a.out / "brb_every_mode.png", out)
    print(f"wrote {a.out / 'brb_every_mode.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
