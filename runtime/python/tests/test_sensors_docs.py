"""The cookbook's model excerpts (docs/sensors.md) are valid models."""

from __future__ import annotations

import re
from pathlib import Path

from modd_model import parse_text
from modd_model.validate import validate

DOC = Path(__file__).resolve().parents[3] / "docs" / "sensors.md"


def test_cookbook_excerpts_validate() -> None:
    blocks = re.findall(r"```\n(Sensor .*?)```", DOC.read_text(), re.S)
    assert len(blocks) == 8
    for block in blocks:
        name = block.split()[1]
        variables = re.findall(r"^\s+(\w+)\(", block, re.M)
        topics = ", ".join(f'"d.{name}.{v}"' for v in variables)
        doc, _ = parse_text(
            f"Drone d {{ Sensors {{ {block} }} }} "
            'PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c"); '
            f"Publishers {{ Publisher p(1, {topics}); }}"
        )
        assert [str(d) for d in validate(doc)] == [], block
