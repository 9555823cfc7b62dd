"""The windows a subscriber has had, by identity (docs/fleet.md): the point where a
window two stations sent (two serving for a moment after a partition heals, a
backfill racing the live value) is kept once. Bounded: the oldest identities go
first, so memory stays flat over a mission.

>>> seen = Seen(limit=2)
>>> [seen.first(("usv", "s", 1, k)) for k in (0, 1, 0, 2, 0)]
[True, True, False, True, True]
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Hashable

from .payload import DeliveredValue

#: Identities remembered per subscription: hours of a 4 Hz subscription.
SEEN_LIMIT = 100_000


class Seen:
    """A bounded set of window identities, oldest out first."""

    def __init__(self, limit: int = SEEN_LIMIT) -> None:
        self.limit = limit
        self._order: deque[Hashable] = deque()
        self._set: set[Hashable] = set()
        self._lock = threading.Lock()  # zenoh may call from several threads

    def first(self, identity: Hashable) -> bool:
        """True the first time ``identity`` comes (it is remembered), else False."""
        with self._lock:
            if identity in self._set:
                return False
            self._set.add(identity)
            self._order.append(identity)
            if len(self._order) > self.limit:
                self._set.discard(self._order.popleft())
            return True


def identity(value: DeliveredValue) -> tuple[str, str, int, int] | None:
    """(drone, subscriber, epoch_ns, window), or None for a payload without it."""
    if value.drone is None or value.epoch_ns is None or value.window is None:
        return None
    return (value.drone, value.subscriber, value.epoch_ns, value.window)
