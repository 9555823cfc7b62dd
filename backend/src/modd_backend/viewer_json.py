"""JSON schemas and messages in the form Foxglove's and Lichtblick's viewers
read, which every message also validates against.

The viewers' JSON-schema reader (``parseJsonSchema``, packages/mcap-support)
takes one ``type`` per field and drops a channel whose schema has a list of
types such as ``["number", "null"]``. So a field that may be null is declared
with its one non-null type and a null is not sent: the field is left out of
the message (a JSON Schema property is optional unless required).

>>> s = for_viewers({"type": "object", "required": ["a", "b"], "properties": {
...     "a": {"anyOf": [{"type": "number"}, {"type": "null"}]}, "b": {"enum": ["x"]}}})
>>> s["properties"], s["required"]
({'a': {'type': 'number'}, 'b': {'enum': ['x'], 'type': 'string'}}, ['b'])
>>> without_nulls({"a": None, "b": {"c": None, "d": 1}, "e": [None, 2]})
{'b': {'d': 1}, 'e': [2]}
"""

from __future__ import annotations

from typing import Any

from modd_contracts import aggregations_gen as agg

#: Keywords kept from a contract schema (the rest is its own bookkeeping).
_KEPT = ("title", "description", "enum", "const")
_JSON_TYPES = {bool: "boolean", int: "integer", float: "number", str: "string"}


def for_viewers(schema: dict[str, Any], root: dict[str, Any] | None = None) -> dict[str, Any]:
    """``schema`` (a contract's, draft 2020-12) with its ``$ref`` inlined,
    each nullable field given its one non-null type, and the nullable fields
    out of ``required``."""
    root = schema if root is None else root
    node = _one_type(_resolve(schema, root), root)
    out: dict[str, Any] = {k: node[k] for k in _KEPT if k in node}
    kind = node.get("type")
    if kind is None and isinstance(node.get("enum"), list) and node["enum"]:
        kind = _JSON_TYPES.get(type(node["enum"][0]))
    if kind is None and "const" in node:  # a one-value field (e.g. a status's "GAVE_UP")
        kind = _JSON_TYPES.get(type(node["const"]))
    if kind is not None:
        out["type"] = kind
    if kind == "object":
        props = node.get("properties") or {}
        out["properties"] = {n: for_viewers(p, root) for n, p in props.items()}
        extra = node.get("additionalProperties")
        if isinstance(extra, dict):
            out["additionalProperties"] = for_viewers(extra, root)
        elif extra is False:
            out["additionalProperties"] = False
        required = [n for n in node.get("required", []) if not _nullable(props.get(n), root)]
        if required:
            out["required"] = required
    elif kind == "array" and isinstance(node.get("items"), dict):
        out["items"] = for_viewers(node["items"], root)
    return out


def _resolve(node: dict[str, Any], root: dict[str, Any]) -> dict[str, Any]:
    ref = node.get("$ref")
    if not isinstance(ref, str):
        return node
    if not ref.startswith("#/$defs/"):
        raise ValueError(f"{ref}: only local $defs references are inlined")
    target: dict[str, Any] = root["$defs"][ref.removeprefix("#/$defs/")]
    return {**target, **{k: v for k, v in node.items() if k != "$ref"}}


def _one_type(node: dict[str, Any], root: dict[str, Any]) -> dict[str, Any]:
    """``node`` without its null alternative (``anyOf`` or a list of types)."""
    alternatives = node.get("anyOf")
    if isinstance(alternatives, list):
        rest = [a for a in alternatives if a.get("type") != "null"]
        if len(rest) != 1:
            raise ValueError(f"{node.get('description', node)}: more than one non-null type")
        merged = {**_resolve(rest[0], root), **{k: v for k, v in node.items() if k != "anyOf"}}
        return _one_type(merged, root)
    kind = node.get("type")
    if isinstance(kind, list):
        rest = [k for k in kind if k != "null"]
        if len(rest) != 1:
            raise ValueError(f"{node.get('description', node)}: more than one non-null type")
        return {**node, "type": rest[0]}
    return node


def _nullable(node: dict[str, Any] | None, root: dict[str, Any]) -> bool:
    if node is None:
        return False
    node = _resolve(node, root)
    kind = node.get("type")
    if isinstance(kind, list):
        return "null" in kind
    return any(a.get("type") == "null" for a in node.get("anyOf", []))


def as_numbers(value: Any) -> Any:
    """A value as a schema's number (or array of numbers): a boolean as 1/0."""
    if isinstance(value, list):
        return [as_numbers(v) for v in value]
    return int(value) if isinstance(value, bool) else value


def delivered_schema(aggregation: str) -> dict[str, Any]:
    """The delivered-value contract's schema as the viewers read it, for one
    subscriber: ``value`` an array of numbers for ``ALL``, a number otherwise
    (true/false as 1/0, absent for an empty window)."""
    from modd_contracts.schema import load

    contract = load("delivered_value")
    value = (
        {"type": "array", "items": {"type": "number"}}
        if aggregation == agg.ALL
        else {"type": "number"}
    )
    props = {**contract["properties"], "value": {**value, "description": "the window's value"}}
    schema = for_viewers({**contract, "properties": props})
    schema["required"] = [r for r in schema.get("required", []) if r != "value"]
    return schema


def without_nulls(doc: Any) -> Any:
    """``doc`` with every null left out, at any depth (object members, array items)."""
    if isinstance(doc, dict):
        return {k: without_nulls(v) for k, v in doc.items() if v is not None}
    if isinstance(doc, list):
        return [without_nulls(v) for v in doc if v is not None]
    return doc
