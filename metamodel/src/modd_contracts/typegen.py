"""Types and tables generated from the contracts, so that no language
re-types them by hand:

- ``metamodel/src/modd_contracts/types_gen.py``: Python TypedDicts of the contract
  schemas (``schemas/*.schema.json``) and their versions;
- ``frontend/src/core/contracts.gen.ts``: the same as TypeScript types;
- ``metamodel/src/modd_contracts/aggregations_gen.py``: the aggregation table
  (the metamodel's ``Aggregation`` ``x-table``) for Python;
- ``runtime/cpp/include/modd/link/aggregation_table.gen.hpp``: the same for C++;
- ``runtime/cpp/include/modd/client/delivered_value.gen.hpp``: the delivered
  value's field names and version, for the C++ subscriber client's parser;
- ``runtime/cpp/include/modd/archive/archive_record.gen.hpp``: the archive
  record's field, MCAP schema names and channel schemas, for the PubBroker's
  archive writer and reader;
- the link and ingress protocols' enumerations, counts and limits
  (``wire.json``, written by :mod:`modd_contracts.wiregen`):
  ``modd_contracts/{link,ingress}_wire_gen.py`` and ``wire.gen.hpp`` headers.

It also writes the metamodel's outputs (:mod:`modd_model.typegen`: the model's
TypeScript and Python types, docs/metamodel.md): this is the one command that
writes every generated file (``python -m modd_model.typegen`` still writes the
metamodel's alone). The .modd parser (``modd_model/_modd_parser_gen.py``) is lark's
standalone tool's output (the command is in its header), and
docs/generated-code.md is the generators' (``python -m modd_gen.table2``).

Run ``python -m modd_contracts.typegen`` to rewrite them; ``--check`` exits 1
when one is stale (``make check`` does that, and a test).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from modd_model import typegen as model_typegen
from modd_model.schema import definition, load_schema
from modd_model.typegen import _dependency_order, _py_type, _ts_doc, _ts_type

from . import wiregen
from .schema import NAMES, load

HEADER = "Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit."
REPO = Path(__file__).resolve().parents[3]
OUTPUTS = {
    "py": REPO / "metamodel" / "src" / "modd_contracts" / "types_gen.py",
    "ts": REPO / "frontend" / "src" / "core" / "contracts.gen.ts",
    "aggpy": REPO / "metamodel" / "src" / "modd_contracts" / "aggregations_gen.py",
    "aggcpp": REPO / "runtime" / "cpp" / "include" / "modd" / "link" / "aggregation_table.gen.hpp",
    "owners": REPO / "metamodel" / "src" / "modd_contracts" / "owners_gen.py",
    "dvcpp": REPO / "runtime" / "cpp" / "include" / "modd" / "client" / "delivered_value.gen.hpp",
    "arcpp": REPO / "runtime" / "cpp" / "include" / "modd" / "archive" / "archive_record.gen.hpp",
    "qcpp": REPO / "runtime" / "cpp" / "include" / "modd" / "link" / "quantised.gen.hpp",
}


def _definitions() -> list[tuple[str, dict[str, Any]]]:
    """Every contract's root (named by its title) and ``$defs``, in order."""
    out: list[tuple[str, dict[str, Any]]] = []
    for name in NAMES:
        schema = load(name)
        out.append((schema["title"], {k: v for k, v in schema.items() if k != "$defs"}))
        out += list(schema.get("$defs", {}).items())
    return out


def _versions() -> list[tuple[str, int]]:
    return [(f"{name.upper()}_VERSION", int(load(name)["x-version"])) for name in NAMES]


