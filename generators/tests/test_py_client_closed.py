"""The Python client carried beside the scientist's stubs (:mod:`modd_gen.py_client`)
imports nothing of ``modd``/``modd_contracts`` it does not carry: a stub runs on a laptop
that has only ``eclipse-zenoh``. (A module added to ``modd.subscriber``'s imports and
not to ``ORIGINALS`` fails here, not first on the scientist's laptop.)"""

from __future__ import annotations

import ast

import pytest
from modd_gen import py_client

OURS = ("modd", "modd_contracts")


def imported(name: str) -> set[str]:
    """The ``modd``/``modd_contracts`` modules one carried file imports, at any depth of
    its code (a function's lazy import counts), as dotted names."""
    package = name.removesuffix(".py").split("/")[:-1]  # a module's or __init__'s package
    out: set[str] = set()
    for node in ast.walk(ast.parse(py_client.read(name))):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] in OURS}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - node.level + 1]
                module = ".".join([*base, *([node.module] if node.module else [])])
            else:
                module = node.module or ""
            if module.split(".")[0] not in OURS:
                continue
            out.add(module)  # (``from .x import y``: y may be a name, not a module)
    return out


def carried_module(module: str) -> bool:
    path = module.replace(".", "/")
    return f"{path}.py" in py_client.ORIGINALS or f"{path}/__init__.py" in py_client.ORIGINALS


@pytest.mark.parametrize("name", sorted(n for n in py_client.ORIGINALS if n.endswith(".py")))
def test_every_module_a_carried_file_imports_is_carried(name: str) -> None:
    missing = sorted(m for m in imported(name) if not carried_module(m))
    assert not missing, f"{name} imports {missing}, which the stubs do not carry"


def test_the_check_sees_a_module_that_is_not_carried(monkeypatch: pytest.MonkeyPatch) -> None:
    """Control: a carried file that imports an uncarried module is caught."""
    monkeypatch.setattr(py_client, "read", lambda name: "from .not_carried import x\n")
    assert "modd.not_carried" in imported("modd/subscriber.py")
    assert not carried_module("modd.not_carried")
