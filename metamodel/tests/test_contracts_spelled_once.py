"""The contracts are spelled in one place (docs/architecture.md, "Contracts"):
outside ``modd_contracts`` and the files generated from it, no component's
code writes an aggregation name or a zenoh key as a literal, nor takes a key
apart by hand. Tests, benchmarks and model fixtures are data and may.

What counts as code: Python under each member's ``src/`` (string tokens, so
docstrings and comments, which document, are not code), the browser's
TypeScript outside tests (comments removed), and the C++ runtime's sources.

The delivered value's field names (``schemas/delivered_value.schema.json``)
are also words of other documents (a Foxglove message has a ``value``), so
they are held where the payload is read: Python takes a delivered value as the
contract's ``DeliveredValue`` TypedDict (mypy then checks every field it
reads), never as an untyped ``json.loads`` result; the browser reads it
through ``contracts.gen.ts``'s ``DeliveredValue`` (tsc checks), never by a
quoted index; the C++ subscriber client names no field in a string literal
(``delivered_value.gen.hpp`` does).
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest
from modd_contracts.aggregations_gen import NAMES
from modd_contracts.keys import ROOT
from modd_contracts.schema import load

REPO = Path(__file__).resolve().parents[2]

#: Where code lives, per language.
PY_ROOTS = ("metamodel/src", "backend/src", "generators/src", "runtime/python/src")
TS_ROOTS = ("frontend/src",)
CPP_ROOTS = ("runtime/cpp/src", "runtime/cpp/include")

#: Where C++ parses the delivered value: the subscriber client.
CPP_PAYLOAD_ROOTS = ("runtime/cpp/src/client", "runtime/cpp/include/modd/client")
#: The delivered value's field names.
PAYLOAD_FIELDS = frozenset(load("delivered_value")["properties"])

#: The contracts home and the files generated from it (or from the schema).
ALLOWED = (
    "metamodel/src/modd_contracts/",
    "metamodel/src/modd_model/types_gen.py",
    "metamodel/src/modd_model/_modd_parser_gen.py",
)


def _allowed(rel: str) -> bool:
    return rel.startswith(ALLOWED) or ".gen." in rel


def _is_test(rel: str) -> bool:
    return ".test." in rel or "/testing/" in rel or "/tests/" in rel


_NAME = "|".join(NAMES)
#: A key taken apart by hand: ``key.split("/")``, ``str(sample.key_expr).split("/")``.
_KEY_SPLIT = re.compile(r"key(?:_expr)?\)?\.split\(\s*[\"']/[\"']")
#: A name in a string, or in a regular expression's alternation (``/^(MIN|MAX)\b/``).
_TS_AGG = re.compile(rf"[\"'`]({_NAME})[\"'`]|[|(]({_NAME})[|)]")
_TS_COMMENT = re.compile(r"/\*[\s\S]*?\*/|(?<![:\\\"'`])//[^\n]*")
_CPP_AGG = re.compile(rf"\"({_NAME})\"")
_KEY_LITERAL = re.compile(rf"[\"'`]{ROOT}/")


def python_findings(rel: str, text: str) -> list[str]:
    """``file:line: what`` for each literal aggregation name or key in ``text``."""
    out = []
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type != tokenize.STRING:
            continue
        body = re.sub(r"^[rbfuRBFU]*", "", tok.string)
        quote = body[:3] if body[:3] in ('"""', "'''") else body[:1]
        inner = body[len(quote) : len(body) - len(quote)]
        where = f"{rel}:{tok.start[0]}"
        if inner in NAMES:
            out.append(f"{where}: aggregation name {tok.string}")
        elif len(quote) == 1 and inner.startswith(f"{ROOT}/"):
            out.append(f"{where}: zenoh key literal {tok.string}")
    for n, line in enumerate(text.splitlines(), 1):
        if _KEY_SPLIT.search(line):
            out.append(f"{rel}:{n}: zenoh key split by hand")
    return out


def ts_findings(rel: str, text: str) -> list[str]:
    code = _TS_COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    out = []
    for n, line in enumerate(code.splitlines(), 1):
        if m := _TS_AGG.search(line):
            out.append(f"{rel}:{n}: aggregation name {m.group(1) or m.group(2)}")
        if _KEY_LITERAL.search(line):
            out.append(f"{rel}:{n}: zenoh key literal")
    return out