def generate_py() -> str:
    defs = _definitions()
    out = [
        f'"""{HEADER}"""',
        "",
        "from __future__ import annotations",
        "",
        "from dataclasses import dataclass",
        "from typing import Any, Literal, NotRequired, TypedDict",
        "",
    ]
    for const, v in _versions():
        out.append(f"{const} = {v}")
    out += ["", ""]
    for name, s in _dependency_order([(n, s) for n, s in defs if "properties" not in s]):
        out.append(f"{name} = {_py_type(s)}")
    out += ["", ""]
    for name, s in defs:
        if "properties" not in s:
            continue
        required = set(s.get("required", []))
        doc = s.get("description", name).split(". ")[0].rstrip(".")
        out += [f"class {name}(TypedDict):", f'    """{doc}."""', ""]
        for prop, ps in s["properties"].items():
            t = _py_type(ps)
            out.append(f"    {prop}: {t if prop in required else f'NotRequired[{t}]'}")
        out += ["", ""]
    records = dict(defs)
    required_consts = []
    for name, (record, omit) in RECORDS.items():
        out += _py_record(name, record, omit, records[name])
        const = _snake(name).upper() + "_REQUIRED"
        required = set(records[name].get("required", []))
        order = [p for p in records[name]["properties"] if p in required]
        out += [
            f"#: The fields every :class:`{name}` carries, in the contract's order.",
            f"{const}: tuple[str, ...] = ({', '.join(json.dumps(p) for p in order)},)",
            "",
            "",
        ]
        required_consts.append(const)
    names = [c for c, _ in _versions()] + [n for n, _ in defs] + [r for r, _ in RECORDS.values()]
    names += required_consts
    out.append("__all__ = [" + ", ".join(f'"{n}"' for n in names) + "]")
    text = "\n".join(out) + "\n"
    if "Any]" not in text:
        text = text.replace("import Any, Literal", "import Literal")
    if "Literal[" not in text:
        text = text.replace("Literal, ", "")
    return text


#: Contracts that Python code holds as objects: a frozen dataclass of the
#: contract's fields but the ones named (its version, a constant of the writer),
#: which the owner subclasses with its methods (``modd.subbroker.payload``).
RECORDS: dict[str, tuple[str, tuple[str, ...]]] = {
    "DeliveredValue": ("DeliveredValueFields", ("v",))
}


def _snake(name: str) -> str:
    """``DeliveredValue`` -> ``delivered_value``."""
    return "".join(f"_{c.lower()}" if c.isupper() else c for c in name).lstrip("_")


def _py_record(name: str, record: str, omit: tuple[str, ...], s: dict[str, Any]) -> list[str]:
    """A frozen dataclass of ``s``'s properties in their order; an optional
    boolean defaults to False, another optional to None (optionals come last)."""
    required = set(s.get("required", []))
    out = [
        "@dataclass(frozen=True)",
        f"class {record}:",
        f'    """The fields of :class:`{name}` but {", ".join(omit)}, as a record."""',
        "",
    ]
    for prop, ps in s["properties"].items():
        if prop in omit:
            continue
        if prop in required:
            out.append(f"    {prop}: {_py_type(ps)}")
        elif ps.get("type") == "boolean":
            out.append(f"    {prop}: bool = False")
        else:  # absent: None
            out.append(f"    {prop}: {_py_type(ps)} | None = None")
    return [*out, "", ""]


def generate_ts() -> str:
    out = [f"// {HEADER}", ""]
    for const, v in _versions():
        out.append(f"export const {const} = {v};")
    out.append("")
    for name, s in _definitions():
        out += _ts_doc(s.get("description"))
        if "properties" in s:
            required = set(s.get("required", []))
            out.append(f"export interface {name} {{")
            for prop, ps in s["properties"].items():
                out += _ts_doc(ps.get("description"), "  ")
                out.append(f"  {prop}{'' if prop in required else '?'}: {_ts_type(ps)};")
            out.append("}")
        else:
            out.append(f"export type {name} = {_ts_type(s)};")
        if "enum" in s:
            out.append(
                f"export const {name}Values = [{', '.join(json.dumps(v) for v in s['enum'])}]"
                " as const;"
            )
        out.append("")
    out += _ts_aggregations()
    out += _ts_owners()
    return "\n".join(out)


# -- who owns which part of a model ------------------------------------------------


def part_owners() -> dict[str, str | None]:
    """JSON pointer of each model part with an ``x-owner`` and its role: the
    root's properties, and the properties of the definitions they refer to
    (``/drone/sensors``)."""
    root = load_schema()
    out: dict[str, str | None] = {}
    for prop, s in root["properties"].items():
        if "x-owner" in s:
            out[f"/{prop}"] = s["x-owner"]
        ref = s.get("$ref", "")
        if ref.startswith("#/$defs/"):
            for sub, ss in root["$defs"][ref.split("/")[-1]].get("properties", {}).items():
                if "x-owner" in ss:
                    out[f"/{prop}/{sub}"] = ss["x-owner"]
    return out


