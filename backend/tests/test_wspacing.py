"""WebSockets parsed a slice per event-loop iteration (wspacing.py): a
backlog of thousands of frames, small and large, arrives whole and in order,
and the parser never takes more than one slice at a time."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from modd_backend import Settings
from modd_backend.wspacing import PacedWebSocketProtocol
from websockets.sync.client import connect

from .conftest import ADMIN_PASSWORD
from .served import serve


@pytest.fixture
def base(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    slices: list[int] = []
    parent: Any = PacedWebSocketProtocol.__mro__[1]
    original = parent.data_received

    def spy(self: object, data: bytes) -> None:
        slices.append(len(data))
        original(self, data)

    monkeypatch.setattr(parent, "data_received", spy)
    settings = Settings(
        data_dir=tmp_path / "data",
        initial_admin_password=ADMIN_PASSWORD,
        zenoh_connect=(),
        ws_subscriptions_per_socket=50,
    )
    with serve(settings) as url:
        yield url
    assert slices and max(slices) <= PacedWebSocketProtocol.CHUNK


def test_backlog_arrives_whole_and_in_order(base: str) -> None:
    token = httpx.post(
        base + "/api/auth/login", timeout=30, json={"username": "admin", "password": ADMIN_PASSWORD}
    ).json()["token"]
    ws = connect(
        base.replace("http", "ws") + "/api/drones/usv/stream", open_timeout=10, max_size=None
    )
    ws.send(json.dumps({"op": "auth", "token": token}))
    assert json.loads(ws.recv(timeout=10))["type"] == "authenticated"
    n = 3000

    def flood() -> None:
        for i in range(n):
            pad = "x" * (30_000 if i % 500 == 7 else 0)  # frames across many slices
            ws.send(json.dumps({"op": "ping" if pad == "" else "nope", "id": i, "pad": pad}))

    sender = threading.Thread(target=flood)
    sender.start()
    seen: list[int] = []
    while len(seen) < n:
        msg = json.loads(ws.recv(timeout=30))
        if msg.get("type") == "dropped":
            pytest.fail("replies dropped: the queue is larger than the backlog here")
        if "id" in msg:
            seen.append(msg["id"])
    sender.join()
    ws.close()
    assert seen == list(range(n))
