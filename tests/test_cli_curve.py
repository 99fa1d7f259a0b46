"""``iwan-element curve``: a ring-down or sweep file on the command line gives the curve the
Python route gives (the file read independently with numpy, then ``amplitude_curve`` or
``sweep_curve``); a file of the wrong kind names the right command; exit status 3 when the
curve is not usable.

The Brake-Reuss records are GPL data read from ``../shared`` beside the checkout (never copied
into the project); those tests skip with the reason when it is absent.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import iwan_element as ie
from iwan_element.cli import main

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
HAMMER = SHARED / "brb-hammer" / "hammer_acc3.csv"
SWEEPS = SHARED / "brb-steppedsine-fc" / "fc_sweeps.csv"
needs_shared = pytest.mark.skipif(
    not (HAMMER.is_file() and SWEEPS.is_file()),
    reason="the Brake-Reuss records (GPL-3.0) are read from ../shared beside the checkout, "
    "absent here",
)


def _table(path: Path) -> np.ndarray:
    """The curve the command wrote: amplitude, frequency, its std, damping, its std."""
    head = path.read_text().splitlines()[0].split(",")
    assert head == [
        "amplitude [m]",
        "frequency [Hz]",
        "frequency std [Hz]",
        "damping ratio [-]",
        "damping ratio std [-]",
    ]
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def _same_curve(table: np.ndarray, curve) -> None:
    """The command's CSV (10 significant digits) is the Python route's curve."""
    assert table.shape[0] == curve.amplitude.size
    for j, v in enumerate(
        (curve.amplitude, curve.frequency, curve.frequency_std, curve.damping_ratio)
    ):
        np.testing.assert_allclose(table[:, j], v, rtol=1e-9)


@needs_shared
def test_hammer_record_gives_the_python_route_curve(tmp_path, capsys):
    out = tmp_path / "curve.csv"
    status = main(["curve", str(HAMMER), "--band", "60,120", "--out", str(out)])
    printed = capsys.readouterr().out
    assert status == 0 and "usable" in printed.splitlines()[1]
    # the Python route, the file read with numpy (its README: t [s], a [m/s^2], SI)
    data = np.loadtxt(HAMMER, delimiter=",", skiprows=1)
    t, a = data[:, 0], data[:, 1]
    keep = t >= t[np.argmax(np.abs(a))]  # from the impact on
    curve = ie.amplitude_curve(t[keep], a[keep], quantity="acceleration", band=(60.0, 120.0))
    _same_curve(_table(out), curve)


@needs_shared
def test_hammer_band_from_the_spectrum_matches_the_data_readme(tmp_path, capsys):
    """No band given: the command finds mode 1 (80.4 Hz) in the spectrum, and its curve
    matches the reference table of the data's README (an analysis independent of this
    package: 0.25 s Hilbert windows, 60-120 Hz) within 0.01 Hz and 0.01 % of damping."""
    out = tmp_path / "curve.csv"
    assert main(["curve", str(HAMMER), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "from the spectrum's peak at 80." in printed
    tab = _table(out)
    order = np.argsort(tab[:, 0])
    ref = {40e-6: (80.444, 0.198e-2), 20e-6: (80.470, 0.175e-2), 10e-6: (80.512, 0.158e-2)}
    for X, (f_ref, z_ref) in ref.items():
        f = np.interp(np.log(X), np.log(tab[order, 0]), tab[order, 1])
        z = np.interp(np.log(X), np.log(tab[order, 0]), tab[order, 3])
        assert abs(f - f_ref) < 0.01 and abs(z - z_ref) < 0.01e-2, (X, f, z)


@needs_shared
def test_sweep_file_gives_the_python_route_curve(tmp_path, capsys):
    out, png = tmp_path / "curve.csv", tmp_path / "curve.png"
    status = main(["curve", str(SWEEPS), "--out", str(out), "--plot", str(png)])
    assert status == 0 and png.stat().st_size > 0
    assert "4 level(s)" in capsys.readouterr().out
    # its README: level, f [Hz], F [N], A [m/s^2] (fundamental amplitudes), phase [rad]
    lev, f, F, A, ph = np.loadtxt(SWEEPS, delimiter=",", skiprows=1, unpack=True)
    curve = ie.sweep_curve(f, F, A, ph, level=lev, quantity="acceleration")
    _same_curve(_table(out), curve)


@needs_shared
def test_a_ring_down_given_to_the_loop_commands_names_curve(capsys):
    for cmd in ("fit", "diagnose"):
        assert main([cmd, str(HAMMER)]) == 1
        err = capsys.readouterr().err
        assert "ring-down" in err and f"iwan-element curve {HAMMER}" in err


def test_a_loop_record_given_to_curve_names_fit(capsys):
    from iwan_element.models import example_test_path

    assert main(["curve", str(example_test_path())]) == 1
    err = capsys.readouterr().err
    assert "loop record" in err and "iwan-element fit" in err


def test_unknown_columns_are_spoken_of_as_the_flag(tmp_path, capsys):
    p = tmp_path / "odd.csv"
    p.write_text("t [s],x [mm],y [kN]\n" + "".join(f"{k},{k % 3},{k % 5}\n" for k in range(50)))
    assert main(["fit", str(p)]) == 1
    err = capsys.readouterr().err
    assert "--columns T,U,F" in err and "columns=(" not in err


def _linear_sweep(path: Path, *, n: int) -> None:
    """One coarse force-controlled sweep of a lightly damped linear mode (80 Hz, 0.02 %, 1 kg)
    at 0.5 N: one point near the resonance."""
    f = np.linspace(78.0, 82.0, n)
    W, W0 = 2 * np.pi * f, 2 * np.pi * 80.0
    X = 0.5 / (W0**2 - W**2 + 2j * 2e-4 * W0 * W)
    rows = [f, np.full(n, 0.5), np.abs(W**2 * X), np.angle(X)]
    np.savetxt(path, np.column_stack(rows), delimiter=",", comments="",
               header="f [Hz],F [N],A [m/s^2],phase [rad]")  # fmt: skip


def test_exit_status_3_when_the_curve_is_not_usable(tmp_path, capsys):
    """A single level of a linear mode spans too little amplitude for a curve of three
    points: the report says so, the status is 3, as the Python route's verdict."""
    p = tmp_path / "one_level.csv"
    _linear_sweep(p, n=10)
    status = main(["curve", str(p)])
    printed = capsys.readouterr().out
    f, F, A, ph = np.loadtxt(p, delimiter=",", skiprows=1, unpack=True)
    curve = ie.sweep_curve(f, F, A, ph, quantity="acceleration")
    assert not curve.success
    assert status == 3 and printed.splitlines()[1].startswith("NOT usable")


