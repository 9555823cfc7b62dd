"""The schema's size bounds, checked before anything else reads a model:
a list past its ``maxItems`` (or an object past its ``maxProperties``) is
reported at its JSON pointer without validating the rest, so an oversized
document costs time in proportion to the bounds, not to its size.

>>> size_errors({"subscribers": [{}] * 50001})[0].pointer
'/subscribers'
"""

from __future__ import annotations

from functools import cache
from typing import Any

from .diagnostics import Diagnostic, pointer_join
from .schema import load_schema

#: (path of keys, "*" for every item of a list or value of an object; bound; what)
Bound = tuple[tuple[str, ...], int, str]


@cache
def schema_bounds() -> tuple[Bound, ...]:
    """Every ``maxItems`` / ``maxProperties`` of the schema, by path."""
    schema = load_schema()
    found: list[Bound] = []

    def resolve(node: dict[str, Any]) -> dict[str, Any]:
        while "$ref" in node:
            target: Any = schema
            for part in node["$ref"].removeprefix("#/").split("/"):
                target = target[part]
            node = target
        return node

    def walk(node: dict[str, Any], path: tuple[str, ...], depth: int) -> None:
        node = resolve(node)
        if depth > 16:
            return
        if "maxItems" in node:
            found.append((path, int(node["maxItems"]), "items"))
        if "maxProperties" in node:
            found.append((path, int(node["maxProperties"]), "properties"))
        if isinstance(node.get("items"), dict):
            walk(node["items"], (*path, "*"), depth + 1)
        for name, sub in node.get("properties", {}).items():
            walk(sub, (*path, name), depth + 1)
        if isinstance(node.get("additionalProperties"), dict):
            walk(node["additionalProperties"], (*path, "*"), depth + 1)

    walk(schema, (), 0)
    return tuple(found)


def _at(
    doc: Any, path: tuple[str, ...], where: tuple[str | int, ...] = ()
) -> list[tuple[tuple[str | int, ...], Any]]:
    if not path:
        return [(where, doc)]
    head, rest = path[0], path[1:]
    out: list[tuple[tuple[str | int, ...], Any]] = []
    if head == "*":
        if isinstance(doc, list):
            for i, item in enumerate(doc):
                out += _at(item, rest, (*where, i))
        elif isinstance(doc, dict):
            for key, item in doc.items():
                out += _at(item, rest, (*where, key))
    elif isinstance(doc, dict) and head in doc:
        out += _at(doc[head], rest, (*where, head))
    return out


def size_errors(doc: Any) -> list[Diagnostic]:
    """Lists and objects of ``doc`` past the schema's bounds."""
    out: list[Diagnostic] = []
    for path, limit, what in schema_bounds():
        for where, value in _at(doc, path):
            if isinstance(value, list | dict) and len(value) > limit:
                out.append(
                    Diagnostic(
                        f"{len(value):,} {what}: at most {limit:,} are allowed here (is too long)",
                        pointer_join(*where),
                    )
                )
    return out
