"""The ``curve`` command of ``iwan-element``: amplitude-dependent frequency and damping of one
mode from a ring-down or stepped-sine sweep file.

::

    iwan-element curve hammer.csv [--band 60,120] [--start 0] [--columns T,Y] [--units RESP,TIME]
                       [--out curve.csv] [--plot curve.png]
    iwan-element curve sweeps.csv [--out curve.csv] [--plot curve.png]

The file's kind and units come from its header (:func:`read_vibration_csv`); a ring-down goes
through :func:`~iwan_element.amplitude_curve` from its largest sample (the impact) on, in the
band given or, when not given, 0.75-1.5 times the frequency of the spectrum's highest peak
above 2 Hz; sweeps go through :func:`~iwan_element.sweep_curve`. The commands' exit status:
0 usable, 3 not usable (the report says why).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["add_curve_command", "run_curve", "spectral_band"]

#: The band around the spectrum's peak frequency when none is given (ratio to the peak).
BAND_RATIO = (0.75, 1.5)


def add_curve_command(sub) -> None:
    """The ``curve`` command and its options."""
    cv = sub.add_parser(
        "curve",
        help="frequency and damping against amplitude from a ring-down or sweep file (CSV)",
        description="Amplitude-dependent frequency and damping ratio of one mode from a "
        "ring-down (time and one response column: displacement, velocity or acceleration) "
        "or from stepped-sine sweeps (frequency, force, response, phase). The kind and the "
        "units are read from the header ('t [s],a [m/s^2]'; 'f [Hz],F [N],A [m/s^2],phase "
        "[rad]') or given with --units.",
    )
    cv.add_argument("csv", type=Path, help="ring-down or stepped-sine sweep record (CSV)")
    cv.add_argument("--columns", metavar="T,Y", help="ring-down: time and response columns")
    cv.add_argument(
        "--units",
        metavar="RESP[,TIME]",
        help="ring-down: units of the response (m, mm, m/s, m/s^2, g, ...) and time (s, ms) "
        "columns when the header does not label them",
    )
    cv.add_argument(
        "--band",
        metavar="LO,HI",
        help="ring-down: band-pass around the mode [Hz] (default: 0.75-1.5 x the spectrum's "
        "highest peak above 2 Hz)",
    )
    cv.add_argument(
        "--start",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="ring-down: start this long after the largest sample (the impact; default 0)",
    )
    cv.add_argument("--out", type=Path, metavar="CSV", help="write the curve as a CSV table")
    cv.add_argument("--plot", type=Path, metavar="PNG", help="write f(X) and zeta(X)")


def spectral_band(t, y) -> tuple[float, tuple[float, float]]:
    """The frequency [Hz] of the highest peak of the record's spectrum above 2 Hz (a Hann
    window; below 2 Hz are a free-free suspension and drift) and the band
    ``BAND_RATIO x`` that frequency, kept below 0.9 x Nyquist.
    """
    dt = float(np.median(np.diff(t)))
    spec = np.abs(np.fft.rfft((y - y.mean()) * np.hanning(y.size)))
    f = np.fft.rfftfreq(y.size, dt)
    spec[f < 2.0] = 0.0
    peak = float(f[int(np.argmax(spec))])
    return peak, (BAND_RATIO[0] * peak, min(BAND_RATIO[1] * peak, 0.45 / dt))


def _pair(text: str, flag: str, what: str) -> tuple[str, str]:
    parts = [s.strip() for s in text.split(",")]
    if len(parts) != 2 or not all(parts):
        raise ValueError(f"{flag} must be {what}, got {text!r}")
    return parts[0], parts[1]


def _ringdown_curve(rec: dict, args):
    from .identify.decays.curve import amplitude_curve

    t, y = rec["t"], rec["y"]
    keep = t >= t[int(np.argmax(np.abs(y)))] + args.start
    if args.band is None:
        peak, band = spectral_band(t[keep], y[keep])
        how = f"band {band[0]:.4g}-{band[1]:.4g} Hz from the spectrum's peak at {peak:.4g} Hz"
    else:
        lo, hi = (float(v) for v in _pair(args.band, "--band", "LO,HI in Hz (e.g. 60,120)"))
        band, how = (lo, hi), f"band {lo:.4g}-{hi:.4g} Hz (given)"
    curve = amplitude_curve(t[keep], y[keep], quantity=rec["quantity"], band=band)
    u = rec["units"]
    head = (
        f"{rec['source']}: ring-down, {t.size} samples ({u['response']}, {u['time']}: "
        f"{rec['quantity']}, converted to SI), from t = {t[keep][0]:.6g} s (largest sample "
        f"+ {args.start:g} s); {how}"
    )
    return curve, head


def _write_csv(path: Path, curve) -> None:
    cols = {
        "amplitude [m]": curve.amplitude,
        "frequency [Hz]": curve.frequency,
        "frequency std [Hz]": curve.frequency_std,
        "damping ratio [-]": curve.damping_ratio,
        "damping ratio std [-]": curve.damping_ratio_std,
    }
    cols = {k: np.full(curve.amplitude.size, np.nan) if v is None else v for k, v in cols.items()}
    table = np.column_stack(list(cols.values()))
    np.savetxt(path, table, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")


def run_curve(args) -> tuple[bool, list[str]]:
    """Run ``curve``: (the curve is usable, the lines to print); files written first."""
    from .identify.files.vibration import read_vibration_csv
    from .identify.sweeps.sweep import sweep_curve

    units = None if args.units is None else [s.strip() for s in args.units.split(",")]
    if units is not None and (len(units) > 2 or not all(units)):
        raise ValueError(f"--units must be RESP or RESP,TIME (e.g. m/s^2,s), got {args.units!r}")
    rec = read_vibration_csv(
        args.csv,
        columns=None
        if args.columns is None
        else [
            int(c) if c.isdigit() else c
            for c in _pair(args.columns, "--columns", "two columns T,Y (names or 0-based indices)")
        ],
        response_unit=None if units is None else units[0],
        time_unit=None if units is None or len(units) < 2 else units[1],
    )
    if rec["kind"] == "sweep":
        if args.band is not None or args.start:
            raise ValueError("--band and --start are for ring-downs; sweeps are read as they are")
        kw = {k: rec[k] for k in ("f", "F", "response", "phase", "level", "quantity")}
        curve = sweep_curve(**kw)
        n_lev = 1 if rec["level"] is None else np.unique(rec["level"]).size
        head = f"{rec['source']}: stepped-sine sweeps, {rec['f'].size} points, {n_lev} level(s)"
    else:
        curve, head = _ringdown_curve(rec, args)
    wrote = []
    if args.out is not None:
        _write_csv(args.out, curve)
        wrote.append(f"wrote {args.out}")
    if args.plot is not None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6, 7))
        curve.plot([fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2)])
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        wrote.append(f"wrote {args.plot}")
    return bool(curve.success), [head, curve.report()] + wrote
