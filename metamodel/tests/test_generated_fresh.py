"""Types and the metamodel reference are generated from the schema; they must
not drift from it."""

from __future__ import annotations

from modd_model import typegen
from modd_model.schema import load_schema


def test_generated_files_are_up_to_date() -> None:
    stale = typegen.stale_outputs()
    assert not stale, f"stale: {stale}; run .venv/bin/python -m modd_model.typegen"


def test_every_property_has_a_description() -> None:
    def walk(node: object, path: str) -> None:
        if isinstance(node, dict):
            for name, prop in node.get("properties", {}).items():
                assert "description" in prop, f"{path}/properties/{name} has no description"
            for key, value in node.items():
                walk(value, f"{path}/{key}")
        elif isinstance(node, list):
            for i, value in enumerate(node):
                walk(value, f"{path}/{i}")

    walk(load_schema(), "#")


def test_typescript_mentions_every_definition() -> None:
    ts = typegen.generate_ts(load_schema())
    for name in load_schema()["$defs"]:
        assert f" {name} " in ts or f" {name}=" in ts or f"{name} {{" in ts
