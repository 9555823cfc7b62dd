"""The link and ingress protocols' enumerations, counts and limits
(``wire.json``), written as C++ headers and Python modules.

Each group of ``wire.json`` goes to one C++ namespace in its header and to one
Python module of this package; groups sharing a header (or a module) are
written into it in the contract's order. The codecs and validation import
what is generated, so a value added to the contract reaches both languages
with no other edit.

>>> sorted(outputs())[0]
'metamodel/src/modd_contracts/ingress_wire_gen.py'
>>> "HELLO = 0x01" in outputs()["metamodel/src/modd_contracts/link_wire_gen.py"]
True
"""

from __future__ import annotations

import json
import textwrap
from functools import cache
from importlib import resources
from typing import Any

from modd_model.schema import definition

HEADER = "Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit."
PY_DIR = "metamodel/src/modd_contracts"


@cache
def load() -> dict[str, Any]:
    """The wire contract (``wire.json``, package data)."""
    text = resources.files(__package__).joinpath("wire.json").read_text(encoding="utf-8")
    contract: dict[str, Any] = json.loads(text)
    return contract


def _camel(name: str) -> str:
    """``AUTH_OK`` -> ``AuthOk``."""
    return "".join(part.capitalize() for part in name.split("_"))


def _values(enum: dict[str, Any]) -> list[tuple[str, str, str]]:
    """``(name, value as written, doc)`` of each member; a ``fromSchema`` enum
    is the metamodel's enum of that name, coded 0, 1, ... in its order."""
    if "fromSchema" in enum:
        names = definition(enum["fromSchema"])["enum"]
        return [(str(n).upper(), str(i), "") for i, n in enumerate(names)]
    return [(v["name"], str(v["value"]), v.get("doc", "")) for v in enum["values"]]


def _check(group: dict[str, Any]) -> None:
    """Names unique, values integers: a typo fails here, not in a compiler."""
    for enum in group["enums"]:
        members = _values(enum)
        if len({n for n, _, _ in members}) != len(members):
            raise ValueError(f"wire.json {group['name']}/{enum['name']}: a name twice")
        if len({int(v, 0) for _, v, _ in members}) != len(members):
            raise ValueError(f"wire.json {group['name']}/{enum['name']}: a value twice")
        if enum.get("labels") and [int(v, 0) for _, v, _ in members] != list(range(len(members))):
            raise ValueError(
                f"wire.json {group['name']}/{enum['name']}: labels need codes 0, 1, ..."
            )
    for c in group["constants"]:
        int(str(c["value"]), 0)


def _comment(prefix: str, text: str) -> list[str]:
    """``text`` as comment lines within the formatter's 100 columns."""
    return [prefix + line for line in textwrap.wrap(text, 96 - len(prefix))]


# -- Python ----------------------------------------------------------------------------


def _py_enum(enum: dict[str, Any]) -> list[str]:
    doc = textwrap.wrap(enum["doc"], 88)
    out = [f"class {enum['name']}(IntEnum):", f'    """{doc[0]}']
    out += [f"    {line}" for line in doc[1:]]
    out[-1] += '"""'
    out.append("")
    out += [f"    {n} = {v}" + (f"  # {d}" if d else "") for n, v, d in _values(enum)]
    if enum.get("labels"):
        out += [
            "",
            "    @property",
            "    def label(self) -> str:",
            '        """The member\'s name in logs and status documents (``"uptime_s"``)."""',
            "        return self.name.lower()",
        ]
    if "fromSchema" in enum:
        names = definition(enum["fromSchema"])["enum"]
        labels = "(" + ", ".join(json.dumps(x) for x in names) + ")"
        codes = "{" + ", ".join(f"{json.dumps(x)}: {i}" for i, x in enumerate(names)) + "}"
        out += [
            "",
            "    @classmethod",
            f"    def parse(cls, label: str) -> {enum['name']}:",
            '        """The member of a metamodel label (``"float32"``); KeyError if none."""',
            f"        return cls({codes}[label])",
            "",
            "    @property",
            "    def label(self) -> str:",
            '        """The metamodel label of the member."""',
            f"        return {labels}[self]",
        ]
    return out


