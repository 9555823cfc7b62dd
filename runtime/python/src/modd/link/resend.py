"""Loss recovery of the datagram transports (docs/protocol.md, "NACK"): the
receiver's gap tracker, which says which slots to ask for and when, and the
sender's bounded ring of recent datagrams, which answers a NACK.

>>> gaps = GapTracker(max_asks=5)
>>> gaps.received(0, 2, now=0.0)
>>> gaps.received(5, 1, now=0.1)  # slots 2, 3, 4 missing
>>> gaps.due(now=0.1, every=1.0)
[(2, 3)]
>>> gaps.received(2, 3, now=0.5)
>>> gaps.due(now=2.0, every=1.0), gaps.missing
([], 0)
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

from .datagram import MAX_NACK_RANGES


@dataclass
class _Gap:
    first: int
    count: int
    asks: int = 0
    last_ask: float = float("-inf")


class GapTracker:
    """Slots received so far and the holes between them; bounded: at most
    ``max_gaps`` holes are tracked (the oldest are given up, counted in ``lost``)."""

    def __init__(self, max_asks: int = 5, max_gaps: int = 256) -> None:
        self.max_asks = max_asks
        self.max_gaps = max_gaps
        self.next = -1  # next slot expected; -1 before the first datagram
        self.gaps: list[_Gap] = []
        self.lost = 0  # slots given up (asked max_asks times, or too many holes)
        self.recovered = 0  # slots that arrived after a gap opened

    @property
    def missing(self) -> int:
        return sum(g.count for g in self.gaps)

    def received(self, first: int, count: int, now: float) -> None:
        """Slots ``first .. first + count - 1`` arrived (tag verified, new)."""
        end = first + count
        if self.next < 0:
            self.next = end
            return
        if first > self.next:
            self.gaps.append(_Gap(self.next, first - self.next))
            while len(self.gaps) > self.max_gaps:
                self.lost += self.gaps.pop(0).count
        self.next = max(self.next, end)
        kept: list[_Gap] = []
        for g in self.gaps:
            g_end = g.first + g.count
            if end <= g.first or first >= g_end:
                kept.append(g)
                continue
            self.recovered += min(end, g_end) - max(first, g.first)
            # an answer is arriving: what is left of the gap waits a full interval
            # from now before it is asked again (a resend still on a slow link is not
            # asked for twice, which would spend the sender's resend budget on copies)
            last = max(g.last_ask, now) if g.asks else g.last_ask
            if first > g.first:
                kept.append(_Gap(g.first, first - g.first, g.asks, last))
            if end < g_end:
                kept.append(_Gap(end, g_end - end, g.asks, last))
        self.gaps = kept

    def due(self, now: float, every: float) -> list[tuple[int, int]]:
        """Ranges to NACK now: gaps not asked for within ``every`` seconds (nor
        answered in part within it); a gap asked ``max_asks`` times is given up
        (counted in ``lost``), so that backfill, not a late resend, fills it."""
        ranges: list[tuple[int, int]] = []
        kept: list[_Gap] = []
        for g in self.gaps:
            if now - g.last_ask < every or len(ranges) >= MAX_NACK_RANGES:
                kept.append(g)
                continue
            if g.asks >= self.max_asks:
                self.lost += g.count
                continue
            g.asks += 1
            g.last_ask = now
            ranges.append((g.first, min(g.count, 65535)))
            kept.append(g)
        self.gaps = kept
        return ranges


class ResendRing:
    """The sender's recent DATA datagrams by first slot, bounded by count and
    bytes; ``lookup`` gives the datagrams that hold any of the nacked slots."""

    def __init__(self, max_datagrams: int = 256, max_bytes: int = 65536) -> None:
        self.max_datagrams = max_datagrams
        self.max_bytes = max_bytes
        self.ring: OrderedDict[int, tuple[int, bytes]] = OrderedDict()  # first -> (count, raw)
        self.bytes = 0
        self.resent = 0
        self.too_old = 0

    def add(self, first: int, count: int, raw: bytes) -> None:
        self.ring[first] = (count, raw)
        self.bytes += len(raw)
        while self.ring and (len(self.ring) > self.max_datagrams or self.bytes > self.max_bytes):
            _, (_, old) = self.ring.popitem(last=False)
            self.bytes -= len(old)

    def lookup(self, ranges: list[tuple[int, int]]) -> list[bytes]:
        """The datagrams to resend for the nacked ``ranges`` (each once, in order)."""
        out: list[bytes] = []
        oldest = next(iter(self.ring), None)
        for first, n in ranges:
            if oldest is None or first < oldest:
                self.too_old += 1
            for start, (count, raw) in self.ring.items():
                if start < first + n and first < start + count and raw not in out:
                    out.append(raw)
        self.resent += len(out)
        return out
