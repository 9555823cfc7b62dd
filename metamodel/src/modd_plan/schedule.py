"""The transmission schedule, kept compact (paper §III-C, Algorithm 1).

Every sent stream of period P is due at P, 2P, 3P, ... after the config epoch
(phase 0). Slot k (k = 0, 1, 2, ...) is the k-th distinct due date > 0; its
DATA frame carries the streams due at that date in stream-id order. The
hyperperiod is never listed: slots are walked with a next-due heap over the
distinct periods, and counted with inclusion–exclusion over the least common
multiples of the periods, merged by value (at most one term per divisor of
the hyperperiod), so that seven coprime periods spanning 26 days count in
microseconds.

All arithmetic is on integer microseconds (periods are whole microseconds on
the wire, ``modd_model.numbers.to_micros``).

>>> s = Schedule.from_periods_us([250_000, 250_000, 2_000_000], hyperperiod_us=2_000_000)
>>> s.messages_per_hyperperiod, next(s.iter_slots())
(8, (0, Fraction(1, 4), [0, 1]))
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cached_property
from math import gcd, lcm

from modd_model.numbers import MICROS_PER_SECOND

Slot = tuple[int, Fraction, list[int]]


def _essential_periods(periods: Sequence[int]) -> list[int]:
    """Distinct periods that are not multiples of another one (a multiple's
    due dates are a subset of its divisor's)."""
    distinct = sorted(set(periods))
    return [p for i, p in enumerate(distinct) if all(p % q for q in distinct[:i])]


def _inclusion_exclusion(periods: Sequence[int]) -> dict[int, int]:
    """Coefficients c_l such that #{due dates in (0, t]} = sum c_l * (t // l)."""
    coef: dict[int, int] = {}
    for p in _essential_periods(periods):
        new = dict(coef)
        new[p] = new.get(p, 0) + 1
        for d, c in coef.items():
            m = lcm(d, p)
            new[m] = new.get(m, 0) - c
        coef = {d: c for d, c in new.items() if c}
    return coef


@dataclass(frozen=True)
class Schedule:
    """Compact schedule: the period (µs) of each sent stream, by stream id.

    ``hyperperiod_us`` is the paper's hyperperiod: the LCM of all subscription
    periods, derived streams included (a multiple of the LCM of the sent ones).
    """

    periods_us: tuple[int, ...]
    hyperperiod_us: int
    _coef: dict[int, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_coef", _inclusion_exclusion(self.periods_us))

    @classmethod
    def from_periods_us(
        cls, periods_us: Sequence[int], hyperperiod_us: int | None = None
    ) -> Schedule:
        """Schedule of streams with these periods; the hyperperiod defaults to their LCM."""
        if any(p <= 0 for p in periods_us):
            raise ValueError("periods must be positive")
        h = hyperperiod_us if hyperperiod_us is not None else lcm(*periods_us) if periods_us else 0
        if periods_us and h % lcm(*periods_us):
            raise ValueError("the hyperperiod must be a multiple of every sent period")
        return cls(tuple(periods_us), h)

    @property
    def hyperperiod(self) -> Fraction:
        """Hyperperiod in seconds."""
        return Fraction(self.hyperperiod_us, MICROS_PER_SECOND)

    def count_until(self, t_us: int) -> int:
        """Number of slots whose date is in (0, t_us]."""
        return sum(c * (t_us // d) for d, c in self._coef.items()) if t_us > 0 else 0

    @cached_property
    def messages_per_hyperperiod(self) -> int:
        """DATA frames (slots) per hyperperiod."""
        return self.count_until(self.hyperperiod_us)

    def slot_date_us(self, slot: int) -> int:
        """Date (µs after the epoch) of slot ``slot``, by bisection on
        :meth:`count_until` over multiples of the periods' GCD."""
        if not self.periods_us:
            raise ValueError("an empty schedule has no slots")
        if slot < 0:
            raise ValueError("slot indexes start at 0")
        g = gcd(*self.periods_us)
        lo, hi = 0, (slot + 1) * min(self.periods_us) // g  # in units of g
        while lo < hi:
            mid = (lo + hi) // 2
            if self.count_until(mid * g) >= slot + 1:
                hi = mid
            else:
                lo = mid + 1
        return lo * g

    def iter_due_periods(self, start_slot: int = 0) -> Iterator[tuple[int, int, list[int]]]:
        """Slots from ``start_slot`` on, forever, as ``(index, date in µs,
        distinct periods due)``: the next-due heap over distinct periods."""
        if not self.periods_us:
            return
        start = self.slot_date_us(start_slot)
        heap = [(-(-start // p) * p, p) for p in sorted(set(self.periods_us))]
        heapq.heapify(heap)
        index = start_slot
        while True:
            date = heap[0][0]
            due: list[int] = []
            while heap[0][0] == date:
                _, p = heapq.heappop(heap)
                due.append(p)
                heapq.heappush(heap, (date + p, p))
            yield index, date, due
            index += 1

    def iter_slots(self, start_slot: int = 0) -> Iterator[Slot]:
        """Slots from ``start_slot`` on, forever: ``(index, date in s, stream ids)``."""
        by_period: dict[int, list[int]] = {}
        for sid, p in enumerate(self.periods_us):
            by_period.setdefault(p, []).append(sid)
        for index, date, due in self.iter_due_periods(start_slot):
            ids = sorted(i for p in due for i in by_period[p])
            yield index, Fraction(date, MICROS_PER_SECOND), ids

    def first_slots(self, limit: int) -> list[Slot]:
        """The first ``limit`` slots (or fewer if the hyperperiod has fewer)."""
        n = min(limit, self.messages_per_hyperperiod)
        out: list[Slot] = []
        if n == 0:
            return out
        for slot in self.iter_slots():
            out.append(slot)
            if len(out) == n:
                break
        return out

    def value_count_per_hyperperiod(self, stream_id: int) -> int:
        """How many windows of a stream fall in one hyperperiod."""
        return self.hyperperiod_us // self.periods_us[stream_id]
