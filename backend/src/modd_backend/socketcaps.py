"""Caps on open WebSockets (live streams, 3D scene, Foxglove) per user and
per client address (every loopback address counting as one:
throttle.address_key), taken before a socket is accepted and given back
when it closes; a socket over either cap is refused (close code 4429).

>>> caps = SocketCaps(per_user=1, per_address=5)
>>> with caps.slot(7, "127.0.0.1"):
...     caps.refusal(7, "127.0.0.2")
'at most 1 open sockets per user; close one first'
>>> caps.refusal(7, "127.0.0.1") is None
True
"""

from __future__ import annotations

import threading
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager

from .throttle import address_key

#: The close code of a socket refused by a cap.
CAP_CLOSE = 4429


class SocketFull(Exception):
    """A cap is reached; the message says which."""


class SocketCaps:
    def __init__(self, per_user: int, per_address: int) -> None:
        self.per_user = per_user
        self.per_address = per_address
        self.users: Counter[int] = Counter()
        self.addresses: Counter[str] = Counter()
        self._lock = threading.Lock()

    def refusal(self, user_id: int, address: str) -> str | None:
        """Why one more socket would be refused now, or None."""
        if self.users[user_id] >= self.per_user:
            return f"at most {self.per_user} open sockets per user; close one first"
        if self.addresses[address_key(address)] >= self.per_address:
            return f"at most {self.per_address} open sockets per client address"
        return None

    @contextmanager
    def slot(self, user_id: int, address: str) -> Iterator[None]:
        """Holds one socket's place (SocketFull when a cap is reached)."""
        key = address_key(address)
        with self._lock:
            reason = self.refusal(user_id, address)
            if reason is not None:
                raise SocketFull(reason)
            self.users[user_id] += 1
            self.addresses[key] += 1
        try:
            yield
        finally:
            with self._lock:
                self.users[user_id] -= 1
                self.addresses[key] -= 1
                if not self.users[user_id]:
                    del self.users[user_id]
                if not self.addresses[key]:
                    del self.addresses[key]
