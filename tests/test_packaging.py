"""The installed package: ``models/`` (beside the package in the source tree) is importable as
``iwan_element.models`` from anywhere, with its data files (the design card's layout)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

_CHECK = """
import importlib.metadata, pathlib, sys
try:
    importlib.metadata.distribution("iwan-element")
except importlib.metadata.PackageNotFoundError:
    sys.exit(3)
import iwan_element.models as m
d = pathlib.Path(m.__file__).parent
assert (d / "example_test_30kN.csv").is_file(), d
assert callable(m.preset)
"""


def test_installed_package_imports_models_with_its_data(tmp_path):
    # outside the checkout and without PYTHONPATH: only an installed package can be found
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    res = subprocess.run(
        [sys.executable, "-c", _CHECK],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    if res.returncode == 3:
        pytest.skip(
            "iwan-element is not installed in this environment (run "
            '`python -m pip install -e ".[test]"`, as the README says)'
        )
    assert res.returncode == 0, res.stderr


def _source_packages(root: Path) -> set[str]:
    """Every folder holding an ``__init__.py`` under ``iwan_element/`` and ``models/``, named as
    installed (``models/`` is ``iwan_element.models``)."""
    found = set()
    for top, name in (("iwan_element", "iwan_element"), ("models", "iwan_element.models")):
        for init in (root / top).rglob("__init__.py"):
            rel = init.parent.relative_to(root / top)
            if any(p.is_symlink() for p in (root / top / rel).parents) or init.parent.is_symlink():
                continue
            if top == "iwan_element" and rel.parts[:1] == ("models",):
                continue  # a development link to models/, not a package
            found.add(".".join((name, *rel.parts)))
    return found


def test_a_built_package_holds_every_subpackage_and_data_file(tmp_path):
    """What a non-editable install copies (setuptools' ``build_py``, the step a wheel is built
    with): every subpackage of the source tree and the data files of ``models/``, whatever the
    rooms are. A subpackage missing here imports only from the checkout, never after
    ``pip install .``."""
    pytest.importorskip("setuptools", reason="setuptools (in the test extra) builds the package")
    root = Path(__file__).resolve().parents[1]
    lib = tmp_path / "lib"
    # the file list made afresh in tmp_path: an old *.egg-info of the checkout would add the
    # files it once listed as data files
    res = subprocess.run(
        [
            sys.executable,
            "setup.py",
            "-q",
            "egg_info",
            "--egg-base",
            str(tmp_path),
            "build_py",
            "--build-lib",
            str(lib),
        ],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    built = {".".join(p.parent.relative_to(lib).parts) for p in lib.rglob("__init__.py")}
    assert built == _source_packages(root)
    data = {
        p.relative_to(root / "models")
        for ext in ("csv", "json", "md")
        for p in (root / "models").rglob(f"*.{ext}")
    }
    assert data, "models/ holds the example records"
    missing = sorted(str(d) for d in data if not (lib / "iwan_element" / "models" / d).is_file())
    assert not missing, f"data files of models/ left out of the package: {missing}"


def test_version_is_the_installed_metadata():
    """``iwan_element.__version__`` is read from the installed metadata, which pyproject.toml
    writes: one version, stated once."""
    import re

    import iwan_element

    text = (Path(__file__).resolve().parents[1] / "pyproject.toml").read_text(encoding="utf-8")
    project = text.split("[project]", 1)[1].split("\n[", 1)[0]
    assert re.search(r'^version = "([^"]+)"$', project, re.MULTILINE).group(1) == (
        iwan_element.__version__
    )
