"""The compiled schema validator (jsonschema-rs) is only a fast path: on every
document it accepts, the reference validator (jsonschema, ECMA-262 patterns)
finds no error either. Checked on seeded random mutations of a valid model
(strings with newlines, invisible and control characters, wrong types,
missing and unknown properties, huge numbers) and on a model of 5,000
subscriptions, which the fast path must accept."""

from __future__ import annotations

import copy
import importlib
import random
from typing import Any

import pytest

validate_module = importlib.import_module("modd_model.validate")

BASE: dict[str, Any] = {
    "schemaVersion": "1.0",
    "drone": {
        "name": "d",
        "sensors": [
            {
                "name": "imu",
                "variables": [
                    {"name": "ax", "unit": "METER"},
                    {"name": "flag", "unit": "NONE", "type": "bool"},
                ],
            }
        ],
    },
    "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 7171}, "logPath": "/tmp/l"},
    "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 7272}, "configPath": "/tmp/c"},
    "publishers": [{"name": "p", "periodS": "0.04", "topics": ["d.imu.ax", "d.imu.flag"]}],
    "subscribers": [
        {"name": "s1", "topic": "d.imu.ax", "periodS": "1.0", "aggregation": "AVERAGE"},
        {"name": "s2", "topic": "d.imu.flag", "periodS": "0.5", "aggregation": "LAST"},
    ],
}

STRINGS = [
    "a\n",
    "a\r",
    "a\u200b",
    "\u0000",
    "a b",
    "1a",
    "é",
    "\u0661",
    "",
    "a$",
    "A" * 300,
    "x.y",
    "d.imu.ax\n",
    "0.1\n",
    "-1",
    "1e3",
    " 1.0",
    "file:\u2028",
    "env:A\n",
]
VALUES: list[Any] = [*STRINGS, 0, -1, 1.5, 10**30, 1e300, True, None, [], {}, ["a"]]


def _paths(doc: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, (*prefix, i))
    return out


def _mutate(rng: random.Random) -> dict[str, Any]:
    doc = copy.deepcopy(BASE)
    for _ in range(rng.randint(1, 2)):
        path = rng.choice(_paths(doc))
        parent: Any = doc
        for k in path[:-1]:
            parent = parent[k]
        action = rng.random()
        if action < 0.1 and isinstance(parent, dict):
            del parent[path[-1]]
        elif action < 0.2 and isinstance(parent, dict):
            parent["extra"] = 1
        else:
            parent[path[-1]] = rng.choice(VALUES)
    return doc


def _reference_errors(doc: Any) -> list[Any]:
    return list(validate_module._schema_validator().iter_errors(doc))


@pytest.mark.parametrize("seed", range(4))
def test_fast_path_never_accepts_what_the_reference_refuses(seed: int) -> None:
    fast = validate_module._fast_validator()
    assert fast is not None
    rng = random.Random(seed)
    refused = 0
    for _ in range(150):
        doc = _mutate(rng)
        try:
            accepted = fast.is_valid(doc)
        except Exception:  # noqa: BLE001 - the reference decides then
            accepted = False
        errors = _reference_errors(doc)
        assert not (accepted and errors), (doc, errors)
        refused += bool(errors)
        # and validate() gives the reference's diagnostics either way
        got = [d.pointer for d in validate_module._schema_diagnostics(doc)]
        assert got == sorted(validate_module._schema_diagnostic(e).pointer for e in errors)
    assert refused > 30  # the mutations do reach the schema's rules


def test_large_valid_model_takes_the_fast_path(monkeypatch: pytest.MonkeyPatch) -> None:
    doc = copy.deepcopy(BASE)
    doc["subscribers"] = [
        {"name": f"s{i}", "topic": "d.imu.ax", "periodS": "1.0", "aggregation": "MAX"}
        for i in range(5000)
    ]

    def refuse() -> None:
        raise AssertionError("the reference validator ran on a valid document")

    monkeypatch.setattr(validate_module, "_schema_validator", refuse)
    assert validate_module._schema_diagnostics(doc) == []
