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

from typing import Any

import numpy as np
from modd_contracts.archive_record import PREFIX, value_of

#: How samples are held while exported: float32 samples as the float64 of
#: their archived text (0.009 stays 0.009 in CSV and Parquet; NetCDF stores
#: them as float32, STORAGE), bool as 0/1.
_DTYPES = {"float32": np.float64, "float64": np.float64, "int": np.int64, "bool": np.int8}
STORAGE = {"float32": np.float32, "float64": np.float64, "int": np.int64, "bool": np.int8}


class RecordError(ValueError):
    """A message that is not an archive record of its channel's type."""


def dtype_of(value_type: str) -> Any:
    """The NumPy dtype a topic of ``value_type`` is stored in (bool as 0/1 int8)."""
    return STORAGE[value_type]


def _slow(value_type: str, data: bytes) -> Any:
    value = value_of(data)
    text = data.decode("utf-8", "replace")
    if value is None:
        raise RecordError(f"not an archive record: {text[:60]!r}")
    if value_type == "bool" and not isinstance(value, bool):
        raise RecordError(f"not a bool record: {text[:60]!r}")
    if value_type != "bool" and (isinstance(value, bool) or not isinstance(value, int | float)):
        raise RecordError(f"not a {value_type} record: {text[:60]!r}")
    return value


def decode_texts(value_type: str, texts: np.ndarray) -> np.ndarray:
    """The samples of value texts (what stands between the prefix and ``}``)."""
    try:
        if value_type == "bool":
            true, false = texts == b"true", texts == b"false"
            if not np.all(true | false):
                raise ValueError
            flags: np.ndarray = true.astype(np.int8)
            return flags
        out: np.ndarray = texts.astype(_DTYPES[value_type])
        return out
    except ValueError:
        datas = [PREFIX + bytes(t) + b"}" for t in texts.tolist()]
        slow: np.ndarray = np.array([_slow(value_type, d) for d in datas], _DTYPES[value_type])
        return slow


def decode_values(value_type: str, datas: list[bytes]) -> np.ndarray:
    """The samples of ``datas`` (message data of one channel) as an array."""
    n = len(PREFIX)
    if all(d.startswith(PREFIX) and d.endswith(b"}") for d in datas):
        return decode_texts(value_type, np.array([d[n:-1] for d in datas], dtype=bytes))
    slow: np.ndarray = np.array([_slow(value_type, d) for d in datas], _DTYPES[value_type])
    return slow
