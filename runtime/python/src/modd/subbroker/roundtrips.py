"""The periodic PINGs of an established link and the round trips they measure
(``[link] ping_period_s``; docs/subbroker.md, "The link").

>>> rt = RoundTrips(1.0); rt.restart(0.0); rt.due(0.5) is None
True
"""

from __future__ import annotations

import os
import statistics
import struct


class RoundTrips:
    """The periodic PINGs of an established link (``[link] ping_period_s``) and the
    round trips their PONGs measure: the link's RTT follows a radio whose latency
    changes (the NACK timing and the next plan use it). At most ``in_flight``
    PINGs are awaited; older ones are forgotten (a lost PING costs nothing)."""

    def __init__(self, period_s: float, keep: int = 5, in_flight: int = 4) -> None:
        self.period_s = period_s
        self._keep = keep
        self._in_flight = in_flight
        self._sent: dict[bytes, float] = {}
        self._recent: list[float] = []
        self._next = 0.0
        self._count = 0

    def restart(self, now: float) -> None:
        """A new session: the first periodic PING one period from now."""
        self._sent.clear()
        self._next = now + self.period_s

    def due(self, now: float) -> bytes | None:
        """The payload of the PING to send now, or None (periodic PINGs off, or not yet)."""
        if self.period_s <= 0 or now < self._next:
            return None
        self._next = now + self.period_s
        self._count += 1
        payload = b"rt" + struct.pack("<I", self._count & 0xFFFFFFFF) + os.urandom(2)
        self._sent[payload] = now
        while len(self._sent) > self._in_flight:
            del self._sent[next(iter(self._sent))]
        return payload

    def on_pong(self, payload: bytes, now: float) -> float | None:
        """The median of the recent round trips once this PONG answers one of ours."""
        start = self._sent.pop(payload, None)
        if start is None:
            return None
        self._recent = [*self._recent[1 - self._keep :], now - start]
        return statistics.median(self._recent)
