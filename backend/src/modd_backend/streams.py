"""One browser's live view of one drone: the zenoh subscriptions it asked
for, all feeding one bounded queue that its WebSocket drains.

Contract: zenoh threads only ever ``put`` into the queue, which never blocks;
a slow browser loses its oldest messages and is told how many with a
``{"type": "dropped", "count": n}`` message. The drone's status
(``modd/<drone>/status``) is relayed on the same socket."""

from __future__ import annotations

import json
import re
from typing import Any

from .relay import DropOldestQueue
from .zbridge import Undeclarable, ZenohBridge

NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_name(kind: str, name: object) -> str:
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ValueError(f"{kind} {name!r} is not an identifier (letters, digits, underscores)")
    return name


def _decode(payload: bytes) -> Any:
    try:
        return json.loads(payload)
    except (ValueError, UnicodeDecodeError):
        return {"raw": payload.hex()}


class StreamRelay:
    """The subscriptions of one WebSocket; ``close`` undeclares them all."""

    def __init__(self, bridge: ZenohBridge, drone: str, queue_size: int) -> None:
        self.drone = check_name("drone", drone)
        self.bridge = bridge
        self.queue: DropOldestQueue[dict[str, Any]] = DropOldestQueue(queue_size)
        self._subs: dict[str, Undeclarable] = {}
        self._status: Undeclarable | None = None

    def start(self) -> None:
        self._status = self.bridge.subscribe(
            f"modd/{self.drone}/status",
            lambda _k, p: self.queue.put({"type": "status", "data": _decode(p)}),
        )

    def subscribe(self, subscriber: object) -> dict[str, Any]:
        name = check_name("subscriber", subscriber)
        key = f"modd/{self.drone}/sub/{name}"
        if name not in self._subs:
            self._subs[name] = self.bridge.subscribe(
                key,
                lambda _k, p: self.queue.put(
                    {"type": "value", "subscriber": name, "data": _decode(p)}
                ),
            )
        return {"type": "subscribed", "subscriber": name, "key": key}

    def unsubscribe(self, subscriber: object) -> dict[str, Any]:
        name = check_name("subscriber", subscriber)
        sub = self._subs.pop(name, None)
        if sub is not None:
            sub.undeclare()
        return {"type": "unsubscribed", "subscriber": name}

    @property
    def subscribers(self) -> list[str]:
        return sorted(self._subs)

    def close(self) -> None:
        for sub in self._subs.values():
            sub.undeclare()
        self._subs.clear()
        if self._status is not None:
            self._status.undeclare()
            self._status = None


def dynamic_request(bridge: ZenohBridge, drone: str, request: dict[str, Any],
                    timeout_s: float) -> dict[str, Any]:
    """Ask the SubBroker's ``modd/<drone>/subscribe`` queryable; its reply
    (``ACCEPTED`` with the key, ``NOT_AVAILABLE`` with the reason, ...) or a
    ``NO_REPLY`` status when nobody answers. Blocking."""
    key = f"modd/{check_name('drone', drone)}/subscribe"
    result = bridge.query(key, json.dumps(request).encode(), timeout_s)
    if not result.ok:
        return {"status": "NO_REPLY", "reason": result.error}
    reply = result.json()
    if not isinstance(reply, dict):
        return {"status": "ERROR", "reason": "the SubBroker's reply is not a JSON object"}
    return reply
