"""The transmission schedule, kept compact (paper §III-C, Algorithm 1).

Every sent stream of period P is due at P, 2P, 3P, ... after the config epoch
(phase 0). Slot k (k = 0, 1, 2, ...) is the k-th distinct due date > 0; its
DATA frame carries the streams due at that date in stream-id order. The
hyperperiod is never listed: slots are walked with a next-due heap over the
distinct periods, and counted with a sieve over the divisor lattice of the
hyperperiod, group by group, with an explicit bound on work and memory
(docs/planning.md, "Counting the slots"):

1. Only the *essential* periods matter: a period that is a multiple of
   another one adds no due date. At most :data:`ESSENTIAL_LIMIT` of them.
2. Divide them by their GCD ``g`` (``r_i = p_i / g``) and split the ``r_i``
   over a coprime base ``B`` (pairwise coprime integers > 1, found with
   ``gcd`` alone, no factoring): ``r_i = prod b^e(i, b)``. Periods that share
   no base element form independent *groups* (Chinese remainder theorem):
   over one reduced hyperperiod ``L = prod_G L_G``, the dates hit by no period
   are the product of each group's.
3. In a group, whether ``r_i`` divides ``x`` depends only on the vector
   ``k_b(x) = max{k <= a_b : b^k | x}``, and ``x mod L_G`` takes each vector
   ``prod_b N_b(k_b)`` times, ``N_b(k) = b^(a_b-k) - b^(a_b-k-1)`` (``1`` at
   ``k = a_b``). Mark the vectors divisible by some ``r_i`` (an OR-prefix scan
   along each axis of the ``prod (a_b + 1)`` cells), then contract the
   unmarked cells with the ``N_b``: that is the group's count of dates hit by
   no period. A group of at most 12 periods uses inclusion–exclusion over
   its ``2^e - 1`` subsets instead, when they are fewer than the cells.

Work and memory per group: at most :data:`LATTICE_LIMIT` cells (a byte and an
int64 each, one OR pass per axis) or 4,095 subsets. A
schedule beyond it raises :class:`ScheduleTooLarge` naming the periods of
the offending group before anything is allocated. Seven coprime periods
spanning 26 days count in microseconds; so do 1,000.

Counting up to an arbitrary date (a slot's date, for a resume) uses the
inclusion–exclusion terms whose LCM is at most that date: each such LCM is
itself a due date, so there are never more terms than slots before it (and
at most :data:`TERM_LIMIT`, else the walk is used).

All arithmetic is on integer microseconds (periods are whole microseconds on
the wire, ``modd_model.numbers.to_micros``).

>>> s = Schedule.from_periods_us([250_000, 250_000, 2_000_000], hyperperiod_us=2_000_000)
>>> s.messages_per_hyperperiod, next(s.iter_slots())
(8, (0, Fraction(1, 4), [0, 1]))
"""

from __future__ import annotations

import heapq
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property, reduce
from math import gcd, lcm, prod
from typing import Any

from modd_model.numbers import MICROS_PER_SECOND

Slot = tuple[int, Fraction, list[int]]

#: Largest divisor lattice (cells) of one group of periods the count sieves:
#: 1 MiB of marks and 8 MiB of counts at most, about 50 ms.
LATTICE_LIMIT = 1 << 20
#: A group of at most 12 periods is counted by inclusion–exclusion over its
#: subsets when they are fewer than the lattice's cells.
SUBSET_LIMIT = (1 << 12) - 1
#: Essential (pairwise non-dividing) periods at most: the coprime base costs
#: O(e^2) gcds.
ESSENTIAL_LIMIT = 512
#: Inclusion–exclusion terms when counting the slots up to a date.
TERM_LIMIT = 1 << 14
#: Slots walked rather than bisected when locating a slot by its index.
WALK_LIMIT = 4096
_INT64_SAFE = 1 << 62


