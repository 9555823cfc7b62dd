"""The archive record (``schemas/archive_record.schema.json``) as Python reads
it: the constants of the contract and one record's value. Standard library
only (every process may import it); ``modd.dataset.record`` decodes whole
chunks with NumPy on top of these.

>>> value_of(b'{"value":-inf}'), value_of(b'{"value":true}'), value_of(b'[]')
(-inf, True, None)
>>> SCHEMA_PREFIX + "float32"
'modd.float32'
"""

from __future__ import annotations

import json
from typing import Any

from .schema import load

_CONTRACT = load("archive_record")
#: The one field of a record (``{"value": ...}``).
FIELD: str = next(iter(_CONTRACT["properties"]))
#: A channel's schema is named SCHEMA_PREFIX + its value type.
SCHEMA_PREFIX: str = _CONTRACT["x-schema-prefix"]
#: The channel metadata key that holds the value type.
TYPE_KEY: str = _CONTRACT["x-type-metadata-key"]
#: The value types, each with its channel schema.
CHANNEL_SCHEMAS: dict[str, Any] = _CONTRACT["x-channel-schemas"]
VALUE_TYPES: tuple[str, ...] = tuple(CHANNEL_SCHEMAS)
#: The compact form's bytes before the value, and the words for non-finite floats.
PREFIX = b'{"' + FIELD.encode() + b'":'
NON_FINITE = {"nan": float("nan"), "inf": float("inf"), "-inf": float("-inf")}


def channel_type(schema_name: str, metadata: dict[str, str]) -> str | None:
    """The value type of a channel (schema ``modd.<type>``, or its metadata);
    None for a channel that is not a MoDD topic."""
    if schema_name.startswith(SCHEMA_PREFIX) and schema_name[len(SCHEMA_PREFIX) :] in VALUE_TYPES:
        return schema_name[len(SCHEMA_PREFIX) :]
    t = metadata.get(TYPE_KEY)
    return t if t in VALUE_TYPES else None


def value_of(data: bytes) -> Any:
    """One record's value whatever its channel's type (None when it is not a record)."""
    text = data.decode("utf-8", "replace").strip()
    if text.startswith(PREFIX.decode()) and text[len(PREFIX) : -1].strip() in NON_FINITE:
        return NON_FINITE[text[len(PREFIX) : -1].strip()]
    try:
        doc = json.loads(text)
    except ValueError:
        return None
    return doc.get(FIELD) if isinstance(doc, dict) else None
