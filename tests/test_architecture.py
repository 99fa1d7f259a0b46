"""The package's rooms and the imports allowed between them (docs/architecture.md).

Read from the source with ``ast`` (every ``import`` at module level and inside functions),
never by importing the package, so a circle that Python's lazy imports tolerate still
fails here. ``models/`` is the package ``iwan_element.models`` (pyproject's package-dir).
"""

from __future__ import annotations

import ast
import collections
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = (("iwan_element", "iwan_element"), ("models", "iwan_element.models"))

#: The rooms from the bottom up, of the package and of each room with rooms inside it: a room
#: may import itself and the rooms before it only (docs/architecture.md draws the same
#: order). ``(modules)`` is a room's own modules beside its sub-rooms; ``__init__`` its face.
LAYERS = {
    "iwan_element": [
        "base",
        "core",
        "fitting",
        "plotting",
        "effects",
        "harmonic",
        "identify",
        "exudyn",
        "ensemble",
        "diagnose",
        "__init__",
        "cli_curve",
        "cli",
        "models",
    ],
    "iwan_element.models": [
        "specimens",
        "linear",
        "beam",
        "solid",
        "reduced",
        "updating",
        "modal",
        "simulation",
        "calibration",
        "(modules)",
        "__init__",
    ],
    "iwan_element.identify": ["loops", "files", "modal", "decays", "sweeps", "__init__"],
    "iwan_element.diagnose": [
        "(modules)",
        "selection",
        "loops",
        "vibration",
        "campaign",
        "__init__",
    ],
    "iwan_element.exudyn": ["slips", "laws", "(modules)", "__init__"],
}
MAX_MODULES, MAX_LINES, MAX_FUNCTION = 12, 500, 80


def _modules() -> dict[str, Path]:
    out = {}
    for folder, pkg in SOURCES:
        for p in sorted((ROOT / folder).rglob("*.py")):
            parts = list(p.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join([pkg, *parts])] = p
    return out


MODULES = _modules()
TREES = {name: ast.parse(path.read_text(encoding="utf-8")) for name, path in MODULES.items()}


