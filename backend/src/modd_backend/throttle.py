"""Login throttling: failed logins counted per account and per client
address in a sliding window; past the limit, logins from there are refused
with 429 and ``Retry-After`` until the oldest failure leaves the window.

>>> t = Throttle(limit=2, window_s=60)
>>> t.fail("ann", now=0); t.fail("ann", now=1); t.retry_after("ann", now=2)
58.0
>>> t.retry_after("bob", now=2)
0.0
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict, deque


class Throttle:
    """Failures per key in the last ``window_s`` seconds; at most ``max_keys``
    keys kept (the least recently failed forgotten first), so memory is bounded."""

    def __init__(self, limit: int, window_s: float, max_keys: int = 100_000) -> None:
        self.limit = limit
        self.window_s = window_s
        self.max_keys = max_keys
        self._fails: OrderedDict[str, deque[float]] = OrderedDict()
        self._lock = threading.Lock()

    def _prune(self, key: str, now: float) -> deque[float] | None:
        q = self._fails.get(key)
        if q is None:
            return None
        while q and q[0] <= now - self.window_s:
            q.popleft()
        if not q:
            del self._fails[key]
            return None
        return q

    def retry_after(self, key: str, now: float | None = None) -> float:
        """Seconds until ``key`` may try again (0: now)."""
        now = time.monotonic() if now is None else now
        with self._lock:
            q = self._prune(key, now)
            if q is None or len(q) < self.limit:
                return 0.0
            return float(max(0.0, q[len(q) - self.limit] + self.window_s - now))

    def fail(self, key: str, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        with self._lock:
            q = self._prune(key, now)
            if q is None:
                q = self._fails[key] = deque(maxlen=max(self.limit, 1) * 2)
            q.append(now)
            self._fails.move_to_end(key)
            while len(self._fails) > self.max_keys:
                self._fails.popitem(last=False)

    def clear(self, key: str) -> None:
        with self._lock:
            self._fails.pop(key, None)
