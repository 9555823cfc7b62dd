"""The contract schemas (``schemas/*.schema.json``), read as package data, so
an installed wheel and a checkout read the same files.

>>> load("delivered_value")["title"]
'DeliveredValue'
>>> validate("delivered_value", {"v": 1})[0][:30]
"/: 'subscriber' is a required p"
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from typing import Any

#: The contracts with a schema, by file stem.
NAMES = ("delivered_value", "status", "plan", "pubbroker", "archive_record", "backfill")


@cache
def load(name: str) -> dict[str, Any]:
    """The JSON Schema of contract ``name`` (one of :data:`NAMES`)."""
    if name not in NAMES:
        raise ValueError(f"no contract {name!r} (known: {', '.join(NAMES)})")
    text = (
        resources.files(__package__)
        .joinpath("schemas", f"{name}.schema.json")
        .read_text(encoding="utf-8")
    )
    schema: dict[str, Any] = json.loads(text)
    return schema


def version(name: str) -> int:
    """The contract's version (``x-version``), the one CHANGELOG.md is keyed to."""
    return int(load(name)["x-version"])


def validate(name: str, document: Any) -> list[str]:
    """Every violation of contract ``name`` by ``document``, each as
    ``/json/pointer: message`` (empty when it conforms). Needs ``jsonschema``,
    which the metamodel package depends on; imported here only."""
    from jsonschema import Draft202012Validator
    from referencing import Registry, Resource

    # the schemas refer to each other by file name (status.schema.json#/$defs/...)
    registry: Registry = Registry().with_resources(
        (load(n)["$id"], Resource.from_contents(load(n))) for n in NAMES
    )
    validator = Draft202012Validator(load(name), registry=registry)
    errors = sorted(validator.iter_errors(document), key=lambda e: list(e.absolute_path))
    return ["/" + "/".join(str(p) for p in e.absolute_path) + f": {e.message}" for e in errors]
