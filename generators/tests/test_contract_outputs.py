"""What the generators write for other processes keeps to the contracts:
the operator's pubbroker.json (read by the C++ PubBroker) validates against
metamodel/src/modd_contracts/schemas/pubbroker.schema.json."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from modd_contracts.schema import validate
from modd_gen.generate import generate
from modd_model import load_model

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((ROOT / "metamodel" / "examples").glob("**/*.modd"))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_pubbroker_json_conforms(path: Path) -> None:
    files = {a.path: a.content for a in generate(load_model(path), "operator")}
    doc = json.loads(files["operator/pubbroker.json"])
    assert validate("pubbroker", doc) == []
    assert validate("pubbroker", {**doc, "tranport": "udp"}) != []  # a typo is caught
