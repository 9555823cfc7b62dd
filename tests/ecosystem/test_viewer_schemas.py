"""Every JSON schema MoDD gives Foxglove and Lichtblick is one their reader
accepts (viewer_schema.py: the rules of Lichtblick's parseJsonSchema)."""

from __future__ import annotations

import json

from modd.subbroker import record
from modd_backend.foxglove import LINK_SCHEMA, LOCATION_SCHEMA, window_schema
from viewer_schema import refusals


def test_the_rules_refuse_what_lichtblick_refused() -> None:
    # the first schemas: Lichtblick 1.28 said "Unsupported type [...] for value"
    old = {"type": "object", "properties": {
        "value": {"type": ["number", "boolean", "array", "null"]},
        "t": {"type": "object", "properties": {"sec": {"type": "integer"}}},
        "rtt_s": {"type": ["number", "null"]}, "untyped": {},
        "list": {"type": "array", "items": {"type": "null"}}}}
    assert refusals(old) == [
        "value: unsupported type ['number', 'boolean', 'array', 'null']",
        "rtt_s: unsupported type ['number', 'null']",
        "untyped: unsupported type None",
        "list: unsupported type 'null' for array items"]
    assert refusals({"type": "array"}) == ["<root>: expected \"type\": \"object\", got 'array'"]
    nested = {"type": "object", "properties": {"fix": {"type": "object", "properties": {
        "lat": {"type": ["number", "null"]}}}}}
    assert refusals(nested) == ["fix.lat: unsupported type ['number', 'null']"]


def test_every_schema_modd_serves_is_read_by_the_viewers() -> None:
    schemas = {"window": window_schema("AVERAGE"), "window ALL": window_schema("ALL"),
               "link": LINK_SCHEMA, "position": LOCATION_SCHEMA,
               "base-station record": json.loads(record._SCHEMA)}
    for archive_type in ("number", "integer", "boolean"):  # the PubBroker's archive.cpp
        schemas[f"archive {archive_type}"] = {
            "type": "object", "properties": {"value": {"type": archive_type}},
            "required": ["value"]}
    for name, schema in schemas.items():
        assert not refusals(schema), (name, refusals(schema))
    assert window_schema("ALL")["properties"]["value"]["items"] == {"type": "number"}