def test_a_ring_down_without_a_header_takes_columns_and_units_from_the_flags(tmp_path, capsys):
    """A synthetic ring-down (the exact modal Iwan oscillator, 0.2 % noise) in a file with a
    comment and no header: --columns and --units say what it holds; the curve is the Python
    route's on the same arrays."""
    p = ie.IwanParameters(Fs=3.0, KT=2.5e4, chi=-0.5, beta=0.3)
    t = np.arange(0, 2.0, 1 / 2000)
    rd = ie.modal_ringdown(t, p, K_inf=(2 * np.pi * 80.0) ** 2 - p.KT, zeta0=1e-3, q0=2e-4)
    acc = rd.acceleration * (1 + 0.002 * np.random.default_rng(0).standard_normal(t.size))
    f = tmp_path / "ring.csv"
    np.savetxt(f, np.column_stack([np.zeros(t.size), t, acc]), delimiter=",", header="rig 4")
    out = tmp_path / "curve.csv"
    args = ["curve", str(f), "--columns", "1,2", "--units", "m/s^2,s", "--band", "60,100"]
    assert main([*args, "--out", str(out)]) == 0
    assert "(given)" in capsys.readouterr().out
    keep = t >= t[np.argmax(np.abs(acc))]
    curve = ie.amplitude_curve(t[keep], acc[keep], quantity="acceleration", band=(60.0, 100.0))
    _same_curve(_table(out), curve)
    assert main(["curve", str(f), "--band", "60,100"]) == 1  # no units: never guessed
    assert "never guessed" in capsys.readouterr().err
