"""The README is a guide whose recipes run as they stand.

Every python block that follows a line ``<!-- recipe: NAME -->`` is executed (from the
repository root, in a fresh namespace, figures on the Agg backend); adding a recipe is
writing a marked block. The guide stays short (under about 4,000 words), its table of
contents points at its headings, and it keeps the CI quick-start block of two commands.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")

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


@pytest.mark.parametrize("name", sorted(RECIPES))
def test_recipe_runs_as_it_stands(name, monkeypatch):
    import matplotlib.pyplot as plt

    if "../shared" in RECIPES[name] and not (ROOT.parent / "shared").is_dir():
        pytest.skip("the recipe reads GPL data from ../shared beside the checkout, absent here")
    monkeypatch.chdir(ROOT)
    t0 = time.process_time()  # CPU time: the machine may be shared
    try:
        exec(compile(RECIPES[name], f"README recipe {name}", "exec"), {"__name__": "__main__"})
    finally:
        plt.close("all")
    assert time.process_time() - t0 < 30, "a recipe must stay quick (small data, few points)"
