"""The import graph drawn from the code (every ``import`` statement of ``camopt/``, inside
functions and ``TYPE_CHECKING`` blocks too): the wings in layer order (docs/design.md,
"Layers"), no import back up, no circle between modules, no loose module at the top."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "camopt"
LAYER = {"camopt": 0, "errors": 0, "units": 0, "lazy": 0, "config": 1, "mechanics": 1, "core": 2,
         "cases": 3, "solvers": 4, "engine": 5, "archive": 6, "reporting": 7, "cli": 8,
         "__main__": 9}
"""Each wing's layer: a module imports only from its own layer or those below
(``camopt`` itself is the version string and imports nothing)."""
TOP = {"__init__", "__main__", "errors", "units", "lazy"}


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return out


def _edges(modules: dict[str, Path]) -> set[tuple[str, str]]:
    """(importer, imported) for every import of a camopt module by another."""
    edges = set()
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join([*up, *([base] if base else [])])
                targets = [base, *(f"{base}.{a.name}" for a in node.names)]
            else:
                continue
            edges.update((name, t) for t in targets if t in modules and t != name)
    return edges


def _wing(module: str) -> str:
    return module.split(".")[1] if "." in module else module


def _circles(edges: set[tuple[str, str]]) -> list[list[str]]:
    """Strongly connected sets of more than one module (Tarjan); a package importing its
    own sub-module (a re-export) is not a circle."""
    graph = defaultdict(set)
    for a, b in edges:
        if not b.startswith(a + "."):
            graph[a].add(b)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while (w := stack.pop()) != v:
                component.append(w)
            if component:
                found.append([v, *component])

    for v in list(graph):
        if v not in index:
            visit(v)
    return found


def test_every_module_belongs_to_a_wing_and_none_is_loose():
    modules = _modules()
    assert {_wing(m) for m in modules} <= set(LAYER)
    loose = [m for m, p in modules.items()
             if m.count(".") == 1 and p.name != "__init__.py" and _wing(m) not in TOP]
    assert loose == []


def test_no_import_runs_back_up_a_layer():
    up = sorted((a, b) for a, b in _edges(_modules()) if LAYER[_wing(b)] > LAYER[_wing(a)])
    assert up == []


def test_no_circles_between_modules():
    assert _circles(_edges(_modules())) == []


def test_the_checks_see_a_lean_and_a_circle():
    """The checks can fail: an import back up and a two-module circle are found."""
    edges = {("camopt.core.record", "camopt.engine.driver"),
             ("camopt.cli.show", "camopt.cli.compare"), ("camopt.cli.compare", "camopt.cli.show")}
    assert [(a, b) for a, b in edges if LAYER[_wing(b)] > LAYER[_wing(a)]] == [
        ("camopt.core.record", "camopt.engine.driver")]
    assert [sorted(c) for c in _circles(edges)] == [["camopt.cli.compare", "camopt.cli.show"]]
    assert len(_edges(_modules())) > 300  # the parser sees the real imports