def _ts_owners() -> list[str]:
    owners = part_owners()
    roles = sorted({r for r in owners.values() if r is not None})
    role_type = " | ".join(json.dumps(r) for r in roles)
    out = [
        "/** The role owning each model part (modd.schema.json x-owner; null: any editor). */",
        f"export const MODEL_PART_OWNERS: Readonly<Record<string, {role_type} | null>> = {{",
    ]
    out += [f"  {json.dumps(k)}: {json.dumps(v)}," for k, v in owners.items()]
    return [*out, "};", ""]


def generate_owners_py() -> str:
    out = [
        f'"""{HEADER}',
        "",
        "The role owning each model part (metamodel/modd.schema.json ``x-owner``;",
        "``None``: any editor), by JSON pointer.",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "MODEL_PART_OWNERS: dict[str, str | None] = {",
    ]
    for pointer, role in part_owners().items():
        out.append(f"    {json.dumps(pointer)}: {json.dumps(role) if role else None},")
    return "\n".join([*out, "}", ""])


# -- the aggregation table ---------------------------------------------------------


def _table() -> list[dict[str, Any]]:
    agg = definition("Aggregation")
    rows: list[dict[str, Any]] = agg["x-table"]
    names = [r["name"] for r in rows]
    if names != agg["enum"] or [r["code"] for r in rows] != list(range(len(rows))):
        raise ValueError("Aggregation x-table must list the enum in wire-code order 0, 1, ...")
    return rows


def _ts_aggregations() -> list[str]:
    out = [
        "/** The aggregation table (modd.schema.json Aggregation x-table). */",
        "export const AGGREGATION_TABLE = [",
    ]
    for r in _table():
        out.append(
            f"  {{ name: {json.dumps(r['name'])}, code: {r['code']}, "
            f"numericOnly: {json.dumps(r['numericOnly'])} }},"
        )
    out += [
        "] as const;",
        "",
        "/** Each aggregation's name, for code that compares or builds one. */",
        "export const AGGREGATION = {",
    ]
    out += [f"  {r['name']}: {json.dumps(r['name'])}," for r in _table()]
    out += ["} as const;", ""]
    return out


def generate_agg_py() -> str:
    out = [
        f'"""{HEADER}',
        "",
        "The aggregation table (metamodel/modd.schema.json, ``Aggregation`` x-table):",
        "one row per aggregation, in wire-code order.",
        "",
        '>>> BY_NAME["AVERAGE"].result["int"]',
        "'float64'",
        '"""',
        "",
        "from __future__ import annotations",
        "",
        "from dataclasses import dataclass",
        "from enum import IntEnum",
        "from typing import Final",
        "",
        "#: Each aggregation's name, for code that compares or builds one",
        "#: (``aggregation == AVERAGE``); typed as its ``Literal``.",
    ]
    out += [f"{r['name']}: Final = {json.dumps(r['name'])}" for r in _table()]
    out += [
        "",
        "",
        "class Aggregation(IntEnum):",
        '    """The wire code of each aggregation (docs/protocol.md); the enum order is',
        '    the stream-id order of the plan contract."""',
        "",
    ]
    out += [f"    {r['name']} = {r['code']}" for r in _table()]
    out += [
        "",
        "",
        "@dataclass(frozen=True)",
        "class AggregationSpec:",
        '    """One aggregation: see the schema\'s ``x-table-doc`` for each field."""',
        "",
        "    name: str",
        "    code: int",
        "    numeric_only: bool",
        "    wire_count: bool",
        "    keeps_samples: bool",
        "    result: dict[str, str]",
        "    derivable_from: tuple[str, ...]",
        "    derivable_from_pair: tuple[str, str] | None",
        "",
        "",
        "AGGREGATIONS: tuple[AggregationSpec, ...] = (",
    ]
    for r in _table():
        pair = r.get("derivableFromPair")
        out += [
            "    AggregationSpec(",
            f"        name={r['name']!r},",
            f"        code={r['code']},",
            f"        numeric_only={r['numericOnly']},",
            f"        wire_count={r['wireCount']},",
            f"        keeps_samples={r.get('keepsSamples', False)},",
            f"        result={r['result']!r},",
            f"        derivable_from={tuple(r['derivableFrom'])!r},",
            f"        derivable_from_pair={tuple(pair) if pair else None!r},",
            "    ),",
        ]
    out += [
        ")",
        "#: The rows by name.",
        "BY_NAME: dict[str, AggregationSpec] = {a.name: a for a in AGGREGATIONS}",
        "#: The names in wire-code order.",
        "NAMES: tuple[str, ...] = tuple(a.name for a in AGGREGATIONS)",
        "",
    ]
    return "\n".join(out)


