"""The archive record (contract ``archive_record``, contracts/vectors/
archive_record.json) decoded: each MCAP message of a MoDD archive is
``{"value":X}`` on a channel whose schema is ``modd.<type>``.

Decoding is vectorised per chunk: the number text between the fixed prefix
and the closing brace is handed to NumPy in one call, which also reads the
``nan``/``inf`` words the C++ writer uses for non-finite floats. A message not
in that compact form is read with ``json`` (whitespace is allowed by JSON).

>>> decode_values("float64", [b'{"value":1.5}', b'{"value":nan}', b'{ "value" : 2 }'])
array([1.5, nan, 2. ])
>>> decode_values("bool", [b'{"value":true}', b'{"value":false}'])
array([1, 0], dtype=int8)
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from modd_contracts.schema import load

_CONTRACT = load("archive_record")
FIELD: str = next(iter(_CONTRACT["properties"]))
SCHEMA_PREFIX: str = _CONTRACT["x-schema-prefix"]
TYPE_KEY: str = _CONTRACT["x-type-metadata-key"]
VALUE_TYPES: tuple[str, ...] = tuple(_CONTRACT["x-channel-schemas"])
_PREFIX = b'{"' + FIELD.encode() + b'":'
#: How samples are held while exported: float32 samples as the float64 of
#: their archived text (0.009 stays 0.009 in CSV and Parquet; NetCDF stores
#: them as float32, STORAGE), bool as 0/1.
_DTYPES = {"float32": np.float64, "float64": np.float64, "int": np.int64, "bool": np.int8}
STORAGE = {"float32": np.float32, "float64": np.float64, "int": np.int64, "bool": np.int8}
_WORDS = {"nan": float("nan"), "inf": float("inf"), "-inf": float("-inf")}


class RecordError(ValueError):
    """A message that is not an archive record of its channel's type."""


def dtype_of(value_type: str) -> Any:
    """The NumPy dtype a topic of ``value_type`` is stored in (bool as 0/1 int8)."""
    return STORAGE[value_type]


def channel_type(schema_name: str, metadata: dict[str, str]) -> str | None:
    """The value type of a channel (schema ``modd.<type>``, or its metadata);
    None for a channel that is not a MoDD topic."""
    if schema_name.startswith(SCHEMA_PREFIX) and schema_name[len(SCHEMA_PREFIX):] in VALUE_TYPES:
        return schema_name[len(SCHEMA_PREFIX):]
    t = metadata.get(TYPE_KEY)
    return t if t in VALUE_TYPES else None


def _slow(value_type: str, data: bytes) -> Any:
    text = data.decode("utf-8", "replace")
    body = text.strip()
    inner = body[len(_PREFIX):-1].strip() if body.startswith(_PREFIX.decode()) else ""
    if inner in _WORDS:
        return _WORDS[inner]
    try:
        doc = json.loads(text)
        value = doc[FIELD]
    except (ValueError, KeyError, TypeError):
        raise RecordError(f"not an archive record: {text[:60]!r}") from None
    if value_type == "bool" and not isinstance(value, bool):
        raise RecordError(f"not a bool record: {text[:60]!r}")
    if value_type != "bool" and (isinstance(value, bool) or not isinstance(value, int | float)):
        raise RecordError(f"not a {value_type} record: {text[:60]!r}")
    return value


def decode_values(value_type: str, datas: list[bytes]) -> np.ndarray:
    """The samples of ``datas`` (message data of one channel) as an array."""
    dtype = _DTYPES[value_type]
    n = len(_PREFIX)
    try:
        if not all(d.startswith(_PREFIX) and d.endswith(b"}") for d in datas):
            raise ValueError
        texts = np.array([d[n:-1] for d in datas], dtype=bytes)
        if value_type == "bool":
            true, false = texts == b"true", texts == b"false"
            if not np.all(true | false):
                raise ValueError
            return true.astype(np.int8)
        return texts.astype(dtype)
    except ValueError:
        return np.array([_slow(value_type, d) for d in datas], dtype=dtype)
