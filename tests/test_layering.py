"""The package layers, checked from the source with ast (nothing is imported or run).

Layers: models/ imports none of the other packages; data/ and inference/ import only
models/; workflows/ (the CLI) sits on top. There is no import cycle among the modules,
no ``_private`` name is imported from another project module (shared helpers get public
names), and nothing below workflows/ plots. Every import statement counts, at module
level or inside a function: an import deferred into a function to dodge a cycle is still
a cycle of the design. Below workflows/ no module imports by name at run time
(importlib.import_module, __import__), which would hide an edge from these checks; the
one exception is the package models/__init__.py loading its own submodules on first use.

The KNOWN_* allow-lists are empty: any violation fails at once. (They held the
violations left in files under rework; an entry must still occur, or the test fails
until it is removed, so the lists can only shrink.)
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("models", "data", "inference", "workflows")
ALLOWED: dict[str, frozenset[str]] = {
    "models": frozenset(),
    "data": frozenset({"models"}),
    "inference": frozenset({"models"}),
    "workflows": frozenset({"models", "data", "inference"}),
}

# (importer, imported module, name): private names imported across modules
KNOWN_PRIVATE_IMPORTS: frozenset[tuple[str, str, str]] = frozenset()
# (importer, imported module): imports against the layers
KNOWN_LAYER_VIOLATIONS: frozenset[tuple[str, str]] = frozenset()
# import cycles (strongly connected components)
KNOWN_CYCLES: frozenset[frozenset[str]] = frozenset()
# the lazy loader of the models package (submodules on first attribute access)
DYNAMIC_IMPORT_EXCEPTIONS: frozenset[str] = frozenset({"models"})


@dataclass(frozen=True)
class Import:
    """One imported module (``names``: the names taken from it by ``from ... import``)."""

    importer: str
    target: str
    line: int
    names: tuple[str, ...] = ()


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def collect(root: Path, packages: tuple[str, ...]) -> tuple[set[str], list[Import], dict]:
    """(project modules, their imports of project modules, private attribute uses).

    ``from pkg import name`` counts as an import of ``pkg.name`` when that is a module,
    else of ``pkg``. Private attribute uses: ``mod._x`` where ``mod`` is a name bound to
    another project module by an import in the same file."""
    files = {module_name(p, root): p for pkg in packages for p in (root / pkg).rglob("*.py")}
    modules = set(files)
    imports: list[Import] = []
    private_attrs: dict[str, list[tuple[str, str, int]]] = {}
    for mod, path in sorted(files.items()):
        is_pkg = path.name == "__init__.py"
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        bound: dict[str, str] = {}  # local name -> project module it refers to
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    name = _unprefixed(alias.name)
                    if name.split(".")[0] in packages:
                        imports.append(Import(mod, _known(name, modules), node.lineno))
                        if alias.asname:
                            bound[alias.asname] = name
            elif isinstance(node, ast.ImportFrom):
                base = _unprefixed(_resolve_from(mod, is_pkg, node))
                top = [a.name for a in node.names] if base == "" else [base]
                if not all(t.split(".")[0] in packages for t in top):
                    continue
                plain = []
                for alias in node.names:
                    sub = f"{base}.{alias.name}" if base else alias.name
                    if sub in modules:
                        imports.append(Import(mod, sub, node.lineno))
                        bound[alias.asname or alias.name] = sub
                    else:
                        plain.append(alias.name)
                if plain:
                    imports.append(Import(mod, _known(base, modules), node.lineno, tuple(plain)))
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in bound and _private(node.attr)
                    and bound[node.value.id] != mod):
                private_attrs.setdefault(mod, []).append(
                    (bound[node.value.id], node.attr, node.lineno))
    return modules, imports, private_attrs


def _unprefixed(name: str) -> str:
    # the packages install as beadrod.models, ...; the graph is drawn on the folders' names
    # ("from beadrod import data" is an import of data: "")
    return "" if name == "beadrod" else name.removeprefix("beadrod.")


def _resolve_from(mod: str, is_pkg: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    parts = mod.split(".") if is_pkg else mod.split(".")[:-1]
    parts = parts[:len(parts) - (node.level - 1)]
    return ".".join(parts + ([node.module] if node.module else []))


def _known(name: str, modules: set[str]) -> str:
    # the longest prefix that is a project module (import a.b.c of a package a.b)
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        if ".".join(parts[:k]) in modules:
            return ".".join(parts[:k])
    return name


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def layer_violations(imports: list[Import]) -> set[tuple[str, str, int]]:
    out = set()
    for imp in imports:
        src, dst = imp.importer.split(".")[0], imp.target.split(".")[0]
        if src != dst and dst not in ALLOWED[src]:
            out.add((imp.importer, imp.target, imp.line))
    return out


def private_imports(imports: list[Import]) -> set[tuple[str, str, str, int]]:
    return {(imp.importer, imp.target, name, imp.line) for imp in imports
            for name in imp.names if _private(name) and imp.target != imp.importer}


def cycles(imports: list[Import]) -> list[list[str]]:
    """Strongly connected components with more than one module, or a self-import, each
    as one concrete cycle m0 -> m1 -> ... -> m0 (Tarjan, then a path inside the SCC)."""
    graph: dict[str, set[str]] = {}
    for imp in imports:
        graph.setdefault(imp.importer, set()).add(imp.target)
        graph.setdefault(imp.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    sccs: list[set[str]] = []

    def visit(v: str) -> None:  # recursion depth <= number of modules (~100)
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on.discard(w)
                comp.add(w)
                if w == v:
                    break
            sccs.append(comp)

    for v in sorted(graph):
        if v not in index:
            visit(v)
    out = []
    for comp in sccs:
        start = min(comp)
        if len(comp) == 1 and start not in graph[start]:
            continue
        out.append(_cycle_through(start, comp, graph))
    return out


def _cycle_through(start: str, comp: set[str], graph: dict[str, set[str]]) -> list[str]:
    # breadth-first from start back to start inside the component: a shortest cycle
    prev: dict[str, str] = {}
    frontier = [start]
    while frontier:
        nxt = []
        for v in frontier:
            for w in sorted(graph[v] & comp):
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(prev[path[-1]])
                    return [start, *reversed(path[:-1]), start] if v != start else [start, start]
                if w not in prev:
                    prev[w] = v
                    nxt.append(w)
        frontier = nxt
    raise AssertionError("a strongly connected component without a cycle")


MODULES, IMPORTS, PRIVATE_ATTRS = collect(ROOT, PACKAGES)


def test_every_package_is_scanned():
    for pkg in PACKAGES:
        assert pkg in MODULES, pkg
    # the scan sees both module-level and function-level imports
    assert ("workflows.pipeline.fits", "inference.sampling.sample") in {(i.importer, i.target)
                                                         for i in IMPORTS}


def test_no_import_against_the_layers():
    found = layer_violations(IMPORTS)
    new = sorted(v for v in found if v[:2] not in KNOWN_LAYER_VIOLATIONS)
    assert not new, "imports against the layers (models < data, inference < workflows):\n" + \
        "\n".join(f"  {a} (line {n}) imports {b}" for a, b, n in new)
    stale = KNOWN_LAYER_VIOLATIONS - {v[:2] for v in found}
    assert not stale, f"fixed, remove from KNOWN_LAYER_VIOLATIONS: {sorted(stale)}"


def test_no_import_cycle():
    found = cycles(IMPORTS)
    new = [c for c in found if not any(set(c) <= k for k in KNOWN_CYCLES)]
    assert not new, "import cycles:\n" + "\n".join("  " + " -> ".join(c) for c in new)
    stale = [k for k in KNOWN_CYCLES if not any(set(c) <= k for c in found)]
    assert not stale, f"fixed, remove from KNOWN_CYCLES: {stale}"


def test_no_private_name_imported_across_modules():
    found = private_imports(IMPORTS)
    attrs = {(m, t, name, line) for m, uses in PRIVATE_ATTRS.items() for t, name, line in uses}
    new = sorted(v for v in found | attrs if v[:3] not in KNOWN_PRIVATE_IMPORTS)
    assert not new, "private names used across modules (give shared helpers public names):\n" \
        + "\n".join(f"  {a} (line {n}): {b}.{name}" for a, b, name, n in new)
    stale = KNOWN_PRIVATE_IMPORTS - {v[:3] for v in found | attrs}
    assert not stale, f"fixed, remove from KNOWN_PRIVATE_IMPORTS: {sorted(stale)}"


def plotting_imports(root: Path, packages: tuple[str, ...]) -> list[tuple[str, int]]:
    """(module, line) of every matplotlib import under ``packages``."""
    out = []
    for pkg in packages:
        for path in sorted((root / pkg).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                         else [node.module or ""] if isinstance(node, ast.ImportFrom)
                         and not node.level else [])
                if any(n.split(".")[0] == "matplotlib" for n in names):
                    out.append((module_name(path, root), node.lineno))
    return out


def dynamic_imports(root: Path, packages: tuple[str, ...]) -> list[tuple[str, int]]:
    """(module, line) of every call of importlib.import_module or __import__ under
    ``packages`` (however importlib was imported: by the attribute or the bare name)."""
    out = []
    for pkg in packages:
        for path in sorted((root / pkg).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if not isinstance(node, ast.Call):
                    continue
                f = node.func
                name = (f.attr if isinstance(f, ast.Attribute)
                        else f.id if isinstance(f, ast.Name) else "")
                if name in ("import_module", "__import__"):
                    out.append((module_name(path, root), node.lineno))
    return out


def test_no_dynamic_import_below_workflows():
    """A module found by name at run time is an import the graph above cannot see (it
    once hid models.tables.shape_build -> models.laws.jkr, a cycle through the laws' tables)."""
    found = [m for m in dynamic_imports(ROOT, ("models", "data", "inference"))
             if m[0] not in DYNAMIC_IMPORT_EXCEPTIONS]
    assert not found, f"modules imported by name at run time below workflows/: {found}"
    assert dynamic_imports(ROOT, ("workflows",))  # the scan does see them (the CLI's)


def test_no_plotting_below_workflows():
    """Figures are drawn and written by workflows/ only (inference returns arrays)."""
    found = plotting_imports(ROOT, ("models", "data", "inference"))
    assert not found, f"matplotlib imported below workflows/: {found}"
    assert plotting_imports(ROOT, ("workflows",))  # the scan does see matplotlib imports


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        p = root / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)


