"""Login throttling: attempts counted per account and per client address
in a sliding window; past the limit, logins from there are refused with 429
and ``Retry-After`` until the oldest attempt leaves the window.

An attempt is counted by :meth:`Throttle.take`, atomically, *before* the
password is checked (and given back when it succeeds): a burst of concurrent
guesses cannot all pass the check while the first ones are still being
hashed. Every loopback address is one client (:func:`address_key`): a local
process rotating through 127.0.0.0/8 is still one address.

An account that logged in from an address (:class:`KnownPairs`) is past that
address's lock there: 50 wrong logins under random names from one local
process lock that address for new names, never the users who log in from it;
their own accounts' limit still holds.

>>> t = Throttle(limit=2, window_s=60)
>>> t.fail("ann", now=0); t.fail("ann", now=1); t.retry_after("ann", now=2)
58.0
>>> t.retry_after("bob", now=2)
0.0
>>> [t.take("cy", now=0), t.take("cy", now=0), t.take("cy", now=0)]
[0.0, 0.0, 60.0]
"""

from __future__ import annotations

import ipaddress
import threading
import time
from collections import OrderedDict, deque


def address_key(host: str) -> str:
    """The throttling key of a client address: every loopback address is
    one key, an IPv6 address counts by its /64, anything else as itself.

    >>> address_key("127.4.5.6"), address_key("2001:db8::1"), address_key("10.0.0.7")
    ('loopback', '2001:db8::/64', '10.0.0.7')
    """
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return host
    if ip.is_loopback:
        return "loopback"
    if ip.version == 6:
        return str(ipaddress.ip_network(f"{ip}/64", strict=False))
    return str(ip)


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
            return self._wait(self._prune(key, now), now)

    def _wait(self, q: deque[float] | None, now: float) -> float:
        if q is None or len(q) < self.limit:
            return 0.0
        return float(max(0.0, q[len(q) - self.limit] + self.window_s - now))

    def take(self, key: str, now: float | None = None) -> float:
        """Count an attempt of ``key`` now and return 0, or, at the limit,
        count nothing and return the seconds to wait (one atomic step)."""
        now = time.monotonic() if now is None else now
        with self._lock:
            wait = self._wait(self._prune(key, now), now)
            if wait == 0.0:
                self._record(key, now)
            return wait

    def give_back(self, key: str) -> None:
        """Forget the newest attempt of ``key`` (it succeeded)."""
        with self._lock:
            q = self._fails.get(key)
            if q:
                q.pop()
            if q is not None and not q:
                del self._fails[key]

    def fail(self, key: str, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        with self._lock:
            self._prune(key, now)
            self._record(key, now)

    def _record(self, key: str, now: float) -> None:
        q = self._fails.get(key)
        if q is None:
            q = self._fails[key] = deque(maxlen=max(self.limit, 1) * 2)
        q.append(now)
        self._fails.move_to_end(key)
        while len(self._fails) > self.max_keys:
            self._fails.popitem(last=False)

    def clear(self, key: str) -> None:
        with self._lock:
            self._fails.pop(key, None)


class KnownPairs:
    """(account, address key) pairs that logged in successfully within
    ``keep_s``; at most ``max_pairs`` kept (the oldest forgotten first).

    >>> k = KnownPairs(keep_s=10)
    >>> k.add("ann", "loopback", now=0); k.has("ann", "loopback", now=5), k.has("ann", "x", now=5)
    (True, False)
    >>> k.has("ann", "loopback", now=11)
    False
    """

    def __init__(self, keep_s: float, max_pairs: int = 100_000) -> None:
        self.keep_s = keep_s
        self.max_pairs = max_pairs
        self._seen: OrderedDict[tuple[str, str], float] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, account: str, address: str, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        with self._lock:
            self._seen[(account, address)] = now
            self._seen.move_to_end((account, address))
            while len(self._seen) > self.max_pairs:
                self._seen.popitem(last=False)

    def has(self, account: str, address: str, now: float | None = None) -> bool:
        now = time.monotonic() if now is None else now
        with self._lock:
            seen = self._seen.get((account, address))
            return seen is not None and now - seen <= self.keep_s
