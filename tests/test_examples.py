"""Every example runs as a script (small settings) and writes what it promises."""
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


def test_seed_figure3(tmp_path):
    out = tmp_path / "fig3.png"
    proc = run_example("seed_figure3.py", "--out", str(out))
    assert out.stat().st_size > 10_000
    assert "wrote" in proc.stdout
