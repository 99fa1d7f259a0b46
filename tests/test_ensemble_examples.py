"""The ensemble examples run as scripts in their quick settings and write what they promise."""
import csv
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run_example(name, *args, timeout=300):
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / name), *args],
                          capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert proc.returncode == 0, proc.stderr
    return proc


def test_uncertainty_bands_quick(tmp_path):
    out = tmp_path / "bands.png"
    proc = run_example("uncertainty_bands.py", "--quick", "--out", str(out))
    assert out.stat().st_size > 20_000
    assert "Prediction bands (90 % central)" in proc.stdout and "peak displacement" in proc.stdout
    with open(out.with_suffix(".csv"), newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 16 and all(r["ok"] == "True" for r in rows)
    # the sampled slip forces scatter around the fitted 9 kN of the synthetic record
    Fs = [float(r["Fs"]) for r in rows]
    assert len(set(Fs)) == 16 and all(abs(f / 9000.0 - 1) < 0.01 for f in Fs)


def test_preload_sweep_quick(tmp_path):
    out = tmp_path / "sweep.png"
    proc = run_example("preload_sweep.py", "--quick", "--out", str(out))
    assert out.stat().st_size > 20_000
    assert "3 succeeded, 0 failed" in proc.stdout
    with open(out.with_suffix(".csv"), newline="") as fh:
        rows = list(csv.DictReader(fh))
    # a lower preload slips more: larger frequency drop and more damping at the top amplitude
    drop = [float(r["frequency_drop"]) for r in rows]
    zmax = [float(r["damping_max"]) for r in rows]
    assert [float(r["preload"]) for r in rows] == [5e3, 15e3, 30e3]
    assert drop[0] > drop[1] > drop[2] > 0 and zmax[0] > zmax[1] > zmax[2]
