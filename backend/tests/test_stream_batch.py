"""The stream socket's sender: with ``batch`` on, what one wake-up finds in
the queue (a drop count first) goes out as one ``batch`` frame, in order;
without, one frame per message, in the same order."""

from __future__ import annotations

import asyncio
import json
from types import SimpleNamespace
from typing import Any

import pytest
from modd_backend.relay import DropOldestQueue
from modd_backend.routers import live


class FakeSocket:
    def __init__(self) -> None:
        self.frames: list[Any] = []

    async def send_text(self, text: str) -> None:
        self.frames.append(json.loads(text))


async def _run(batched: bool, items: list[dict[str, Any]], size: int) -> list[Any]:
    queue: DropOldestQueue[dict[str, Any]] = DropOldestQueue(size)
    queue.bind(asyncio.get_running_loop())
    for item in items:
        queue.put(item)
    sock = FakeSocket()
    task = asyncio.create_task(live._send_loop(sock, SimpleNamespace(queue=queue), batched))  # type: ignore[arg-type]
    await asyncio.sleep(0.05)
    queue.put({"type": "value", "subscriber": "late", "data": {}})
    await asyncio.sleep(0.05)
    task.cancel()
    return sock.frames


ITEMS = [{"type": "value", "subscriber": f"s{i % 2}", "data": {"end_ns": i}} for i in range(6)]


@pytest.mark.parametrize("batched", [False, True])
def test_sender_order_and_drops(batched: bool) -> None:
    frames = asyncio.run(_run(batched, ITEMS, 4))
    flat = [m for f in frames for m in (f["messages"] if f["type"] == "batch" else [f])]
    assert flat == [
        {"type": "dropped", "count": 2},
        *ITEMS[2:],
        {"type": "value", "subscriber": "late", "data": {}},
    ]
    if batched:
        assert frames[0]["type"] == "batch" and len(frames[0]["messages"]) == 5
        assert frames[1]["type"] == "value"  # a lone message is sent as itself
    else:
        assert all(f["type"] != "batch" for f in frames) and len(frames) == 6


def test_batches_are_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(live, "BATCH_LIMIT", 2)
    frames = asyncio.run(_run(True, ITEMS[:5], 10))
    assert [len(f["messages"]) for f in frames[:3]] == [2, 2, 1]
