"""Held-out: the hostile model of test_hostile_strings.py through every file
every target generates, checked by what each file is rather than by what the
templates are known to print: every structured file parses (JSON, TOML, XML,
Python, ROS message definitions), no hostile line break starts a line of
code, CMake never sees an unescaped ``${`` or ``$(`` of a model string, and
the Foxglove layout (a backend download) carries the strings as JSON
strings only."""

from __future__ import annotations

import ast
import json
import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from modd_gen import generate, write_artifacts

from .test_hostile_strings import DESCRIPTION, hostile_model

INJECTED_LINES = re.compile(r"^\s*int p=std::system", re.MULTILINE)  # DESCRIPTION's 3rd line


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    out = tmp_path_factory.mktemp("hostile-all")
    write_artifacts(out, generate(hostile_model()))
    found = sorted(p for p in out.rglob("*") if p.is_file())
    assert len(found) >= 20
    return found


def _strings(node: Any) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [s for k, v in node.items() for s in (*_strings(k), *_strings(v))]
    if isinstance(node, list):
        return [s for v in node for s in _strings(v)]
    return []


def test_no_model_string_starts_a_line_of_code(files: list[Path]) -> None:
    for path in files:
        text = path.read_text(errors="replace")
        hit = INJECTED_LINES.search(text)
        assert hit is None, f"{path.name}: {text[max(0, hit.start() - 80) : hit.end()]!r}"


def test_structured_files_parse(files: list[Path]) -> None:
    kinds = set()
    for path in files:
        text = path.read_text()
        if path.suffix == ".json":
            doc = json.loads(text)
            assert not [s for s in _strings(doc) if "\n#include" in s and s != DESCRIPTION]
            kinds.add("json")
        elif path.suffix == ".toml":
            tomllib.loads(text)
            kinds.add("toml")
        elif path.suffix == ".xml":
            ET.fromstring(text)
            kinds.add("xml")
        elif path.suffix == ".py":
            compile(text, str(path), "exec")
            calls = {
                n.func.attr
                for n in ast.walk(ast.parse(text))
                if isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
            }
            assert not calls & {"system", "popen"}, path
            kinds.add("py")
        elif path.suffix == ".msg":
            for line in text.splitlines():
                line = line.split("#", 1)[0].strip()
                assert not line or re.fullmatch(r"[A-Za-z_][\w/]*(\[\])? [a-z_]\w*", line), line
            kinds.add("msg")
    assert kinds == {"json", "toml", "xml", "py", "msg"}


def test_cmake_never_expands_a_model_string(files: list[Path]) -> None:
    for path in files:
        if path.name != "CMakeLists.txt" and path.suffix != ".cmake":
            continue
        for line in path.read_text().splitlines():
            code = line.split("#", 1)[0] if not line.lstrip().startswith("#") else ""
            for bad in ("${HOME}", "$(id)", "`id`"):
                assert bad not in code.replace("\\${", "\\$_{"), (path, line)


def test_foxglove_layout_holds_strings_as_strings() -> None:
    from modd_backend.layouts import foxglove_layout

    layout = foxglove_layout(hostile_model())
    text = json.dumps(layout)
    assert json.loads(text) == layout
    assert INJECTED_LINES.search(text) is None