class ScheduleTooLarge(ValueError):
    """The slots of these periods cannot be counted within the planner's
    bound; ``periods_us`` are the periods of the offending group."""

    def __init__(self, periods_us: Sequence[int], reason: str) -> None:
        self.periods_us = tuple(sorted(periods_us))
        self.reason = reason
        listed = ", ".join(_seconds(p) for p in self.periods_us[:12])
        more = f" and {len(self.periods_us) - 12} more" if len(self.periods_us) > 12 else ""
        super().__init__(f"the sent periods {listed}{more} s: {reason}")


def _seconds(us: int) -> str:
    whole, frac = divmod(us, MICROS_PER_SECOND)
    return f"{whole}.{frac:06d}".rstrip("0").rstrip(".") if frac else str(whole)


def essential_periods(periods: Sequence[int]) -> list[int]:
    """Distinct periods that are not multiples of another one (a multiple's
    due dates are a subset of its divisor's), ascending. Raises
    :class:`ScheduleTooLarge` past :data:`ESSENTIAL_LIMIT` of them."""
    distinct = sorted(set(periods))
    out: list[int] = []
    if len(distinct) > 64 and distinct[-1] < _INT64_SAFE:  # numpy: only for many periods
        import numpy as np

        rest = np.asarray(distinct, dtype=np.int64)
        while rest.size:
            p = int(rest[0])
            out.append(p)
            if len(out) > ESSENTIAL_LIMIT:
                break
            rest = rest[rest % p != 0]
    else:
        for p in distinct:
            if all(p % q for q in out):
                out.append(p)
                if len(out) > ESSENTIAL_LIMIT:
                    break
    if len(out) > ESSENTIAL_LIMIT:
        raise ScheduleTooLarge(
            out, f"more than {ESSENTIAL_LIMIT} sent periods of which none divides another"
        )
    return out


def inclusion_exclusion(periods: Sequence[int], horizon: int, limit: int) -> dict[int, int]:
    """Coefficients ``c_l`` with ``#{dates in (0, t]} = sum c_l * (t // l)`` for
    every ``t <= horizon`` (terms of LCM beyond the horizon are 0 there and
    dropped, so every term is a due date <= horizon). Raises
    :class:`ScheduleTooLarge` when more than ``limit`` terms are live."""
    coef: dict[int, int] = {}
    for p in essential_periods(periods):
        if p > horizon:
            break
        new = dict(coef)
        new[p] = new.get(p, 0) + 1
        for d, c in coef.items():
            m = d // gcd(d, p) * p
            if m <= horizon:
                new[m] = new.get(m, 0) - c
        coef = {d: c for d, c in new.items() if c}
        if len(coef) > limit:
            raise ScheduleTooLarge(
                [q for q in periods if q <= p],
                f"more than {limit} inclusion–exclusion terms up to {_seconds(horizon)} s",
            )
    return coef


