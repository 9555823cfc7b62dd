"""Types and reference docs generated from the JSON Schema, so that nothing
re-types the metamodel by hand:

- ``frontend/src/core/model.gen.ts``: TypeScript types for the workbench;
- ``metamodel/src/modd_model/types_gen.py``: Python TypedDicts;
- ``docs/metamodel.md``: the metamodel reference.

Run ``python -m modd_model.typegen`` to rewrite them; ``--check`` exits 1 when
one is stale (the test suite does that). Handles the subset of JSON Schema the
metamodel uses: objects, arrays, enums, const, $ref, anyOf, string/number/
integer/boolean."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .schema import load_schema

HEADER = (
    "Generated from metamodel/modd.schema.json by `python -m modd_contracts.typegen`. Do not edit."
)
REPO = Path(__file__).resolve().parents[3]
OUTPUTS = {
    "ts": REPO / "frontend" / "src" / "core" / "model.gen.ts",
    "py": REPO / "metamodel" / "src" / "modd_model" / "types_gen.py",
    "md": REPO / "docs" / "metamodel.md",
}
ROOT_NAME = "ModdModel"


def _ref_name(ref: str) -> str:
    return ref.rsplit("/", 1)[-1]


def _definitions(schema: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    root = {k: v for k, v in schema.items() if k != "$defs"}
    return [(ROOT_NAME, root), *schema["$defs"].items()]


# -- TypeScript ---------------------------------------------------------------


def _ts_type(s: dict[str, Any]) -> str:
    if "$ref" in s:
        return _ref_name(s["$ref"])
    if "const" in s:
        return f'"{s["const"]}"'
    if "enum" in s:
        return " | ".join(f'"{v}"' for v in s["enum"])
    if "anyOf" in s:
        return " | ".join(_ts_type(x) for x in s["anyOf"])
    t = s.get("type")
    if t == "array":
        inner = _ts_type(s["items"])
        return f"({inner})[]" if "|" in inner else f"{inner}[]"
    if t == "object" and "properties" not in s:
        extra = s.get("additionalProperties")
        return f"Record<string, {_ts_type(extra)}>" if isinstance(extra, dict) else "object"
    return {
        "string": "string",
        "integer": "number",
        "number": "number",
        "boolean": "boolean",
        "null": "null",
    }.get(str(t), "unknown")


def _ts_doc(text: str | None, indent: str = "") -> list[str]:
    return [f"{indent}/** {text} */"] if text else []


def generate_ts(schema: dict[str, Any]) -> str:
    out = [f"// {HEADER}", ""]
    for name, s in _definitions(schema):
        out += _ts_doc(s.get("description"))
        if s.get("type") == "object" and "properties" in s:
            out.append(f"export interface {name} {{")
            required = set(s.get("required", []))
            for prop, ps in s["properties"].items():
                out += _ts_doc(ps.get("description"), "  ")
                opt = "" if prop in required else "?"
                out.append(f"  {prop}{opt}: {_ts_type(ps)};")
            out.append("}")
        else:
            out.append(f"export type {name} = {_ts_type(s)};")
        if "enum" in s:
            values = ", ".join(f'"{v}"' for v in s["enum"])
            out.append(f"export const {name}Values = [{values}] as const;")
        out.append("")
    return "\n".join(out)


# -- Python ---------------------------------------------------------------------


def _py_type(s: dict[str, Any]) -> str:
    if "$ref" in s:
        return _ref_name(s["$ref"])
    if "const" in s:
        return f'Literal["{s["const"]}"]'
    if "enum" in s:
        return "Literal[" + ", ".join(f'"{v}"' for v in s["enum"]) + "]"
    if "anyOf" in s:
        return " | ".join(_py_type(x) for x in s["anyOf"])
    t = s.get("type")
    if t == "array":
        return f"list[{_py_type(s['items'])}]"
    if t == "object" and "properties" not in s:
        extra = s.get("additionalProperties")
        return f"dict[str, {_py_type(extra)}]" if isinstance(extra, dict) else "dict[str, Any]"
    return {
        "string": "str",
        "integer": "int",
        "number": "float",
        "boolean": "bool",
        "null": "None",
    }.get(str(t), "Any")


def _refs(s: Any) -> set[str]:
    if isinstance(s, dict):
        found = {_ref_name(s["$ref"])} if "$ref" in s else set()
        for v in s.values():
            found |= _refs(v)
        return found
    if isinstance(s, list):
        return set().union(*(_refs(v) for v in s)) if s else set()
    return set()


def _dependency_order(items: list[tuple[str, dict[str, Any]]]) -> list[tuple[str, dict[str, Any]]]:
    """Aliases ordered so that each is defined after those it refers to."""
    pending, done, out = dict(items), set[str](), []
    while pending:
        for name, s in list(pending.items()):
            if _refs(s) & set(pending) - {name} - done <= set():
                out.append((name, s))
                done.add(name)
                del pending[name]
    return out


def generate_py(schema: dict[str, Any]) -> str:
    out = [
        f'"""{HEADER}"""',
        "",
        "from __future__ import annotations",
        "",
        "from typing import Any, Literal, NotRequired, TypedDict",
        "",
        "",
    ]
    objects = [(n, s) for n, s in _definitions(schema) if "properties" in s]
    aliases = _dependency_order([(n, s) for n, s in _definitions(schema) if "properties" not in s])
    for name, s in aliases:
        out.append(f"{name} = {_py_type(s)}")
    out += ["", ""]
    for name, s in objects:
        required = set(s.get("required", []))
        out.append(f"class {name}(TypedDict):")
        out.append(f'    """{s.get("description", name)}"""')
        out.append("")
        for prop, ps in s["properties"].items():
            t = _py_type(ps)
            out.append(f"    {prop}: {t if prop in required else f'NotRequired[{t}]'}")
        out += ["", ""]
    out.append("__all__ = [" + ", ".join(f'"{n}"' for n, _ in _definitions(schema)) + "]")
    text = "\n".join(out) + "\n"
    if "Any]" not in text:
        text = text.replace("import Any, Literal", "import Literal")
    return text


# -- Markdown reference ------------------------------------------------------------


def _md_type(s: dict[str, Any]) -> str:
    if "$ref" in s:
        n = _ref_name(s["$ref"])
        return f"[{n}](#{n.lower()})"
    if "enum" in s:
        return "one of " + ", ".join(f"`{v}`" for v in s["enum"])
    if "anyOf" in s:
        return " or ".join(_md_type(x) for x in s["anyOf"])
    if "const" in s:
        return f'`"{s["const"]}"`'
    if s.get("type") == "array":
        return f"list of {_md_type(s['items'])}"
    if s.get("type") == "object" and isinstance(s.get("additionalProperties"), dict):
        return f"map of name to {_md_type(s['additionalProperties'])}"
    text = str(s.get("type", "any"))
    if "pattern" in s:
        text += f" matching `{s['pattern']}`"
    return text


def generate_md(schema: dict[str, Any]) -> str:
    out = [
        "# Metamodel reference",
        "",
        f"<!-- {HEADER} -->",
        "",
        schema["description"],
        "",
        "A model is a JSON document of this form; the `.modd` text (see "
        "[dsl.md](dsl.md)) is another notation for the same document.",
        "",
    ]
    for name, s in _definitions(schema):
        out += [f"## {name}", "", s.get("description", ""), ""]
        if "properties" in s:
            required = set(s.get("required", []))
            out += [
                "| property | type | required | default | description |",
                "| --- | --- | --- | --- | --- |",
            ]
            for prop, ps in s["properties"].items():
                default = f"`{ps['default']}`" if "default" in ps else ""
                req = "yes" if prop in required else ""
                desc = ps.get("description", "").replace("|", "\\|")
                out.append(f"| `{prop}` | {_md_type(ps)} | {req} | {default} | {desc} |")
        else:
            out.append(f"Type: {_md_type(s)}.")
        out += _md_sentences(s)
        out.append("")
    return "\n".join(out)


def _md_sentences(s: dict[str, Any]) -> list[str]:
    """The NMEA sentence table (``x-sentences``) as a table: fields in order, with kinds."""
    if "x-sentences" not in s:
        return []
    out = [
        "",
        s.get("x-sentences-doc", ""),
        "",
        "| sentence | fields (1, 2, ...: what each holds) |",
        "| --- | --- |",
    ]
    for sentence, fields in s["x-sentences"].items():
        cells = ", ".join(f"`{name}` {kind}" for name, kind in fields.items())
        out.append(f"| {sentence} | {cells} |")
    return out


GENERATORS = {"ts": generate_ts, "py": generate_py, "md": generate_md}


def stale_outputs() -> list[Path]:
    schema = load_schema()
    stale = []
    for key, path in OUTPUTS.items():
        text = GENERATORS[key](schema)
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            stale.append(path)
    return stale


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--check", action="store_true", help="exit 1 if an output is stale")
    args = parser.parse_args(argv)
    stale = stale_outputs()
    if args.check:
        for p in stale:
            print(
                f"stale: {p.relative_to(REPO)} (run python -m modd_model.typegen)", file=sys.stderr
            )
        return 1 if stale else 0
    schema = load_schema()
    for key, path in OUTPUTS.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(GENERATORS[key](schema), encoding="utf-8")
        print(f"wrote {path.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