@pytest.fixture
def fake_project(tmp_path):
    """A project with one violation of each kind, to show that the checks can fail."""
    _write(tmp_path, {
        "models/__init__.py": "",
        "models/a.py": "def f():\n    from data import b  # upward, deferred\n",
        "models/c.py": "from .d import _helper\nfrom . import d\nx = d._other\n",
        "models/d.py": "from models.c import x\n_helper = _other = 1\n",
        "models/g.py": "import importlib\n\ndef law(n):\n"
                       "    return importlib.import_module(f'models.{n}')\n",
        "data/__init__.py": "",
        "data/b.py": "from models import a\nimport inference.e\n",
        "inference/__init__.py": "",
        "inference/e.py": "from ..models import a\n",
        "workflows/__init__.py": "",
        "workflows/w.py": "from inference import e\nfrom models.a import f\n",
    })
    return collect(tmp_path, PACKAGES)


def test_checks_find_planted_violations(fake_project, tmp_path):
    modules, imports, attrs = fake_project
    assert {"models.a", "models.c", "data.b", "workflows.w"} <= modules
    assert {v[:2] for v in layer_violations(imports)} == {("models.a", "data.b"),
                                                          ("data.b", "inference.e")}
    assert {v[:3] for v in private_imports(imports)} == {("models.c", "models.d", "_helper")}
    assert attrs == {"models.c": [("models.d", "_other", 3)]}
    found = cycles(imports)
    # models.c <-> models.d, and models.a -> data.b -> models.a (deferred import)
    assert sorted(sorted(set(c)) for c in found) == [["data.b", "models.a"],
                                                     ["models.c", "models.d"]]
    for c in found:
        assert c[0] == c[-1] and len(c) == 3
    assert dynamic_imports(tmp_path, PACKAGES) == [("models.g", 4)]
