"""One zenoh subscription for every live value and one for every status,
shared by all WebSockets (and the 3D scene), fanned out in process.

A WebSocket's ``subscribe`` only adds a callback to a dict: nothing is
declared on zenoh, no thread is started and the event loop never waits, so
neither the number of sockets nor of subscriptions costs OS threads (the
two wildcard subscribers are declared once, at start-up).

It is also where the backend keeps each window once (docs/fleet.md, "Exactly once
at the subscriber"): a value whose identity (drone, subscriber, epoch_ns, window,
with its period) it has had, sent again by another station, reaches no callback (the WebSockets,
the 3D scene, the Foxglove server); a value without one passes as before.

>>> hub = SubscriptionHub()
>>> got = []
>>> hub.add("usv", "sub_1", lambda name, p: got.append((name, p)))
>>> hub.on_value("modd/usv/sub/sub_1", b"1"); hub.on_value("modd/usv/sub/sub_2", b"2")
>>> got
[('sub_1', b'1')]
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable

from modd.subbroker.seen import Seen, identity_of
from modd_contracts import keys

from .zenoh_session import Undeclarable, ZenohSession

ValueCallback = Callable[[str, bytes], None]
StatusCallback = Callable[[bytes], None]
#: Wildcards the hub subscribes to.
VALUES = keys.ALL_VALUES
STATUS = keys.ALL_STATUS


class SubscriptionHub:
    """Callbacks per (drone, subscriber) and per drone status; callbacks run on
    a zenoh thread and must not block (they put into a DropOldestQueue)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._values: dict[tuple[str, str], set[ValueCallback]] = {}
        self._status: dict[str, set[StatusCallback]] = {}
        self._every_value: list[Callable[[str, bytes], None]] = []
        self._every_status: list[Callable[[str, bytes], None]] = []
        self._declared: list[Undeclarable] = []
        self._seen = Seen()
        #: Values dropped as windows already had (another station's copy).
        self.duplicates = 0

    def start(self, zenoh_session: ZenohSession) -> None:
        """Declare the two wildcard subscribers (blocking; call at start-up)."""
        self._declared = [
            zenoh_session.subscribe(VALUES, self.on_value),
            zenoh_session.subscribe(STATUS, self.on_status),
        ]

    def stop(self) -> None:
        for sub in self._declared:
            sub.undeclare()
        self._declared = []

    def listen_all(self, callback: Callable[[str, bytes], None]) -> None:
        """``callback(key, payload)`` for every value (the 3D scene)."""
        self._every_value.append(callback)

    def listen_all_status(self, callback: Callable[[str, bytes], None]) -> None:
        """``callback(key, payload)`` for every drone's status (the Foxglove server)."""
        self._every_status.append(callback)

    def on_value(self, key: str, payload: bytes) -> None:
        if not first_window(self._seen, payload):
            with self._lock:
                self.duplicates += 1
            return
        found = keys.match_sub_key(key)
        for cb in self._every_value:
            cb(key, payload)
        if found is None:
            return
        with self._lock:
            targets = list(self._values.get(found, ()))
        for cb in targets:
            cb(found[1], payload)

    def on_status(self, key: str, payload: bytes) -> None:
        drone = keys.match_status_key(key)
        for every in self._every_status:
            every(key, payload)
        if drone is None:
            return
        with self._lock:
            targets = list(self._status.get(drone, ()))
        for cb in targets:
            cb(payload)

    def add(self, drone: str, name: str, callback: ValueCallback) -> None:
        with self._lock:
            self._values.setdefault((drone, name), set()).add(callback)

    def remove(self, drone: str, name: str, callback: ValueCallback) -> None:
        with self._lock:
            cbs = self._values.get((drone, name))
            if cbs is not None:
                cbs.discard(callback)
                if not cbs:
                    del self._values[(drone, name)]

    def add_status(self, drone: str, callback: StatusCallback) -> None:
        with self._lock:
            self._status.setdefault(drone, set()).add(callback)

    def remove_status(self, drone: str, callback: StatusCallback) -> None:
        with self._lock:
            cbs = self._status.get(drone)
            if cbs is not None:
                cbs.discard(callback)
                if not cbs:
                    del self._status[drone]

    @property
    def keys(self) -> int:
        with self._lock:
            return len(self._values)


def first_window(seen: Seen, payload: bytes) -> bool:
    """False when ``payload`` is a window ``seen`` has had (it is remembered
    otherwise); a payload without an identity, or not JSON, is always first.

    >>> seen = Seen()
    >>> line = b'{"drone":"usv","subscriber":"s","period_s":"1","epoch_ns":1,"window":0}'
    >>> first_window(seen, line), first_window(seen, line), first_window(seen, b"{")
    (True, False, True)
    """
    if b'"window"' not in payload:  # older payloads: no parse
        return True
    try:
        doc = json.loads(payload)
    except (ValueError, UnicodeDecodeError, RecursionError):
        return True
    ident = identity_of(doc) if isinstance(doc, dict) else None
    return ident is None or seen.first(ident)
