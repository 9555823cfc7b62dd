"""What Foxglove's and Lichtblick's JSON-schema reader accepts, field by field.

A port of the rules of ``parseJsonSchema`` (lichtblick-suite/lichtblick,
packages/mcap-support/src/parseJsonSchema.ts, read at 66adecb; the same code
as Foxglove Studio's): a channel whose schema it refuses is dropped by the
viewer ("Failed to parse channel schema on /topic"), its plots stay empty.
Seen in Lichtblick 1.28 on MoDD's first schemas, whose ``value`` was typed
``["number", "boolean", "array", "null"]``.
"""

from __future__ import annotations

from typing import Any

SCALARS = {"boolean", "number", "integer"}


def refusals(schema: Any, path: str = "") -> list[str]:
    """The reasons the viewer refuses ``schema`` (empty: it reads it)."""
    if not isinstance(schema, dict) or schema.get("type") != "object":
        got = schema.get("type") if isinstance(schema, dict) else schema
        return [f'{path or "<root>"}: expected "type": "object", got {got!r}']
    out: list[str] = []
    for name, field in (schema.get("properties") or {}).items():
        where = f"{path}.{name}" if path else name
        if isinstance(field.get("oneOf"), list):
            if not all(isinstance(a.get("const"), int | float) for a in field["oneOf"]):
                out.append(f"{where}: oneOf alternatives must have number values")
            continue
        kind = field.get("type")
        if isinstance(kind, str) and kind in SCALARS:
            continue
        if not isinstance(kind, str):  # a list of types, or none
            out.append(f"{where}: unsupported type {kind!r}")
        elif kind == "string":
            if field.get("contentEncoding") not in (None, "base64"):
                out.append(f"{where}: unsupported contentEncoding {field['contentEncoding']!r}")
        elif kind == "object":
            out += refusals(field, where)
        elif kind == "array":
            item = field.get("items") or {}
            ikind = item.get("type")
            if not isinstance(ikind, str):
                out.append(f"{where}: unsupported type {ikind!r} for array items")
            elif ikind == "object":
                out += refusals(item, where)
            elif ikind == "string" and item.get("contentEncoding") is not None:
                out.append(f"{where}: unsupported contentEncoding for array items")
            elif ikind not in SCALARS | {"string", "object"}:
                out.append(f"{where}: unsupported type {ikind!r} for array items")
        else:
            out.append(f"{where}: unsupported type {kind!r}")
    return out
