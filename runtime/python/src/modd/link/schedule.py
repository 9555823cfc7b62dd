"""The slot table, computed lazily from the streams' periods with a next-due heap.

Slot k is the k-th distinct due date > 0 after the epoch; its streams are those whose
period divides the date, in stream-id order. The hyperperiod is never materialised.

Example::

    it = SlotIterator([250_000, 250_000, 2_000_000])
    s = next(it)   # Slot(index=0, offset_us=250000, streams=(0, 1))
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator, Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Slot:
    index: int
    offset_us: int
    streams: tuple[int, ...]


class SlotIterator(Iterator[Slot]):
    def __init__(self, periods_us: Sequence[int]) -> None:
        self._periods: list[int] = []
        self._groups: list[list[int]] = []
        for sid, p in enumerate(periods_us):
            if p <= 0:
                raise ValueError(f"stream {sid} has period {p}")
            if p in self._periods:
                self._groups[self._periods.index(p)].append(sid)
            else:
                self._periods.append(p)
                self._groups.append([sid])
        self._heap = [(p, g) for g, p in enumerate(self._periods)]
        heapq.heapify(self._heap)
        self._next = 0

    def empty(self) -> bool:
        return not self._heap

    def peek_offset_us(self) -> int:
        return self._heap[0][0] if self._heap else 0

    def __next__(self) -> Slot:
        if not self._heap:
            raise StopIteration
        due = self._heap[0][0]
        streams: list[int] = []
        while self._heap and self._heap[0][0] == due:
            _, g = heapq.heappop(self._heap)
            streams.extend(self._groups[g])
            heapq.heappush(self._heap, (due + self._periods[g], g))
        s = Slot(self._next, due, tuple(sorted(streams)))
        self._next += 1
        return s

    def skip_to(self, index: int) -> None:
        """Advances so that the next slot returned has this index."""
        while self._next < index:
            next(self)