def coprime_base(numbers: Sequence[int]) -> list[int]:
    """Pairwise coprime integers > 1 of which every number is a product of
    powers (by gcd splitting; no factoring).

    >>> sorted(coprime_base([12, 18]))
    [2, 3]
    """
    base: list[int] = []
    todo = [n for n in numbers if n > 1]
    while todo:
        x = todo.pop()
        if x == 1:
            continue
        for i, b in enumerate(base):
            g = gcd(x, b)
            if g == 1:
                continue
            if g == b == x:
                break  # already in the base
            base[i] = base[-1]
            base.pop()
            todo += [g, b // g, x // g]
            break
        else:
            base.append(x)
    return base


def _valuation(n: int, b: int) -> int:
    k = 0
    while n % b == 0:
        n //= b
        k += 1
    return k


def _groups(reduced: Sequence[int]) -> list[tuple[list[int], list[int]]]:
    """(base elements, numbers) of each independent group."""
    base = coprime_base(reduced)
    parent = list(range(len(base)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    uses = [[j for j, b in enumerate(base) if r % b == 0] for r in reduced]
    for used in uses:
        for j in used[1:]:
            parent[find(j)] = find(used[0])
    groups: dict[int, tuple[list[int], list[int]]] = {}
    for j, b in enumerate(base):
        groups.setdefault(find(j), ([], []))[0].append(b)
    for r, used in zip(reduced, uses, strict=True):
        groups[find(used[0])][1].append(r)
    return list(groups.values())


def _unhit_inclusion_exclusion(numbers: Sequence[int], period: int) -> int:
    """Dates in [1, period] (a multiple of every number) divisible by none."""
    hit = sum(c * (period // d) for d, c in inclusion_exclusion(numbers, period, 1 << 30).items())
    return period - hit


def _unhit_lattice(base: Sequence[int], numbers: Sequence[int]) -> int:
    """Dates in [1, prod b^a_b] divisible by none of ``numbers`` (the sieve)."""
    import numpy as np

    top = {b: max(_valuation(r, b) for r in numbers) for b in base}
    # axes by modulus b^a ascending: the counts are contracted in that order,
    # in int64 while every partial sum stays below 2^62, then in Python ints
    axes = sorted(base, key=lambda b: b ** top[b])
    marked = np.zeros([top[b] + 1 for b in axes], dtype=bool)
    for r in numbers:
        marked[tuple(_valuation(r, b) for b in axes)] = True
    for axis in range(marked.ndim):  # upward closure: an OR-prefix along each axis
        view = np.moveaxis(marked, axis, 0)
        for k in range(1, view.shape[0]):
            np.logical_or(view[k], view[k - 1], out=view[k])
    counts: np.ndarray[Any, Any] = np.logical_not(marked).astype(np.int64)
    del marked
    bound = 1
    for b in axes:
        a = top[b]
        bound *= b**a
        if counts.dtype != object and bound >= _INT64_SAFE:
            counts = counts.astype(object)
        weights = [b ** (a - k) - b ** (a - k - 1) for k in range(a)] + [1]
        counts = np.tensordot(np.asarray(weights, dtype=counts.dtype), counts, axes=([0], [0]))
    return int(counts)


@dataclass(frozen=True)
class Schedule:
    """Compact schedule: the period (µs) of each sent stream, by stream id.

    ``hyperperiod_us`` is the paper's hyperperiod: the LCM of all subscription
    periods, derived streams included (a multiple of the LCM of the sent ones).
    Nothing is counted until asked.
    """

    periods_us: tuple[int, ...]
    hyperperiod_us: int

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

    @cached_property
    def essential_us(self) -> tuple[int, ...]:
        """The periods that are not multiples of another one, ascending."""
        return tuple(essential_periods(self.periods_us))

    def check_bounds(self) -> None:
        """Raise :class:`ScheduleTooLarge` if counting the slots would exceed
        the bound (nothing is allocated to find out)."""
        self._plan_count()

    def _plan_count(self) -> tuple[int, list[tuple[list[int], list[int], bool]]]:
        """(g, [(base, reduced numbers, by lattice?)]) after checking the bound."""
        ess = self.essential_us
        g = reduce(gcd, ess, 0)
        out: list[tuple[list[int], list[int], bool]] = []
        if len(ess) <= 1:
            return g, out  # one period: H / p slots
        for base, numbers in _groups([p // g for p in ess]):
            terms = (1 << len(numbers)) - 1
            cells = prod(max(_valuation(r, b) for r in numbers) + 1 for b in base)
            by_terms = terms <= min(cells, SUBSET_LIMIT)
            if not by_terms and cells > LATTICE_LIMIT:
                raise ScheduleTooLarge(
                    [r * g for r in numbers],
                    f"counting their slots needs {cells:,} lattice cells, over the planner's "
                    f"bound {LATTICE_LIMIT:,}; make some of these periods multiples of "
                    "others (e.g. 0.25, 0.5, 1, 2 s) or remove some",
                )
            out.append((base, numbers, not by_terms))
        return g, out

    @cached_property
    def messages_per_hyperperiod(self) -> int:
        """DATA frames (slots) per hyperperiod: the lattice sieve, per group."""
        if not self.periods_us:
            return 0
        g, groups = self._plan_count()
        if not groups:  # one essential period
            return self.hyperperiod_us // g
        unhit = 1
        period = 1  # L, the reduced LCM of the sent periods
        for base, numbers, lattice in groups:
            group_period = lcm(*numbers)
            period *= group_period
            unhit *= (
                _unhit_lattice(base, numbers)
                if lattice
                else _unhit_inclusion_exclusion(numbers, group_period)
            )
        return (self.hyperperiod_us // (g * period)) * (period - unhit)

    @cached_property
    def _period_us(self) -> int:
        return lcm(*self.periods_us)

    def count_until(self, t_us: int) -> int:
        """Number of slots whose date is in (0, t_us]. Past the first
        hyperperiod of the sent periods it is periodic; within it, the
        inclusion–exclusion terms up to the date (ScheduleTooLarge past
        :data:`TERM_LIMIT` of them)."""
        if t_us <= 0 or not self.periods_us:
            return 0
        whole, rest = divmod(t_us, self._period_us)
        per_period = self.messages_per_hyperperiod * self._period_us // self.hyperperiod_us
        return whole * per_period + self._count_within(rest)

    def _count_within(self, t_us: int) -> int:
        coef = inclusion_exclusion(self.periods_us, t_us, TERM_LIMIT)
        return sum(c * (t_us // d) for d, c in coef.items())

    def slot_date_us(self, slot: int) -> int:
        """Date (µs after the epoch) of slot ``slot``: whole periods of the sent
        streams skipped, then a short walk, or a bisection on the count (the
        walk again if that needs more than :data:`TERM_LIMIT` terms)."""
        if not self.periods_us:
            raise ValueError("an empty schedule has no slots")
        if slot < 0:
            raise ValueError("slot indexes start at 0")
        per_period = self.messages_per_hyperperiod * self._period_us // self.hyperperiod_us
        whole, k = divmod(slot, per_period)
        offset = whole * self._period_us
        if k >= WALK_LIMIT:
            try:
                return offset + self._bisect(k)
            except ScheduleTooLarge:
                pass
        for index, date, _ in self._walk(0, 0):
            if index == k:
                return offset + date
        raise AssertionError("unreachable")  # pragma: no cover

    def _bisect(self, k: int) -> int:
        g = reduce(gcd, self.periods_us)
        lo, hi = 0, (k + 1) * min(self.periods_us) // g  # in units of g
        coef = inclusion_exclusion(self.periods_us, hi * g, TERM_LIMIT)
        while lo < hi:
            mid = (lo + hi) // 2
            if sum(c * (mid * g // d) for d, c in coef.items()) >= k + 1:
                hi = mid
            else:
                lo = mid + 1
        return lo * g

    def _walk(self, start_index: int, start_us: int) -> Iterator[tuple[int, int, list[int]]]:
        heap = [(start_us // p * p + p, p) for p in sorted(set(self.periods_us))]
        heapq.heapify(heap)
        index = start_index
        while True:
            date = heap[0][0]
            due: list[int] = []
            while heap[0][0] == date:
                _, p = heapq.heappop(heap)
                due.append(p)
                heapq.heappush(heap, (date + p, p))
            yield index, date, due
            index += 1

    def iter_due_periods(self, start_slot: int = 0) -> Iterator[tuple[int, int, list[int]]]:
        """Slots from ``start_slot`` on, forever, as ``(index, date in µs,
        distinct periods due)``: the next-due heap over distinct periods."""
        if not self.periods_us:
            return iter(())
        if start_slot == 0:
            return self._walk(0, 0)
        start = self.slot_date_us(start_slot)
        return self._walk(start_slot, start - 1)

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
