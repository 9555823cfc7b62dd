"""Fixtures shared by every test tree: where the paper's scenarios live
(../shared/scenarios beside the repository, as in CI)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parent
SCENARIOS = REPO.parent / "shared" / "scenarios"


@pytest.fixture(scope="session")
def scenarios_dir() -> Path:
    if not SCENARIOS.is_dir():
        pytest.fail(f"the reference scenarios are missing: {SCENARIOS} (CI puts ../shared "
                    "beside the repository)")
    return SCENARIOS


@pytest.fixture(scope="session")
def expected(scenarios_dir: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((scenarios_dir / "expected.json").read_text())
    return data
