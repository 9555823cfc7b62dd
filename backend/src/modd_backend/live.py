"""One browser's live view of one drone: the subscriptions it asked for,
all feeding one bounded queue that its WebSocket drains.

Contract: zenoh threads only ever ``put`` into the queue, which never blocks;
a slow browser loses its oldest messages and is told how many with a
``{"type": "dropped", "count": n}`` message. The drone's status
(``modd/<drone>/status``) is relayed on the same socket. Subscriptions are
entries in the shared :class:`~modd_backend.hub.SubscriptionHub` (no zenoh
declaration, no thread), capped per socket and per user."""

from __future__ import annotations

import json
from collections import Counter
from typing import Any

from modd_contracts.keys import check_name, sub_key, subscribe_key

from .hub import SubscriptionHub
from .liveqc import LiveQc
from .relay import DropOldestQueue
from .zenoh_session import ZenohSession


def _decode(payload: bytes) -> Any:
    try:
        return json.loads(payload)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return {"raw": payload[:4096].hex()}


class CapReached(ValueError):
    """A subscription past the per-socket or per-user cap."""


class LiveRelay:
    """The subscriptions of one WebSocket; ``close`` removes them all.

    ``per_user`` is shared by all sockets of the app (user id -> live
    subscriptions); it is only touched from the event loop."""

    def __init__(
        self,
        hub: SubscriptionHub,
        drone: str,
        queue_size: int,
        *,
        user_id: int = 0,
        per_socket: int = 256,
        per_user: int = 1024,
        per_user_counts: Counter[int] | None = None,
    ) -> None:
        self.drone = check_name("drone", drone)
        self.hub = hub
        self.queue: DropOldestQueue[dict[str, Any]] = DropOldestQueue(queue_size)
        self.user_id = user_id
        self.per_socket = per_socket
        self.per_user = per_user
        self.counts: Counter[int] = per_user_counts if per_user_counts is not None else Counter()
        self._subs: set[str] = set()
        self._started = False
        #: QARTOD flags per subscriber with tests configured (liveqc.py)
        self._qc: dict[str, LiveQc] = {}

    def _on_value(self, name: str, payload: bytes) -> None:
        data = _decode(payload)
        message: dict[str, Any] = {"type": "value", "subscriber": name, "data": data}
        qc = self._qc.get(name)
        flags = qc.flags(data) if qc is not None else None
        if flags is not None:
            message["qc"] = flags
        self.queue.put(message)

    def _on_status(self, payload: bytes) -> None:
        self.queue.put({"type": "status", "data": _decode(payload)})

    def start(self) -> None:
        self.hub.add_status(self.drone, self._on_status)
        self._started = True

    def subscribe(
        self, subscriber: object, qc_tests: dict[str, Any] | None = None
    ) -> dict[str, Any]:
        """Relay the subscriber's values (flagged by ``qc_tests[subscriber]``'s QARTOD
        tests when it has some: liveqc.py)."""
        name = check_name("subscriber", subscriber)
        key = sub_key(self.drone, name)
        tests = (qc_tests or {}).get(name)
        if tests and name not in self._qc:
            self._qc[name] = LiveQc(tests)
        if name not in self._subs:
            if len(self._subs) >= self.per_socket:
                raise CapReached(f"at most {self.per_socket} subscriptions per connection")
            if self.counts[self.user_id] >= self.per_user:
                raise CapReached(f"at most {self.per_user} live subscriptions per user")
            self._subs.add(name)
            self.counts[self.user_id] += 1
            self.hub.add(self.drone, name, self._on_value)
        return {"type": "subscribed", "subscriber": name, "key": key}

    def unsubscribe(self, subscriber: object) -> dict[str, Any]:
        name = check_name("subscriber", subscriber)
        self._qc.pop(name, None)
        if name in self._subs:
            self._subs.discard(name)
            self._release(1)
            self.hub.remove(self.drone, name, self._on_value)
        return {"type": "unsubscribed", "subscriber": name}

    def _release(self, n: int) -> None:
        left = self.counts[self.user_id] - n
        if left > 0:
            self.counts[self.user_id] = left
        else:
            self.counts.pop(self.user_id, None)

    @property
    def subscribers(self) -> list[str]:
        return sorted(self._subs)

    def close(self) -> None:
        for name in self._subs:
            self.hub.remove(self.drone, name, self._on_value)
        self._release(len(self._subs))
        self._subs.clear()
        if self._started:
            self.hub.remove_status(self.drone, self._on_status)
            self._started = False


def dynamic_request(
    zenoh_session: ZenohSession, drone: str, request: dict[str, Any], timeout_s: float
) -> dict[str, Any]:
    """Ask the SubBroker's ``modd/<drone>/subscribe`` queryable; its reply
    (``ACCEPTED`` with the key, ``NOT_AVAILABLE`` with the reason, ...) or a
    ``NO_REPLY`` status when nobody answers. Blocking."""
    key = subscribe_key(check_name("drone", drone))
    result = zenoh_session.query(key, json.dumps(request).encode(), timeout_s)
    if not result.ok:
        return {"status": "NO_REPLY", "reason": result.error}
    reply = result.json()
    if not isinstance(reply, dict):
        return {"status": "ERROR", "reason": "the SubBroker's reply is not a JSON object"}
    return reply
