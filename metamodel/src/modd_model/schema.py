"""The JSON Schema (metamodel/modd.schema.json): the one source of truth for
what a model is. Loaded once; the vocabularies (units, types, aggregations)
used elsewhere are read from it, never re-typed."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

SCHEMA_FILE = "modd.schema.json"


def schema_path() -> Path:
    """The schema file: inside the installed package, or metamodel/ in a checkout."""
    here = Path(__file__).resolve().parent
    for candidate in (here / SCHEMA_FILE, here.parents[1] / SCHEMA_FILE):
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(f"{SCHEMA_FILE} not found beside {here}")


@cache
def load_schema() -> dict[str, Any]:
    with schema_path().open(encoding="utf-8") as f:
        schema: dict[str, Any] = json.load(f)
    return schema


def definition(name: str) -> dict[str, Any]:
    """A ``$defs`` entry of the schema."""
    d: dict[str, Any] = load_schema()["$defs"][name]
    return d
