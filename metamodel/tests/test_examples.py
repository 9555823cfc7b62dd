"""The example models shipped with the project load without errors or warnings."""

from __future__ import annotations

from pathlib import Path

import pytest
from modd_model import load_file

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.modd"))


def test_there_are_examples() -> None:
    assert EXAMPLES


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_is_valid(path: Path) -> None:
    result = load_file(path)
    assert result.ok and result.diagnostics == [], [str(d) for d in result.diagnostics]