def cpp_findings(rel: str, text: str) -> list[str]:
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        if m := _CPP_AGG.search(line):
            out.append(f"{rel}:{n}: aggregation name {m.group(0)}")
        if _KEY_LITERAL.search(line) and not line.lstrip().startswith("#include"):
            out.append(f"{rel}:{n}: zenoh key literal")
    return out


_FIELD = "|".join(sorted(PAYLOAD_FIELDS))
#: A payload field read by a quoted index (``d["value"]``) rather than a typed property.
_TS_FIELD_INDEX = re.compile(rf"(?:[\w)\]]|\?\.)\[\s*[\"'`]({_FIELD})[\"'`]\s*\]")
_CPP_STRING = re.compile(r'"((?:[^"\\\n]|\\.)*)"')
#: The name a delivered value goes by in Python code.
_PY_DELIVERED = "delivered"
#: An annotation that holds a JSON object untyped (``delivered: int``, a count, is not one).
_PY_UNTYPED = re.compile(r"\b(dict|Mapping|MutableMapping|Any|object)\b")


def _untyped(annotation: ast.expr | None) -> bool:
    return annotation is None or bool(_PY_UNTYPED.search(ast.unparse(annotation)))


def _is_json_loads(node: ast.expr) -> bool:
    return isinstance(node, ast.Call) and ast.unparse(node.func) in ("json.loads", "loads")


def python_payload_findings(rel: str, text: str) -> list[str]:
    """A delivered value held untyped: a ``delivered`` parameter or variable not
    annotated with the contract's ``DeliveredValue``, or set from ``json.loads``
    (``modd_contracts.delivered.load_delivered`` types it)."""
    out = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            a = node.args
            for arg in [*a.posonlyargs, *a.args, *a.kwonlyargs]:
                if arg.arg == _PY_DELIVERED and _untyped(arg.annotation):
                    out.append(f"{rel}:{arg.lineno}: delivered value parameter not typed")
        elif (
            isinstance(node, ast.AnnAssign)
            and ast.unparse(node.target) == _PY_DELIVERED
            and _untyped(node.annotation)
        ):
            out.append(f"{rel}:{node.lineno}: delivered value variable not typed")
        elif (
            isinstance(node, ast.Assign)
            and _is_json_loads(node.value)
            and any(ast.unparse(t) == _PY_DELIVERED for t in node.targets)
        ):
            out.append(f"{rel}:{node.lineno}: delivered value parsed untyped")
    return out


def ts_payload_findings(rel: str, text: str) -> list[str]:
    code = _TS_COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    return [
        f"{rel}:{n}: payload field {m.group(1)} by a quoted index"
        for n, line in enumerate(code.splitlines(), 1)
        if (m := _TS_FIELD_INDEX.search(line))
    ]


def cpp_payload_findings(rel: str, text: str) -> list[str]:
    code = _TS_COMMENT.sub(lambda m: "\n" * m.group(0).count("\n"), text)
    return [
        f"{rel}:{n}: payload field name {m.group(0)}"
        for n, line in enumerate(code.splitlines(), 1)
        if not line.lstrip().startswith("#include")
        for m in _CPP_STRING.finditer(line)
        if m.group(1) in PAYLOAD_FIELDS
    ]


def _files(roots: tuple[str, ...], suffixes: tuple[str, ...]) -> list[tuple[str, str]]:
    out = []
    for root in roots:
        for path in sorted((REPO / root).rglob("*")):
            rel = path.relative_to(REPO).as_posix()
            if path.suffix in suffixes and not _allowed(rel) and not _is_test(rel):
                out.append((rel, path.read_text(encoding="utf-8")))
    return out


