"""Every JSON schema MoDD gives Foxglove and Lichtblick is one their reader
accepts (viewer_schema.py: the rules of Lichtblick's parseJsonSchema)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from jsonschema import Draft202012Validator
from modd.subbroker import record
from modd_backend.foxglove import LINK_SCHEMA, LOCATION_SCHEMA, window_message, window_schema
from modd_backend.viewer_json import without_nulls
from modd_contracts.delivered import as_delivered
from modd_contracts.schema import load as contract_schema
from viewer_schema import refusals

VECTORS = Path(__file__).resolve().parents[2] / "contracts" / "vectors"


def violations(schema: dict[str, Any], message: Any) -> list[str]:
    """What a JSON Schema validator (``jsonschema``, draft 2020-12) finds wrong."""
    Draft202012Validator.check_schema(schema)
    return [
        f"/{'/'.join(map(str, e.absolute_path))}: {e.message}"
        for e in Draft202012Validator(schema).iter_errors(message)
    ]


def declared(schema: dict[str, Any], path: str = "") -> set[str]:
    """Every field path a schema declares, nested objects included."""
    out: set[str] = set()
    for name, field in (schema.get("properties") or {}).items():
        out.add(f"{path}{name}")
        if "anyOf" in field:
            field = next(a for a in field["anyOf"] if a.get("type") != "null")
        if "$ref" in field:
            field = contract_schema("status")["$defs"][field["$ref"].rsplit("/", 1)[-1]]
        out |= declared(field, f"{path}{name}.")
    return out


def test_every_window_message_is_valid_against_its_schema() -> None:
    """Each delivered-value vector (an empty window, an ALL window, a boolean
    LAST, MIN/MAX without count...) as the live server sends it."""
    for vector in json.loads((VECTORS / "delivered_value.json").read_text())["vectors"]:
        doc = json.loads(vector["line"])
        msg = window_message(doc)
        assert violations(window_schema(doc["aggregation"]), msg) == [], vector["name"]
    doc = as_delivered({"value": None, "count": None, "aggregation": "MIN", "end_ns": 1})
    assert doc is not None
    empty = window_message(doc)
    assert "value" not in empty and "count" not in empty  # left out, not null


def test_the_link_status_declares_every_field_and_its_messages_are_valid() -> None:
    """The status contract's fields are the link schema's (it declared 7 of
    33), and every status vector, as sent, validates against it."""
    assert declared(LINK_SCHEMA) == declared(contract_schema("status"))
    for vector in json.loads((VECTORS / "status.json").read_text())["vectors"]:
        assert violations(LINK_SCHEMA, without_nulls(vector["document"])) == [], vector["name"]
        # with its nulls, the document breaks the viewers' one-type schema
        if any(v is None for v in vector["document"].values()):
            assert violations(LINK_SCHEMA, vector["document"])


def test_the_rules_refuse_what_lichtblick_refused() -> None:
    # the first schemas: Lichtblick 1.28 said "Unsupported type [...] for value"
    old = {
        "type": "object",
        "properties": {
            "value": {"type": ["number", "boolean", "array", "null"]},
            "t": {"type": "object", "properties": {"sec": {"type": "integer"}}},
            "rtt_s": {"type": ["number", "null"]},
            "untyped": {},
            "list": {"type": "array", "items": {"type": "null"}},
        },
    }
    assert refusals(old) == [
        "value: unsupported type ['number', 'boolean', 'array', 'null']",
        "rtt_s: unsupported type ['number', 'null']",
        "untyped: unsupported type None",
        "list: unsupported type 'null' for array items",
    ]
    assert refusals({"type": "array"}) == ['<root>: expected "type": "object", got \'array\'']
    nested = {
        "type": "object",
        "properties": {
            "fix": {"type": "object", "properties": {"lat": {"type": ["number", "null"]}}}
        },
    }
    assert refusals(nested) == ["fix.lat: unsupported type ['number', 'null']"]


def test_every_schema_modd_serves_is_read_by_the_viewers() -> None:
    schemas = {
        "window": window_schema("AVERAGE"),
        "window ALL": window_schema("ALL"),
        "link": LINK_SCHEMA,
        "position": LOCATION_SCHEMA,
        "base-station record": json.loads(record._SCHEMA),
    }
    for archive_type in ("number", "integer", "boolean"):  # the PubBroker's archive.cpp
        schemas[f"archive {archive_type}"] = {
            "type": "object",
            "properties": {"value": {"type": archive_type}},
            "required": ["value"],
        }
    for name, schema in schemas.items():
        assert not refusals(schema), (name, refusals(schema))
    assert window_schema("ALL")["properties"]["value"]["items"] == {"type": "number"}
