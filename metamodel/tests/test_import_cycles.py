"""No import cycle between the modules of our Python packages
(docs/architecture.md, "Names").

Every import counts: at module level, inside a function (a lazy import is
still a dependency) and under ``if TYPE_CHECKING:`` (a type-only cycle is
still two modules that cannot be read, tested or moved apart). Where two
modules need each other's types, one of them states what it reads as a
``Protocol`` (``modd_plan.planjson.PlanView``) or the shared type moves to a
module of its own (``modd.subbroker.running``).

The graph is read from the sources with ``ast`` (nothing is imported), so a
cycle is found even where Python would tolerate it at run time.

Layers: no arrow runs back up from the runtime (``runtime/python/src``) to the
generators (``generators/src``); what both need lives below them, in the
metamodel's packages (``modd_model``, ``modd_contracts``). Only the launcher
(``launcher/src``: ``modd up``) depends on both, and nothing imports it
(docs/architecture.md, "Parts").
"""

from __future__ import annotations

import ast
from collections.abc import Iterator, Mapping
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: The members' source roots.
ROOTS = ("metamodel/src", "generators/src", "runtime/python/src", "backend/src", "launcher/src")

#: Generated third-party code: Lark's standalone parser keeps Lark's own
#: ``from . import __version__`` (in its cache branch, never taken here).
GENERATED = frozenset({"modd_model._modd_parser_gen"})


def modules(roots: Mapping[str, Path]) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` under the roots."""
    out: dict[str, Path] = {}
    for root in roots.values():
        for path in sorted(root.rglob("*.py")):
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            if parts:
                out[".".join(parts)] = path
    return out


def _imported(node: ast.AST, package: str, known: Mapping[str, Path]) -> Iterator[str]:
    if isinstance(node, ast.Import):
        yield from (alias.name for alias in node.names)
    elif isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:
            parts = package.split(".")
            parts = parts[: len(parts) - (node.level - 1)]
            base = ".".join([*parts, base] if base else parts)
        for alias in node.names:
            sub = f"{base}.{alias.name}"
            yield sub if sub in known else base


def import_graph(known: Mapping[str, Path]) -> dict[str, set[str]]:
    """Module -> the modules of ours it imports, anywhere in its body."""
    graph: dict[str, set[str]] = {name: set() for name in known}
    for name, path in known.items():
        if name in GENERATED:
            continue
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            for target in _imported(node, package, known):
                if target in known and target != name:
                    graph[name].add(target)
    return graph


def cycles(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan,
    iterative so that a deep graph cannot exhaust the stack)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work: list[tuple[str, Iterator[str]]] = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, edges = work[-1]
            nxt = next(edges, None)
            if nxt is not None:
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph[nxt]))))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component: list[str] = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_no_import_cycle_in_our_packages() -> None:
    known = modules({root: REPO / root for root in ROOTS})
    assert "modd_plan.plan" in known and "modd.subbroker.broker" in known  # roots read
    assert cycles(import_graph(known)) == []


def test_a_cycle_is_found(tmp_path: Path) -> None:
    """The rule's own sample: a type-only cycle and a lazy one are found, a
    one-way import is not."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .b import B\n"
    )
    (pkg / "b.py").write_text("from . import a\n")
    (pkg / "c.py").write_text("def f():\n    from pkg.d import g\n")
    (pkg / "d.py").write_text("import pkg.c\n")
    (pkg / "e.py").write_text("from .a import x\n")
    assert cycles(import_graph(modules({"t": tmp_path}))) == [
        ["pkg.a", "pkg.b"],
        ["pkg.c", "pkg.d"],
    ]


def layer_violations(roots: Mapping[str, Path], upper: str, lower: str) -> list[tuple[str, str]]:
    """``(module, imported)`` where a module under the root ``lower`` imports
    one under ``upper`` (the arrow running back up)."""
    known = modules(roots)
    below = set(modules({lower: roots[lower]}))
    above = set(modules({upper: roots[upper]}))
    graph = import_graph(known)
    return sorted((name, target) for name in below for target in graph[name] if target in above)


def test_runtime_does_not_import_the_generators() -> None:
    roots = {root: REPO / root for root in ROOTS}
    assert "modd_launch.up" in modules(roots)  # the launcher is read
    assert layer_violations(roots, "generators/src", "runtime/python/src") == []


@pytest.mark.parametrize("lower", [r for r in ROOTS if r != "launcher/src"])
def test_nothing_imports_the_launcher(lower: str) -> None:
    roots = {root: REPO / root for root in ROOTS}
    assert layer_violations(roots, "launcher/src", lower) == []


def test_a_layer_violation_is_found(tmp_path: Path) -> None:
    """The rule's own sample: a lazy import back up and a module-level one are
    found, an import downwards is not."""
    upper, lower = tmp_path / "gen", tmp_path / "rt"
    for root, pkg in ((upper, "g"), (lower, "r")):
        (root / pkg).mkdir(parents=True)
        (root / pkg / "__init__.py").write_text("")
    (upper / "g" / "a.py").write_text("import r.b\n")
    (lower / "r" / "b.py").write_text("def f():\n    from g.a import x\n")
    (lower / "r" / "c.py").write_text("from g import a\n")
    roots = {"gen": upper, "rt": lower}
    assert layer_violations(roots, "gen", "rt") == [("r.b", "g.a"), ("r.c", "g.a")]