def test_the_scanners_find_what_they_look_for() -> None:
    """Each scanner on a sample that breaks the rule (so the test can fail)."""
    py = 'X = "AVERAGE"\nK = f"modd/{d}/status"\nd = key.split("/")\n"""AVERAGE in a doc"""\n'
    assert [f.split(": ", 1)[1] for f in python_findings("a.py", py)] == [
        'aggregation name "AVERAGE"',
        'zenoh key literal f"modd/{d}/status"',
        "zenoh key split by hand",
    ]
    ts = (
        'const a = "MIN"; // MAX in a comment\n/* SUM */ x = AGGREGATION.SUM;\nk = `modd/${d}`;\n'
        "const MAX = 3; const K = /^(Drone|FIRST|LAST)\\b/;\n"
    )
    assert ts_findings("a.ts", ts) == [
        "a.ts:1: aggregation name MIN",
        "a.ts:3: zenoh key literal",
        "a.ts:4: aggregation name FIRST",
    ]
    assert cpp_findings("a.cpp", 'if (s == "COUNT") {}  // COUNT\n') == [
        'a.cpp:1: aggregation name "COUNT"'
    ]


def test_the_payload_scanners_find_what_they_look_for() -> None:
    """Each payload-field scanner on a sample that breaks the rule."""
    py = (
        "def f(delivered: dict[str, Any]) -> None: ...\n"
        "def g(delivered: DeliveredValue, data: dict) -> None: ...\n"
        "delivered = json.loads(raw)\n"
        "delivered: dict = {}\n"
        "x = {'value': 1}\n"
        "def h(delivered) -> None: ...\n"
        "delivered: int = 0\n"
    )
    assert python_payload_findings("a.py", py) == [
        "a.py:1: delivered value parameter not typed",
        "a.py:3: delivered value parsed untyped",
        "a.py:4: delivered value variable not typed",
        "a.py:6: delivered value parameter not typed",
    ]
    ts = (
        'const v = d["end_ns"]; // d["value"]\nconst t = d.end_ns; m["type"] = "value";\n'
        'const roles = ["subscriber", "topic"]; const c = msg?.["count"];\n'
    )
    assert ts_payload_findings("a.ts", ts) == [
        "a.ts:1: payload field end_ns by a quoted index",
        "a.ts:3: payload field count by a quoted index",
    ]
    cpp = (
        '#include "modd/client/subscriber.hpp"\n'
        'if (key == "start_ns") return bad("bad \\"" + key + "\\"");  // "value"\n'
        "if (key == f::kValue) {}\n"
    )
    assert cpp_payload_findings("a.cpp", cpp) == ['a.cpp:2: payload field name "start_ns"']


@pytest.mark.parametrize(
    ("language", "roots", "suffixes", "scan"),
    [
        ("python", PY_ROOTS, (".py",), python_payload_findings),
        ("typescript", TS_ROOTS, (".ts", ".tsx"), ts_payload_findings),
        ("c++", CPP_PAYLOAD_ROOTS, (".cpp", ".hpp", ".h"), cpp_payload_findings),
    ],
)
def test_no_payload_field_spelled_outside_its_types(
    language: str, roots: tuple[str, ...], suffixes: tuple[str, ...], scan: object
) -> None:
    assert callable(scan)
    found = [f for rel, text in _files(roots, suffixes) for f in scan(rel, text)]
    assert found == [], (
        f"{language}: delivered-value fields read outside the contract's types "
        "(modd_contracts.types_gen.DeliveredValue and modd_contracts.delivered.load_delivered, "
        "contracts.gen.ts, delivered_value.gen.hpp):\n" + "\n".join(found)
    )


@pytest.mark.parametrize(
    ("language", "roots", "suffixes", "scan"),
    [
        ("python", PY_ROOTS, (".py",), python_findings),
        ("typescript", TS_ROOTS, (".ts", ".tsx"), ts_findings),
        ("c++", CPP_ROOTS, (".cpp", ".hpp", ".h"), cpp_findings),
    ],
)
def test_no_contract_spelled_outside_its_home(
    language: str, roots: tuple[str, ...], suffixes: tuple[str, ...], scan: object
) -> None:
    assert callable(scan)
    found = [f for rel, text in _files(roots, suffixes) for f in scan(rel, text)]
    assert found == [], (
        f"{language}: contracts spelled outside modd_contracts (use modd_contracts.keys / "
        "aggregations, contracts.gen.ts, aggregation_table.gen.hpp):\n" + "\n".join(found)
    )