def generate_agg_cpp() -> str:
    types = ["float32", "float64", "int", "bool"]
    enum = {"float32": "Float32", "float64": "Float64", "int": "Int", "bool": "Bool"}
    out = [
        f"// {HEADER}",
        "// The aggregation table (metamodel/modd.schema.json, Aggregation x-table).",
        "#pragma once",
        "",
        "#include <cstdint>",
        "",
        "namespace modd::link {",
        "",
        "// The wire code of each aggregation (docs/protocol.md).",
        "enum class Aggregation : uint8_t {",
    ]
    out += [
        f"  {''.join(p.capitalize() for p in r['name'].split('_'))} = {r['code']},"
        for r in _table()
    ]
    out += [
        "};",
        "",
        "}  // namespace modd::link",
        "",
        "namespace modd::link::table {",
        "",
        "struct AggregationRow {",
        "  const char* name;",
        "  uint8_t code;",
        "  bool numeric_only;",
        "  bool wire_count;",
        "  bool keeps_samples;  // holds every sample of the window (at most kMaxList)",
        "  // Wire value type per topic type, indexed by ValueType",
        "  // (float32, float64, int, bool): 0 float32, 1 float64, 2 int, 3 bool.",
        "  uint8_t result[4];",
        "};",
        "",
        "inline constexpr AggregationRow kAggregations[] = {",
    ]
    for r in _table():
        res = ", ".join(str(types.index(r["result"][t])) for t in types)
        out.append(
            f'    {{"{r["name"]}", {r["code"]}, {str(r["numericOnly"]).lower()}, '
            f"{str(r['wireCount']).lower()}, {str(r.get('keepsSamples', False)).lower()}, "
            f"{{{res}}}}},"
        )
    out += [
        "};",
        f"inline constexpr int kAggregationCount = {len(_table())};",
        "",
        f"// Value types in the order of result[]: {', '.join(enum[t] for t in types)}.",
        "",
        "}  // namespace modd::link::table",
        "",
    ]
    return "\n".join(out)


# -- the delivered value's field names for C++ ----------------------------------------


def _cpp_ident(field: str) -> str:
    """``start_ns`` -> ``kStartNs`` (the project's constant style)."""
    return "k" + "".join(part.capitalize() for part in field.split("_"))


def generate_delivered_value_cpp() -> str:
    schema = load("delivered_value")
    out = [
        f"// {HEADER}",
        "// The delivered value's field names and version",
        "// (metamodel/src/modd_contracts/schemas/delivered_value.schema.json),",
        "// read by the C++ subscriber client's parser (docs/subbroker.md).",
        "#pragma once",
        "",
        "#include <cstdint>",
        "#include <string_view>",
        "",
        "namespace modd::delivered_value {",
        "",
        "// Payload version; a reader rejects a higher one.",
        f"inline constexpr int64_t kVersion = {int(schema['x-version'])};",
        "",
    ]
    for prop, ps in schema["properties"].items():
        doc = str(ps.get("description", prop)).split(". ")[0].rstrip(".")
        out += [
            f"// {doc}.",
            f"inline constexpr std::string_view {_cpp_ident(prop)} = {json.dumps(prop)};",
        ]
    out += ["", "}  // namespace modd::delivered_value", ""]
    return "\n".join(out)


#: The value types in the order of the C++ ``link::ValueType`` (its wire codes).
CPP_VALUE_TYPES = ("float32", "float64", "int", "bool")


