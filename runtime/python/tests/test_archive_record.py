"""The archive record contract (contracts/vectors/archive_record.json): the
vectors are what the schema says, and the Python readers (``modd dataset``'s
decoder, the backend's archive reader) read every one; the C++ writer and
reader are held to the same vectors by runtime/cpp/tests/test_contracts.cpp."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from modd.dataset.record import decode_values
from modd_backend.archives import _value as backend_value
from modd_contracts.archive_record import SCHEMA_PREFIX, channel_type, value_of
from modd_contracts.schema import load, validate

VECTORS = json.loads(
    (
        Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "archive_record.json"
    ).read_text()
)


def _same(got: Any, want: Any) -> bool:
    if isinstance(want, str):  # nan, inf, -inf
        return math.isnan(got) if want == "nan" else got == float(want)
    return bool(got == want)


def test_channels_are_the_contracts() -> None:
    schemas = load("archive_record")["x-channel-schemas"]
    assert [c["type"] for c in VECTORS["channels"]] == list(schemas)
    for c in VECTORS["channels"]:
        assert c["schema_data"] == json.dumps(schemas[c["type"]], separators=(",", ":"))
        assert c["schema_name"] == SCHEMA_PREFIX + c["type"]
        assert channel_type(c["schema_name"], {}) == c["type"]
        assert channel_type("other", c["metadata"]) == c["type"]


def test_every_record_conforms_and_is_read_back() -> None:
    for r in VECTORS["records"]:
        data = r["data"].encode()
        if not isinstance(r["value"], str):  # the non-finite words are not JSON
            assert validate("archive_record", json.loads(data)) == [], r["name"]
        (got,) = decode_values(r["type"], [data]).tolist()
        want = r["value"]
        assert _same(got, int(want) if r["type"] == "bool" else want), r["name"]
        assert _same(value_of(data), want), r["name"]
        assert _same(backend_value(data), want), r["name"]
