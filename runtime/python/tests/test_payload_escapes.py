"""Delivered values JSON cannot hold (docs/protocol.md, "Values JSON cannot hold"): a SUM
beyond the double range and ``inf − inf`` travel as the strings "Infinity", "-Infinity"
and "NaN", never as bare tokens a strict JSON reader refuses."""

from __future__ import annotations

import json
import math

import pytest
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd_plan.derive import derive_value


def _strict(raw: bytes) -> dict[str, object]:
    def refuse(token: str) -> object:
        raise ValueError(f"bare {token} in JSON")

    doc = json.loads(raw, parse_constant=refuse)
    assert isinstance(doc, dict)
    return doc


@pytest.mark.parametrize(
    ("value", "escaped"),
    [
        (derive_value("SUM", [("ALL", [[1e308, 1e308]])]), "Infinity"),
        (derive_value("SUM", [("SUM", [-1e308, -1e308])]), "-Infinity"),
        (derive_value("SUM", [("SUM", [math.inf, -math.inf])]), "NaN"),
        ([1.0, math.inf, 2.0], [1.0, "Infinity", 2.0]),
    ],
)
def test_a_value_json_cannot_hold_travels_as_its_escape(value: object, escaped: object) -> None:
    head = StreamPayload("usv.a.x", "SUM", "2", "METER", 1)
    raw = subscriber_prefix("s") + head.tail(7, 0, 2_000_000_000, value, None, 5)  # type: ignore[arg-type]
    assert _strict(raw)["value"] == escaped
    back = DeliveredValue.from_json(raw)
    assert back.to_json() == raw
    got = back.value if isinstance(back.value, list) else [back.value]
    want = value if isinstance(value, list) else [value]
    assert [str(x) for x in got] == [str(x) for x in want]