def _runtime_nodes(tree: ast.AST):
    """Every node of ``tree`` except those under ``if TYPE_CHECKING:`` (imports a type
    checker reads and Python never runs: an annotation may name a module above or beside
    without an import at run time)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and (
                (isinstance(child.test, ast.Name) and child.test.id == "TYPE_CHECKING")
                or (isinstance(child.test, ast.Attribute) and child.test.attr == "TYPE_CHECKING")
            ):
                stack.extend(child.orelse)
                continue
            stack.append(child)


def _imports(name: str):
    """``(target module, imported name or None, line)`` of every import of module ``name``
    inside the package that runs (module level or in a function; not the type checker's),
    relative imports resolved."""
    package = name if MODULES[name].name == "__init__.py" else name.rpartition(".")[0]
    for node in _runtime_nodes(TREES[name]):
        if isinstance(node, ast.Import):
            items = [(a.name, None) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            items = [(mod, a.name) for a in node.names]
        else:
            continue
        for mod, nm in items:
            if mod == "iwan_element" or mod.startswith("iwan_element."):
                yield mod, nm, node.lineno


def _resolve(mod: str, nm: str | None) -> str:
    """The module an import reaches: ``from pkg import sub`` reaches the submodule."""
    if nm and f"{mod}.{nm}" in MODULES:
        return f"{mod}.{nm}"
    while mod not in MODULES and "." in mod:
        mod = mod.rpartition(".")[0]
    return mod


def _graph() -> dict[str, set[str]]:
    g = collections.defaultdict(set)
    for name in MODULES:
        for mod, nm, _ in _imports(name):
            tgt = _resolve(mod, nm)
            if tgt != name:
                g[name].add(tgt)
    return g


def _package(module: str) -> str:
    return module if MODULES[module].name == "__init__.py" else module.rpartition(".")[0]


def _sub_room(module: str, parent: str) -> str | None:
    """The room of ``module`` inside ``parent`` (None when it is not inside): a sub-package's
    name, ``(modules)`` for a module of ``parent`` itself, ``__init__`` for its face."""
    if module == parent:
        return "__init__"
    if not module.startswith(parent + "."):
        return None
    head = module[len(parent) + 1 :].split(".")[0]
    path = MODULES.get(f"{parent}.{head}")
    if path is not None and path.name == "__init__.py":
        return head
    return head if parent == "iwan_element" else "(modules)"


def test_every_room_imports_only_the_rooms_below_it():
    bad = []
    graph = _graph()
    for parent, layers in LAYERS.items():
        order = {r: i for i, r in enumerate(layers)}
        for a, targets in graph.items():
            for b in targets:
                ra, rb = _sub_room(a, parent), _sub_room(b, parent)
                if ra is None or rb is None or ra == rb:
                    continue
                assert ra in order and rb in order, f"{parent}: room {ra}/{rb} not in LAYERS"
                if order[rb] > order[ra]:
                    bad.append(f"{a} -> {b}")
    assert not bad, "imports of a room above:\n" + "\n".join(sorted(bad))


def _circles(g: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, stack, on, comps = {}, {}, [], set(), []
    for v0 in sorted(set(g) | {w for ws in g.values() for w in ws}):
        if v0 in index:
            continue
        index[v0] = low[v0] = len(index)
        stack.append(v0)
        on.add(v0)
        work = [(v0, iter(sorted(g.get(v0, ()))))]
        while work:
            u, it = work[-1]
            for w in it:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(g.get(w, ())))))
                    break
                if w in on:
                    low[u] = min(low[u], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[u])
                if low[u] == index[u]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == u:
                            break
                    if len(comp) > 1:
                        comps.append(sorted(comp))
    return comps


def test_no_import_circle_among_modules():
    """Every strongly connected component of the module graph (function-level imports
    included) is one module."""
    comps = _circles(_graph())
    assert not comps, "import circles:\n" + "\n".join(" <-> ".join(c) for c in comps)


def test_no_private_name_crosses_a_package():
    """A ``_private`` module or name is used only inside the package (folder) that owns
    it; what another package needs is public in its owner."""
    bad = []
    for a in MODULES:
        for mod, nm, line in _imports(a):
            tgt = _resolve(mod, nm)
            owner = _package(tgt)
            private_module = any(
                p.startswith("_") and not p.startswith("__") for p in tgt.split(".")
            )
            private_name = (
                nm is not None
                and nm.startswith("_")
                and not nm.startswith("__")
                and f"{mod}.{nm}" not in MODULES
            )
            if (
                (private_module or private_name)
                and _package(a) != owner
                and not (private_module and not private_name and _package(a) == owner)
            ):
                bad.append(f"{MODULES[a].relative_to(ROOT)}:{line} {mod} import {nm}")
    assert not bad, "private names across packages:\n" + "\n".join(bad)


def test_rooms_and_modules_stay_small():
    folders = collections.Counter(p.parent for p in MODULES.values())
    big = [f"{f.relative_to(ROOT)}: {n} modules" for f, n in folders.items() if n > MAX_MODULES]
    long_modules = [
        f"{p.relative_to(ROOT)}: {n} lines"
        for p in MODULES.values()
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    ]
    long_functions = []
    for name, tree in TREES.items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                body = node.body
                doc = (
                    body[0]
                    if (
                        isinstance(body[0], ast.Expr)
                        and isinstance(body[0].value, ast.Constant)
                        and isinstance(body[0].value.value, str)
                    )
                    else None
                )
                n = node.end_lineno - node.lineno + 1
                if doc is not None:  # the numpydoc docstring is documentation, not code
                    n -= doc.end_lineno - doc.lineno + 1
                if n > MAX_FUNCTION:
                    long_functions.append(
                        f"{MODULES[name].relative_to(ROOT)}:{node.lineno} {node.name}: {n} lines"
                    )
    assert not (big or long_modules or long_functions), "\n".join(
        big + long_modules + long_functions
    )


def test_the_checks_find_what_they_claim():
    """The circle finder on hand-made graphs, the resolver on known imports (the checks
    above are only as good as these)."""
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _circles({"a": {"b"}, "b": {"c"}, "d": {"a", "c"}}) == []
    assert _circles({"a": {"b"}, "b": {"a"}, "c": {"d"}, "d": {"c"}}) == [["a", "b"], ["c", "d"]]
    assert _resolve("iwan_element.models", "preset") == "iwan_element.models"
    assert _resolve("iwan_element.models.no_such_module", None) == "iwan_element.models"
    assert _package("iwan_element.models") == "iwan_element.models"
    assert _sub_room("iwan_element.models.modal.qsma", "iwan_element.models") == "modal"
    assert _sub_room("iwan_element.models", "iwan_element.models") == "__init__"
    assert _sub_room("iwan_element.models.studies", "iwan_element.models") == "(modules)"
    assert _sub_room("iwan_element.cli", "iwan_element") == "cli"
    assert _sub_room("iwan_element.cli", "iwan_element.models") is None
    tree = ast.parse("import a\nif TYPE_CHECKING:\n    import b\nelse:\n    import c\n")
    names = {a.name for n in _runtime_nodes(tree) if isinstance(n, ast.Import) for a in n.names}
    assert names == {"a", "c"}
