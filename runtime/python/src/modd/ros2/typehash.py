"""REP-2016 type hashes (``RIHS01_<sha256>``) of message types made of
primitive fields and nested messages, computed from their type description as
``rosidl_generator_type_description`` does: the JSON of
``{"type_description", "referenced_type_descriptions"}`` with the field
types as ``type_description_interfaces/msg/FieldType`` ids, separators
``", "`` and ``": "``, hashed with SHA-256.

>>> type_hash(MessageType("std_msgs/msg/Float64", (Field("data", "float64"),)))
'RIHS01_705ba9c3d1a09df43737eb67095534de36fd426c0587779bda2bc51fe790182a'
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

#: type_description_interfaces/msg/FieldType ids of the primitive types.
FIELD_TYPE_IDS: dict[str, int] = {
    "int8": 2,
    "uint8": 3,
    "int16": 4,
    "uint16": 5,
    "int32": 6,
    "uint32": 7,
    "int64": 8,
    "uint64": 9,
    "float32": 10,
    "float64": 11,
    "char": 13,
    "bool": 15,
    "byte": 16,
    "string": 17,
}
NESTED_TYPE = 1
#: Added to a type's id for an unbounded sequence (``float64[]``), as in FieldType.
UNBOUNDED_SEQUENCE = 144


@dataclass(frozen=True)
class Field:
    """A field: a primitive type name (``float64``), an unbounded sequence of
    one (``float64[]``) or a message type (``builtin_interfaces/msg/Time``)."""

    name: str
    type: str


@dataclass(frozen=True)
class MessageType:
    name: str  # e.g. "std_msgs/msg/Float64"
    fields: tuple[Field, ...]


def _field(f: Field) -> dict[str, Any]:
    if f.type.endswith("[]") and f.type[:-2] in FIELD_TYPE_IDS:
        type_id, nested = FIELD_TYPE_IDS[f.type[:-2]] + UNBOUNDED_SEQUENCE, ""
    elif f.type in FIELD_TYPE_IDS:
        type_id, nested = FIELD_TYPE_IDS[f.type], ""
    elif f.type.count("/") == 2:
        type_id, nested = NESTED_TYPE, f.type
    else:
        raise ValueError(f"field {f.name}: unsupported type {f.type!r}")
    return {
        "name": f.name,
        "type": {
            "type_id": type_id,
            "capacity": 0,
            "string_capacity": 0,
            "nested_type_name": nested,
        },
    }


def _description(t: MessageType) -> dict[str, Any]:
    return {"type_name": t.name, "fields": [_field(f) for f in t.fields]}


def type_hash(t: MessageType, referenced: Sequence[MessageType] = ()) -> str:
    """``RIHS01_`` + SHA-256 of the type description; ``referenced`` holds
    every nested type (recursively), in any order."""
    known = {r.name: r for r in referenced}
    needed: dict[str, MessageType] = {}
    stack = [t]
    while stack:
        for f in stack.pop().fields:
            if f.type.removesuffix("[]") not in FIELD_TYPE_IDS and f.type not in needed:
                if f.type not in known:
                    raise ValueError(f"{t.name}: the description of {f.type} is missing")
                needed[f.type] = known[f.type]
                stack.append(known[f.type])
    doc = {
        "type_description": _description(t),
        "referenced_type_descriptions": [_description(needed[n]) for n in sorted(needed)],
    }
    text = json.dumps(doc, separators=(", ", ": "), ensure_ascii=True)
    return "RIHS01_" + hashlib.sha256(text.encode()).hexdigest()
