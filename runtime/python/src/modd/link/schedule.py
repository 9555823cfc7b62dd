"""The link's slot table, as the receiver walks it: the planner's own slot walk
(:meth:`modd_plan.schedule.Schedule.iter_due_periods`), so that the SubBroker
and the plan can never disagree on which streams a DATA frame carries.

Slot k is the k-th distinct due date > 0 after the epoch; its streams are those whose
period divides the date, in stream-id order. The hyperperiod is never materialised.

Example::

    it = SlotIterator([250_000, 250_000, 2_000_000])
    s = next(it)   # Slot(index=0, offset_us=250000, streams=(0, 1))
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from modd_plan.schedule import Schedule


@dataclass(frozen=True)
class Slot:
    index: int
    offset_us: int
    streams: tuple[int, ...]


class SlotIterator(Iterator[Slot]):
    def __init__(self, periods_us: Sequence[int]) -> None:
        for sid, p in enumerate(periods_us):
            if p <= 0:
                raise ValueError(f"stream {sid} has period {p}")
        self._by_period: dict[int, list[int]] = {}
        for sid, p in enumerate(periods_us):
            self._by_period.setdefault(p, []).append(sid)
        # The LCM hyperperiod is only a number here: the walk never enumerates it.
        self._schedule = Schedule.from_periods_us(list(periods_us))
        self._walk = self._schedule.iter_due_periods(0)
        self._next = 0

    def __next__(self) -> Slot:
        index, date_us, due = next(self._walk)  # StopIteration when there are no streams
        self._next = index + 1
        return Slot(index, date_us, tuple(sorted(s for p in due for s in self._by_period[p])))

    def skip_to(self, index: int) -> None:
        """Advances so that the next slot returned has this index (a bisection
        on the slot count, not a walk: a late resume costs no more than an early one)."""
        if index > self._next:
            self._walk = self._schedule.iter_due_periods(index)
            self._next = index
