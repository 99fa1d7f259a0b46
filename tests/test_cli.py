"""Command line: ``iwan-element fit data.csv --units mm,kN ...``."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _helpers import write_record_csv

from iwan_element import IwanParameters
from iwan_element.cli import main
from iwan_element.identify.loops.testdata import simulate_test

P = IwanParameters(9e3, 5e7, -0.5, 0.5)


@pytest.fixture(scope="module")
def csv_path(tmp_path_factory):
    d = simulate_test(
        P,
        np.array([0.025, 0.05, 0.1, 0.2, 0.3, 0.45]) * 1e-3,
        cycles=3,
        sample_rate=5,
        force_noise=15.0,
        seed=0,
    )
    return write_record_csv(
        tmp_path_factory.mktemp("cli") / "test.csv",
        d.t,
        d.u,
        d.F,
        digits=(2, 7, 6),
        comment="# SYNTHETIC",
    )


def _one_line_error(err: str, match: str) -> None:
    assert err.startswith("iwan-element: error:") and err.strip().count("\n") == 0, err
    assert match in err, err


def test_fit_loops_prints_report_and_writes_json_and_plot(csv_path, tmp_path, capsys):
    js, png = tmp_path / "r.json", tmp_path / "r.png"
    code = main(["fit", str(csv_path), "--units", "mm,kN", "--json", str(js), "--plot", str(png)])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "loop fit" in out.out and "KT   [N/m]" in out.out and "units mm, kN, s" in out.out
    assert out.err == ""  # warnings go into the report, not stderr
    d = json.loads(js.read_text())
    q = IwanParameters.from_dict(d["joint"])
    assert q.KT == pytest.approx(P.KT, rel=0.01) and q.Fs == pytest.approx(P.Fs, rel=0.01)
    assert d["data"]["units"] == {"time": "s", "displacement": "mm", "force": "kN"}
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("method, extra", [("dissipation", []), ("seed", ["--slip-force", "9"])])
def test_fit_dissipation_methods(csv_path, capsys, method, extra):
    code = main(["fit", str(csv_path), "--units", "mm,kN", "--method", method] + extra)
    out = capsys.readouterr().out
    assert code == 0
    assert ("seed-paper procedure" in out) == (method == "seed")
    if method == "seed":
        assert "given (not fitted)" in out and "9000" in out  # --slip-force in kN -> N


@pytest.mark.parametrize(
    "argv, code, match",
    [
        (["fit", "{csv}", "--units", "mm"], 1, "--units must be"),
        (["fit", "{csv}", "--units", "mm,tonne"], 1, "not a known unit"),
        (["fit", "{csv}", "--units", "m,kN"], 1, "labelled in 'mm'"),
        (["fit", "{csv}", "--units", "mm,kN", "--method", "seed"], 1, "needs --slip-force"),
        (
            ["fit", "{csv}", "--units", "mm,kN", "--slip-force", "9"],
            1,
            "only used by --method seed",
        ),
        (["fit", "{csv}", "--units", "mm,kN", "--method", "fminsearch"], 2, "invalid choice"),
        (["fit", "{csv}", "--units", "mm,kN", "--smooth", "4"], 1, "smooth must be"),
        (["fit", "missing.csv", "--units", "mm,kN"], 1, "cannot read"),
        ([], 2, "required: <command>"),
    ],
)
def test_bad_input_exits_nonzero_with_one_line(csv_path, capsys, argv, code, match):
    argv = [a.replace("{csv}", str(csv_path)) for a in argv]
    assert main(argv) == code
    _one_line_error(capsys.readouterr().err, match)


def test_units_come_from_the_header_or_are_refused(csv_path, tmp_path, capsys):
    """Issue 34 case 8: without --units the header's labels are the units; a header without
    them (or no header) is refused naming the columns, never read as mm and kN."""
    assert main(["fit", str(csv_path), "--method", "dissipation"]) == 0
    assert "units mm, kN, s" in capsys.readouterr().out
    bare = tmp_path / "bare.csv"
    bare.write_text(
        "time,displacement,force\n"
        + "\n".join(line.replace(" ", "") for line in csv_path.read_text().splitlines()[2:])
        + "\n"
    )
    assert main(["fit", str(bare)]) == 1
    _one_line_error(capsys.readouterr().err, "is not stated: the header names the columns")


def test_bad_data_files(tmp_path, capsys):
    nan = tmp_path / "nan.csv"
    nan.write_text("time,displacement,force\n0,0,0\n1,nan,1\n2,0.1,2\n")
    assert main(["fit", str(nan), "--units", "mm,kN"]) == 1
    _one_line_error(capsys.readouterr().err, "displacement column contains NaN")
    zero = tmp_path / "zero.csv"
    t = np.arange(2000) * 0.5
    zero.write_text("\n".join(f"{a},{0.1 * np.sin(0.02 * a)},0" for a in t))
    assert main(["fit", str(zero), "--units", "mm,kN"]) == 1
    _one_line_error(capsys.readouterr().err, "force column")


def test_console_entry_point_runs_as_module(csv_path):
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    res = subprocess.run(
        [
            sys.executable,
            "-m",
            "iwan_element.cli",
            "fit",
            str(csv_path),
            "--units",
            "mm,kN",
            "--method",
            "dissipation",
        ],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    assert "least squares" in res.stdout
