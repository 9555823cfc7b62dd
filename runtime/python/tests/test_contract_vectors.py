"""The SubBroker writes the contracts' delivered values byte for byte
(contracts/vectors/delivered_value.json), and its link codec's aggregation
codes are the table's."""

from __future__ import annotations

import json
from dataclasses import fields
from pathlib import Path
from typing import Any, cast

from modd.link.frames import Aggregation
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.schema import load, validate, version
from modd_contracts.types_gen import DeliveredValueFields
from modd_plan.windows import Value

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"


def _vectors(name: str) -> list[dict[str, Any]]:
    data: dict[str, Any] = json.loads((VECTORS / f"{name}.json").read_text())
    cases: list[dict[str, Any]] = data["vectors"]
    return cases


def test_delivered_values_are_written_as_the_vectors() -> None:
    for case in _vectors("delivered_value"):
        line = case["line"].encode()
        doc = json.loads(line)
        assert validate("delivered_value", doc) == [], case["name"]
        v = DeliveredValue.from_json(line)
        assert v.to_json() == line, case["name"]
        head = StreamPayload(v.topic, v.aggregation, v.period_s, v.unit, v.config_id)
        value = cast(Value, v.value)  # read back: an escape string is a float again
        tail = head.tail(v.slot, v.start_ns, v.end_ns, value, v.count, v.delivered_ns)
        assert subscriber_prefix(v.subscriber) + tail == line, case["name"]


def test_payload_version_is_the_schemas() -> None:
    v = _vectors("delivered_value")[0]
    assert json.loads(v["line"])["v"] == version("delivered_value")


def test_link_codes_are_the_tables() -> None:
    assert {a.name: a.value for a in Aggregation} == {a.name: a.code for a in AGGREGATIONS}


def test_the_payload_object_declares_no_field_of_its_own() -> None:
    """DeliveredValue's fields are the generated record's, which are the
    schema's properties but the version ``v``: one definition."""
    assert fields(DeliveredValue) == fields(DeliveredValueFields)
    props = list(load("delivered_value")["properties"])
    assert [f.name for f in fields(DeliveredValue)] == [p for p in props if p != "v"]
