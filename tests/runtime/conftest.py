"""Fixtures for the tests that drive the real modd-pubbroker binary."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from pubbroker_harness import PubBroker  # noqa: E402

S1_TOPICS = [(f"usv.accelerometer.accel_{a}", "float32") for a in "xyz"]


@pytest.fixture
def broker_factory(tmp_path: Path) -> Iterator[object]:
    """Starts brokers in per-test temporary directories and stops every one (by PID)."""
    started: list[PubBroker] = []

    def make(topics: list[tuple[str, str]] | None = None, **overrides: object) -> PubBroker:
        d = tmp_path / f"b{len(started)}"
        d.mkdir()
        b = PubBroker(d, S1_TOPICS if topics is None else topics, **overrides)
        started.append(b)
        return b.start()

    yield make
    for b in started:
        b.stop()
