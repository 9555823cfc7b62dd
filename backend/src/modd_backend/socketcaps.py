"""Caps on open WebSockets (live streams, 3D scene, Foxglove) per user and
per client address (every loopback address counting as one:
throttle.address_key), taken before a socket is accepted and given back
when it closes; a socket over either cap is refused (close code 4429).

Each user's first ``reserved`` sockets at an address do not count against
that address's cap: other accounts at the same address (every local user is
one loopback address) cannot fill it and lock the operator out; what they
can hold there is ``per_address`` plus ``reserved`` each.

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


#: Sockets of each user at an address outside that address's cap.
RESERVED_PER_USER = 8


class SocketCaps:
    def __init__(self, per_user: int, per_address: int, reserved: int = RESERVED_PER_USER) -> None:
        self.per_user = per_user
        self.per_address = per_address
        self.reserved = reserved
        self.users: Counter[int] = Counter()
        #: Sockets per address beyond their users' reserved ones.
        self.addresses: Counter[str] = Counter()
        self._at: Counter[tuple[int, str]] = Counter()
        self._lock = threading.Lock()

    def refusal(self, user_id: int, address: str) -> str | None:
        """Why one more socket would be refused now, or None."""
        if self.users[user_id] >= self.per_user:
            return f"at most {self.per_user} open sockets per user; close one first"
        key = address_key(address)
        if self._at[(user_id, key)] < self.reserved:
            return None
        if self.addresses[key] >= self.per_address:
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
            beyond = self._at[(user_id, key)] >= self.reserved
            self.users[user_id] += 1
            self._at[(user_id, key)] += 1
            self.addresses[key] += beyond
        try:
            yield
        finally:
            with self._lock:
                self.users[user_id] -= 1
                self._at[(user_id, key)] -= 1
                self.addresses[key] -= beyond
                if not self.users[user_id]:
                    del self.users[user_id]
                if not self._at[(user_id, key)]:
                    del self._at[(user_id, key)]
                if not self.addresses[key]:
                    del self.addresses[key]