def _py_module(groups: list[dict[str, Any]]) -> str:
    """Blocks two blank lines apart, as the formatter writes them."""
    head = [
        f'"""{HEADER}',
        "",
        "Wire enumerations, counts and limits (modd_contracts/wire.json).",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "from enum import IntEnum",
    ]
    if any(g["constants"] for g in groups):
        head.append("from typing import Final")
    blocks = [head]
    names: list[str] = []
    for g in groups:
        block = _comment("# -- ", f"{g['name']}: {g['doc']}")
        for c in g["constants"]:
            block += [*_comment("#: ", c["doc"]), f"{c['name']}: Final = {c['value']}"]
            names.append(c["name"])
        blocks.append(block)
        for enum in g["enums"]:
            blocks.append(_py_enum(enum))
            names.append(enum["name"])
    blocks.append(["__all__ = [", *[f"    {json.dumps(n)}," for n in names], "]"])
    # one blank line after the imports (isort), two between the other blocks
    text = "\n\n\n".join("\n".join(b) for b in blocks[1:])
    return "\n".join(blocks[0]) + "\n\n" + text + "\n"


# -- C++ --------------------------------------------------------------------------------


def _cpp_enum(enum: dict[str, Any]) -> list[str]:
    name = enum.get("cpp", enum["name"])
    members = _values(enum)
    out = ["", *_comment("// ", enum["doc"]), f"enum class {name} : {enum['type']} {{"]
    out += [f"  {_camel(n)} = {v}," + (f"  // {d}" if d else "") for n, v, d in members]
    out += [
        "};",
        f"// The number of {name} values.",
        f"inline constexpr size_t k{name}Count = {len(members)};",
    ]
    if enum.get("labels"):
        labels = ", ".join(json.dumps(n.lower()) for n, _, _ in members)
        out += [
            f"// Each {name}'s name in logs and status documents, by code.",
            f"inline constexpr const char* k{name}Labels[] = {{{labels}}};",
        ]
    if "fromSchema" in enum:
        labels = ", ".join(json.dumps(x) for x in definition(enum["fromSchema"])["enum"])
        out += [
            f"// The metamodel's label of each {name}, by code.",
            f"inline constexpr const char* k{name}Labels[] = {{{labels}}};",
        ]
    return out


def _cpp_group(group: dict[str, Any]) -> list[str]:
    namespace = group["cpp"]["namespace"]
    out = [*_comment("// ", group["doc"]), f"namespace {namespace} {{", ""]
    for c in group["constants"]:
        name = c.get("cpp", "k" + _camel(c["name"]))
        out += [*_comment("// ", c["doc"]), f"inline constexpr {c['type']} {name} = {c['value']};"]
    for enum in group["enums"]:
        out += _cpp_enum(enum)
    return [*out, "", f"}}  // namespace {namespace}", ""]


def _cpp_header(groups: list[dict[str, Any]]) -> str:
    out = [
        f"// {HEADER}",
        "// Wire enumerations, counts and limits (modd_contracts/wire.json).",
        "#pragma once",
        "",
        "#include <cstddef>",
        "#include <cstdint>",
        "",
    ]
    for g in groups:
        out += _cpp_group(g)
    return "\n".join(out)


def outputs() -> dict[str, str]:
    """Each generated file (path from the repository root) and its text."""
    py: dict[str, list[dict[str, Any]]] = {}
    cpp: dict[str, list[dict[str, Any]]] = {}
    for g in load()["groups"]:
        _check(g)
        py.setdefault(f"{PY_DIR}/{g['py']}.py", []).append(g)
        cpp.setdefault(g["cpp"]["header"], []).append(g)
    return {
        **{p: _py_module(gs) for p, gs in py.items()},
        **{p: _cpp_header(gs) for p, gs in cpp.items()},
    }
