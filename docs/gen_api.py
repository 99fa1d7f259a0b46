"""Build-time pages of the documentation site (run by mkdocs-gen-files, see mkdocs.yml).

* ``guide.md``: the README, its ``docs/`` links pointing at the site's own pages;
* ``reference/``: one page per public module of ``iwan_element/`` and ``models/`` (which
  installs as ``iwan_element.models``), found by walking the folders: a module that moves to
  another room moves in the reference too. A private module (``_name``) is documented through
  the names its package exports in ``__all__``;
* ``SUMMARY.md``: the navigation (literate-nav): the guide, the topic pages in the order
  ``docs/README.md`` lists them (pages it does not list follow), the changelog, the reference.
"""

from __future__ import annotations

import re
from pathlib import Path

import mkdocs_gen_files

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: source folder -> the name it is imported by
ROOMS = {"iwan_element": "iwan_element", "models": "iwan_element.models"}
#: pages of docs/ that are not topics
NOT_TOPICS = {"README.md", "index.md"}


def _write(path: str, text: str, source: Path) -> None:
    with mkdocs_gen_files.open(path, "w") as f:
        f.write(text)
    mkdocs_gen_files.set_edit_path(path, source.relative_to(ROOT))


def _guide() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    _write("guide.md", re.sub(r"\]\(docs/", "](", text), ROOT / "README.md")
    _write(
        "changelog.md", (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), ROOT / "CHANGELOG.md"
    )


def _public_modules(folder: str) -> list[tuple[tuple[str, ...], Path]]:
    """(dotted parts below the folder, source file) of every public module, depth first: a
    package, then its modules and subpackages (the navigation nests them).
    """
    found = []
    for path in sorted((ROOT / folder).rglob("*.py")):
        rel = path.relative_to(ROOT / folder).with_suffix("")
        parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
        if rel.name == "__main__" or any(p.startswith("_") for p in parts):
            continue
        if not all(
            (ROOT / folder / Path(*rel.parts[:i]) / "__init__.py").is_file()
            for i in range(len(rel.parts))
        ):
            continue  # a script folder, not a package
        found.append((parts, path))
    return sorted(found, key=lambda item: item[0])


def _reference() -> list[str]:
    """Write the reference pages; return the navigation's lines for them."""
    nav = ["* API reference"]
    for folder, name in ROOMS.items():
        for parts, path in _public_modules(folder):
            shown = ".".join((name, *parts))
            ident = ".".join((folder, *parts))  # griffe reads models/ as ``models``
            page = Path("reference", *shown.split(".")).with_suffix(".md")
            if path.name == "__init__.py":
                page = page.with_suffix("") / "index.md"
            options = [f'        heading: "{shown}"', f'        toc_label: "{shown}"']
            text = f"::: {ident}\n    options:\n" + "\n".join(options) + "\n"
            _write(page.as_posix(), text, path)
            depth = len(shown.split(".")) - 1
            label = shown if path.name == "__init__.py" else parts[-1]
            nav.append("    " * depth + f"    * [{label}]({page.as_posix()})")
    return nav


def _topics() -> list[str]:
    index = (DOCS / "README.md").read_text(encoding="utf-8")
    listed = list(dict.fromkeys(re.findall(r"\]\(([\w.-]+\.md)\)", index)))
    pages = listed + sorted(
        p.name for p in DOCS.glob("*.md") if p.name not in listed and p.name not in NOT_TOPICS
    )
    lines = ["* Topics"]
    for page in pages:
        title = next(
            (
                line[2:].strip()
                for line in (DOCS / page).read_text(encoding="utf-8").splitlines()
                if line.startswith("# ")
            ),
            page,
        )
        lines.append(f"    * [{title}]({page})")
    return lines


_guide()
summary = [
    "* [Home](README.md)",
    "* [Guide](guide.md)",
    *_topics(),
    "* [Changelog](changelog.md)",
    *_reference(),
]
with mkdocs_gen_files.open("SUMMARY.md", "w") as f:
    f.write("\n".join(summary) + "\n")
