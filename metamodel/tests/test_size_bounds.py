"""A legal model has a bounded size (docs/metamodel.md, "Size bounds"):
every list of the schema has ``maxItems``, every string a ``maxLength``
(or a fixed set of values), every open object ``maxProperties``; a model past
a bound is refused with an error at the list's JSON pointer."""

from __future__ import annotations

import copy
import json
import time
from collections.abc import Iterator
from typing import Any

import pytest
from modd_model import load_model, validate
from modd_model.schema import schema_path

SCHEMA: dict[str, Any] = json.loads(schema_path().read_text())
#: The documented bound on a legal model's JSON text in UTF-8 (docs/metamodel.md).
DOCUMENTED_MAX_BYTES = 3 * 1024**3


def _nodes(node: Any, path: str = "#") -> Iterator[tuple[str, dict[str, Any]]]:
    if isinstance(node, dict):
        yield path, node
        for key, value in node.items():
            yield from _nodes(value, f"{path}/{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _nodes(value, f"{path}/{i}")


def test_every_collection_and_string_of_the_schema_is_bounded() -> None:
    unbounded = []
    for path, node in _nodes(SCHEMA):
        kind = node.get("type")
        if kind == "array" and "maxItems" not in node:
            unbounded.append(f"{path}: array without maxItems")
        if kind == "string" and not ({"maxLength", "const", "enum"} & node.keys()):
            unbounded.append(f"{path}: string without maxLength")
        if (
            kind == "object"
            and node.get("additionalProperties") not in (False, None)
            and "maxProperties" not in node
        ):
            unbounded.append(f"{path}: open object without maxProperties")
    assert unbounded == []


def _resolve(ref: str) -> dict[str, Any]:
    node: Any = SCHEMA
    for part in ref.removeprefix("#/").split("/"):
        node = node[part]
    return dict(node)


def max_json_bytes(node: dict[str, Any]) -> int:
    """An upper bound of the UTF-8 JSON text of any instance of ``node``
    (4 bytes per character of a string: the schema leaves no character that
    JSON escapes longer, but line breaks and tabs of descriptions, 2 bytes;
    numbers 32 characters)."""
    if "$ref" in node:
        return max_json_bytes(_resolve(node["$ref"]))
    if "const" in node or "enum" in node:
        return max(len(json.dumps(v)) for v in node.get("enum", [node.get("const")]))
    kind = node.get("type")
    if kind == "string" or "maxLength" in node:
        return 2 + 4 * int(node["maxLength"])
    if kind in ("number", "integer", "boolean"):
        return 32
    if kind == "array":
        return 2 + int(node["maxItems"]) * (max_json_bytes(node["items"]) + 2)
    if kind == "object" or "properties" in node:
        total = 2
        for name, sub in node.get("properties", {}).items():
            total += len(json.dumps(name)) + 3 + max_json_bytes(sub)
        extra = node.get("additionalProperties")
        if isinstance(extra, dict):
            key = 2 + 4 * int(node["propertyNames"]["maxLength"])
            total += int(node["maxProperties"]) * (key + 3 + max_json_bytes(extra))
        return total
    if "oneOf" in node or "anyOf" in node:
        return max(max_json_bytes(s) for s in node.get("oneOf", node.get("anyOf", [])))
    raise AssertionError(f"unbounded schema node {node}")


def test_a_legal_model_has_a_documented_size_bound() -> None:
    bound = max_json_bytes(SCHEMA)
    assert bound <= DOCUMENTED_MAX_BYTES, f"{bound:,} bytes"
    print(f"largest legal model: {bound:,} bytes of JSON")


@pytest.fixture(scope="module")
def base(scenarios_dir: Any) -> dict[str, Any]:
    return load_model(scenarios_dir / "scenario1.modd")


@pytest.mark.parametrize(
    ("pointer", "limit"),
    [
        ("/drone/sensors/0/variables", 256),
        ("/publishers/0/topics", 256),
    ],
)
def test_lists_past_their_bound_refused_at_their_pointer(
    base: dict[str, Any], pointer: str, limit: int
) -> None:
    doc = copy.deepcopy(base)
    node: Any = doc
    for part in pointer.strip("/").split("/"):
        node = node[int(part)] if isinstance(node, list) else node[part]
    node.extend([node[0]] * (limit + 1 - len(node)))
    found = [d for d in validate(doc) if d.pointer == pointer]
    assert found and "is too long" in found[0].message, found


def test_fifty_thousand_and_one_subscribers_refused_fast(base: dict[str, Any]) -> None:
    doc = copy.deepcopy(base)
    one = doc["subscribers"][0]
    doc["subscribers"] = [dict(one, name=f"s{k}") for k in range(50001)]
    t0 = time.monotonic()
    found = [d for d in validate(doc) if d.pointer == "/subscribers"]
    assert found and "is too long" in found[0].message
    assert time.monotonic() - t0 < 5  # the bound is checked before the rest


def test_layout_nodes_bounded(base: dict[str, Any]) -> None:
    doc = copy.deepcopy(base)
    doc["layout"] = {"nodes": {f"n{k}": {"x": 0, "y": 0} for k in range(60001)}}
    found = [d for d in validate(doc) if d.pointer == "/layout/nodes"]
    assert found, [d.pointer for d in validate(doc)][:5]
