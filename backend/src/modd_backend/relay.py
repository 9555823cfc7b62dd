"""A bounded queue between zenoh threads and one WebSocket: ``put`` never
blocks (a full queue drops its oldest item and counts it), ``get`` awaits.

>>> q = DropOldestQueue(2)
>>> for i in range(3): q.put(i)
>>> q.dropped, q.drain()
(1, [1, 2])
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections import deque
from typing import Generic, TypeVar

T = TypeVar("T")


class DropOldestQueue(Generic[T]):
    """Thread-safe producer side; one asyncio consumer bound with :meth:`bind`."""

    def __init__(self, maxsize: int) -> None:
        if maxsize < 1:
            raise ValueError("maxsize must be at least 1")
        self._items: deque[T] = deque(maxlen=maxsize)
        self._lock = threading.Lock()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready: asyncio.Event | None = None
        self.dropped = 0
        self.wakeups_saved = 0  # puts that found the consumer already woken

    def bind(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._ready = asyncio.Event()

    def put(self, item: T) -> None:
        with self._lock:
            was_empty = not self._items
            if len(self._items) == self._items.maxlen:
                self.dropped += 1
            self._items.append(item)
        # The consumer drains everything it is woken for, and sleeps only after
        # seeing the queue empty: waking it when the queue stops being empty is
        # enough. Waking it for every item cost one self-pipe write and one loop
        # iteration per value (a fleet's stream proxy spent its time there).
        if not was_empty:
            self.wakeups_saved += 1
            return
        loop, ready = self._loop, self._ready
        if loop is not None and ready is not None and not loop.is_closed():
            # RuntimeError: the loop is closing, the consumer is gone.
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(ready.set)

    def drain(self) -> list[T]:
        with self._lock:
            items = list(self._items)
            self._items.clear()
        return items

    def take_dropped(self) -> int:
        with self._lock:
            n, self.dropped = self.dropped, 0
        return n

    async def get_batch(self) -> list[T]:
        """Everything queued, waiting until there is something."""
        assert self._ready is not None, "bind() the queue to the consumer's loop first"
        while True:
            items = self.drain()
            if items:
                return items
            self._ready.clear()
            items = self.drain()
            if items:
                return items
            await self._ready.wait()
