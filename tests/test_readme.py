"""The README is a guide whose recipes run as they stand.

Every python block that follows a line ``<!-- recipe: NAME -->`` is executed as a tester runs
it: in a Python started at the repository root (as a notebook there is), against a
non-editable install of the package (the files ``pip install .`` copies, built once per test
session), figures on the Agg backend; adding a recipe is writing a marked block. Every verdict a
recipe prints is "usable" or a "NOT usable" that the recipe's section of the guide explains. The
guide stays short (under about 4,000 words), its table of contents points at its headings, and
it keeps the CI quick-start block of two commands.
"""

from __future__ import annotations

import os
import re
import site
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
MARKER = re.compile(
    r"^<!-- recipe: ([a-z0-9_-]+) -->\n```python\n(.*?)^```$", re.MULTILINE | re.DOTALL
)
RECIPES = dict(MARKER.findall(README))
#: The recipes the guide promises (issue 35); others may be added.
PROMISED = set("abcdefgh")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_every_marker_holds_a_python_block_and_the_promised_recipes_are_there():
    markers = re.findall(r"^<!-- recipe: ([a-z0-9_-]+) -->$", README, re.MULTILINE)
    assert len(markers) == len(set(markers)) == len(RECIPES), (
        "every recipe marker must be followed directly by one ```python block"
    )
    assert PROMISED <= set(RECIPES)


def test_the_guide_is_short_with_a_table_of_contents_that_resolves():
    assert len(README.split()) < 4000
    headings = {_anchor(h) for h in re.findall(r"^#{2,3} (.+)$", README, re.MULTILINE)}
    toc = README[README.index("## Contents") : README.index("## Two ways in")]
    links = re.findall(r"\]\(#([^)]+)\)", toc)
    assert len(links) >= 10 and set(links) <= headings


def test_quick_start_keeps_its_two_ci_commands():
    block = README.split("<!-- ci: quickstart", 1)[1].split("```bash\n", 1)[1].split("```")[0]
    assert [c for c in block.splitlines() if c.strip()] == [
        "python -m pip install . && python examples/jointed_beam.py",
        'python -m pip install ".[test]" && pytest -q -n 2',
    ]


def test_linked_documentation_pages_exist():
    for target in re.findall(r"\]\(((?:docs/)[^)#]+)\)", README):
        assert (ROOT / target).is_file(), target


#: Runs a recipe read from stdin, as a notebook cell runs at the checkout's root: ``-S`` keeps
#: site-packages' ``.pth`` files (an editable install's finder) out, so the package is found
#: only from the checkout's root (first on sys.path, as in a notebook) and the built copy.
_RUNNER = """
import sys, time
import matplotlib
matplotlib.use("Agg")
code = sys.stdin.read()
t0 = time.process_time()
exec(compile(code, "README recipe", "exec"), {"__name__": "__main__"})
print(f"[recipe CPU {time.process_time() - t0:.3f} s]")
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """A non-editable install of the checkout: the package and its metadata as ``pip install
    .`` copies them (setuptools' ``egg_info`` and ``build_py``, the steps a wheel is built
    with), in a folder of its own."""
    pytest.importorskip("setuptools", reason="setuptools (in the test extra) builds the package")
    lib = tmp_path_factory.mktemp("installed")
    cmd = [sys.executable, "setup.py", "-q", "egg_info", "--egg-base", str(lib)]
    res = subprocess.run(
        [*cmd, "build_py", "--build-lib", str(lib)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 0, res.stderr
    assert (lib / "iwan_element" / "models" / "__init__.py").is_file()
    return lib


def _section(name: str) -> str:
    """The README's text of recipe ``name``: from its heading to the next heading."""
    start = README.index(f"### ({name})")
    end = min(i for i in (README.find("\n## ", start), README.find("\n### ", start + 4)) if i > 0)
    return " ".join(README[start:end].split())


def _unexplained(output: str, section: str) -> list[str]:
    """The "NOT usable" verdicts printed whose reason the section does not quote: each reason
    (the text after "NOT usable: " up to its first ";") must appear in the section, in its own
    words, beside the explanation."""
    reasons = re.findall(r"NOT usable: ([^;\n]+)", output)
    return [r for r in reasons if " ".join(r.split()).rstrip(".") not in section]


def _run(code: str, lib: Path, env_extra: dict[str, str]) -> subprocess.CompletedProcess:
    paths = [str(lib), *site.getsitepackages(), site.getusersitepackages()]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env.update(PYTHONPATH=os.pathsep.join(paths), MPLBACKEND="Agg", **env_extra)
    return subprocess.run(
        [sys.executable, "-S", "-c", _RUNNER],
        input=code,
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_models_import_at_the_root_after_a_non_editable_install(installed):
    """The bug a notebook at the checkout's root met: the source tree hides the installed
    package, whose ``models`` is mapped from the top-level folder ``models/``."""
    res = _run("from iwan_element.models import preset\nprint(preset)", installed, {})
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("name", sorted(RECIPES))
def test_recipe_runs_as_it_stands(name, installed):
    if "../shared" in RECIPES[name] and not (ROOT.parent / "shared").is_dir():
        pytest.skip("the recipe reads GPL data from ../shared beside the checkout, absent here")
    res = _run(RECIPES[name], installed, {"CI": "1"})
    assert res.returncode == 0, f"recipe {name} failed:\n{res.stderr[-4000:]}"
    cpu = float(re.findall(r"\[recipe CPU ([0-9.]+) s\]", res.stdout)[-1])
    assert cpu < 30, "a recipe must stay quick (small data, few points)"
    missing = _unexplained(res.stdout, _section(name))
    assert not missing, f"recipe {name} prints NOT usable verdicts the README does not explain"
