"""Fixtures of the SubBroker tests: free ports, a zenoh client session, the
real PubBroker binary (the end-to-end tests skip, saying so, when it has not
been built: `make build`)."""

from __future__ import annotations

import json
import sys
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from modd.subbroker.payload import DeliveredValue  # noqa: E402
from modd.zenoh_session import client_settings, open_session  # noqa: E402
from subbroker_harness import PUBBROKER, shared_credentials  # noqa: E402


@pytest.fixture
def needs_pubbroker() -> None:
    if not PUBBROKER.exists():
        pytest.fail(f"{PUBBROKER} is not built: run make build (make test does)")


class Collector:
    """Everything put under modd/<drone>/**: values per subscriber, statuses."""

    def __init__(self) -> None:
        self.values: dict[str, list[DeliveredValue]] = {}
        self.status: list[dict[str, Any]] = []
        self.lock = threading.Lock()

    def on_sample(self, sample: Any) -> None:
        key = str(sample.key_expr)
        data = sample.payload.to_bytes()
        with self.lock:
            if key.endswith("/status"):
                self.status.append(json.loads(data))
            elif "/sub/" in key:
                v = DeliveredValue.from_json(data)
                self.values.setdefault(v.subscriber, []).append(v)

    def snapshot(self) -> dict[str, list[DeliveredValue]]:
        with self.lock:
            return {k: list(v) for k, v in self.values.items()}


@pytest.fixture
def zenoh_client() -> Iterator[Any]:
    """A factory: zenoh_client(port, identity="backend") -> a client session of
    that SubBroker, with that identity's credentials (shared_credentials)."""
    sessions: list[Any] = []

    def make(port: int, identity: str = "backend") -> Any:
        cred = shared_credentials().cred_file(identity)
        s = open_session(client_settings(f"tcp/127.0.0.1:{port}", cred))
        sessions.append(s)
        return s

    yield make
    for s in sessions:
        s.close()
