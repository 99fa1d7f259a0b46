"""The checks every change passes: lint, format, types and the documentation build.

Each tool runs on the checkout as a subprocess, configured in pyproject.toml (ruff, mypy) and
mkdocs.yml (the site), with the versions the ``test`` extra installs. A tool that is not
installed skips its test with the reason; CI installs them all.

Issue 44: the code predates the configuration. The lint findings, the formatting and the type
errors are fixed in one pass once the package's rooms are settled; until then those three
tests are expected to fail (strict: the marker goes when they pass). The documentation build
passes today and is checked as it stands.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: generous per-tool limits; measured on 2 shared cores (CPU s): ruff 0.1 each, mypy 10-15
#: with a cold cache, mkdocs 12-14
TIMEOUT = {"ruff": 60, "mypy": 300, "mkdocs": 300}


def _run(module: str, *args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    if importlib.util.find_spec(module) is None:
        pytest.skip(
            f'{module} is not installed (it is in the test extra: python -m pip install ".[test]")'
        )
    env = dict(os.environ, NO_COLOR="1", NO_MKDOCS_2_WARNING="1", DISABLE_MKDOCS_2_WARNING="true")
    return subprocess.run(
        [sys.executable, "-m", module, *args],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        timeout=TIMEOUT[module],
    )


def _by_code(lines: str, pattern: str) -> str:
    """The findings counted by code, largest first (for the failure message)."""
    counts = Counter(re.findall(pattern, lines, re.MULTILINE))
    return ", ".join(f"{code} {n}" for code, n in counts.most_common())


def test_ruff_check_finds_nothing():
    res = _run("ruff", "check", "--output-format", "concise", "--no-cache", ".")
    counts = _by_code(res.stdout, r": ([A-Z]+[0-9]+) ")
    assert res.returncode == 0, f"ruff check: {counts}\n{res.stdout[-3000:]}"


def test_ruff_format_changes_nothing():
    res = _run("ruff", "format", "--check", "--no-cache", ".")
    assert res.returncode == 0, f"ruff format would change:\n{res.stdout[-3000:]}"


def test_mypy_finds_no_type_error(tmp_path):
    res = _run("mypy", "--cache-dir", str(tmp_path / "mypy_cache"))
    counts = _by_code(res.stdout, r"  \[([a-z-]+)\]$")
    assert res.returncode == 0, f"mypy: {counts}\n{res.stdout[-3000:]}"


def test_documentation_site_builds_without_warnings(tmp_path):
    """mkdocs with warnings as errors: broken links, unknown anchors, docstrings the numpy
    parser cannot read; the API reference is generated from the folders (docs/gen_api.py)."""
    for tool in (
        "mkdocs_gen_files",
        "mkdocs_literate_nav",
        "mkdocstrings_handlers.python",
        "material",
    ):
        if importlib.util.find_spec(tool.split(".")[0]) is None:
            pytest.skip(f"{tool} is not installed (the docs and test extras install it)")
    res = _run("mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site"))
    assert res.returncode == 0, res.stderr[-5000:]
    reference = tmp_path / "site" / "reference" / "iwan_element"
    assert (reference / "index.html").is_file()
    assert (reference / "models" / "index.html").is_file(), "iwan_element.models documented"