def generate_archive_record_cpp() -> str:
    schema = load("archive_record")
    channels = schema["x-channel-schemas"]
    if tuple(channels) != CPP_VALUE_TYPES:
        raise ValueError(f"archive_record x-channel-schemas must list {CPP_VALUE_TYPES}")

    def lit(text: str) -> str:
        return json.dumps(text)

    compact = [lit(json.dumps(channels[t], separators=(",", ":"))) for t in CPP_VALUE_TYPES]
    sv = "inline constexpr std::string_view"
    out = [
        f"// {HEADER}",
        "// The archive record (metamodel/src/modd_contracts/schemas/archive_record.schema.json):",
        "// the MCAP message, schema and channel of one sample, written by the archiver",
        "// and read by the archive reader (docs/pubbroker.md).",
        "#pragma once",
        "",
        "#include <cstdint>",
        "#include <string_view>",
        "",
        "namespace modd::archive_record {",
        "",
        f"inline constexpr int64_t kVersion = {int(schema['x-version'])};",
        "// The one field of a message: the sample.",
        f"{sv} kValue = {lit(next(iter(schema['properties'])))};",
        "// A channel's schema is named kSchemaPrefix + value type.",
        f"{sv} kSchemaPrefix = {lit(schema['x-schema-prefix'])};",
        f"{sv} kSchemaEncoding = {lit(schema['x-schema-encoding'])};",
        f"{sv} kMessageEncoding = {lit(schema['x-message-encoding'])};",
        "// The channel metadata key holding the value type.",
        f"{sv} kTypeMetadataKey = {lit(schema['x-type-metadata-key'])};",
        "// Schema data of a channel, by value type (link::ValueType's order).",
        "inline constexpr std::string_view kChannelSchemas[] = {",
        *[f"    {c}," for c in compact],
        "};",
        "",
        "}  // namespace modd::archive_record",
        "",
    ]
    return "\n".join(out)


def generate_quantised_cpp() -> str:
    """The wire constants of quantised values (modd_contracts/quantised.py)."""
    from .quantised import CONSTANTS

    out = [
        f"// {HEADER}",
        "// The wire constants of quantised values (modd_contracts/quantised.py,",
        '// docs/protocol.md "Quantised values"), read by link/quantise.cpp.',
        "#pragma once",
        "",
        "#include <cstdint>",
        "",
        "namespace modd::link::quantised {",
        "",
    ]
    for name, value, doc in CONSTANTS:
        out += [f"// {doc}", f"inline constexpr uint64_t {_cpp_ident(name.lower())} = {value};"]
    out += ["", "}  // namespace modd::link::quantised", ""]
    return "\n".join(out)


GENERATORS: dict[str, Callable[[], str]] = {
    "py": generate_py,
    "ts": generate_ts,
    "aggpy": generate_agg_py,
    "aggcpp": generate_agg_cpp,
    "owners": generate_owners_py,
    "dvcpp": generate_delivered_value_cpp,
    "arcpp": generate_archive_record_cpp,
    "qcpp": generate_quantised_cpp,
}


def _wire_output(rel: str) -> Callable[[], str]:
    return lambda: wiregen.outputs()[rel]


def _model_output(key: str) -> Callable[[], str]:
    return lambda: model_typegen.GENERATORS[key](load_schema())


# The metamodel's own outputs (modd_model.typegen: model types, docs/metamodel.md),
# so that this one command writes every generated file.
for _key, _path in model_typegen.OUTPUTS.items():
    OUTPUTS[f"model:{_key}"] = _path
    GENERATORS[f"model:{_key}"] = _model_output(_key)


# The wire contract's headers and modules (wiregen.py), one key each.
for _rel in wiregen.outputs():
    OUTPUTS[f"wire:{_rel}"] = REPO / _rel
    GENERATORS[f"wire:{_rel}"] = _wire_output(_rel)


def stale_outputs() -> list[Path]:
    return [
        path
        for key, path in OUTPUTS.items()
        if not path.is_file() or path.read_text(encoding="utf-8") != GENERATORS[key]()
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--check", action="store_true", help="exit 1 if an output is stale")
    args = parser.parse_args(argv)
    if args.check:
        stale = stale_outputs()
        for p in stale:
            print(
                f"stale: {p.relative_to(REPO)} (run python -m modd_contracts.typegen)",
                file=sys.stderr,
            )
        return 1 if stale else 0
    for key, path in OUTPUTS.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(GENERATORS[key](), encoding="utf-8")
        print(f"wrote {path.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
