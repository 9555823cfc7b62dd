"""Derived windows by window index (modd.subbroker.derivation, sans-I/O): whatever
the order the source windows arrive in (a NACK's resend seconds late, after later
ones), every derived window whose sources all arrive is completed once, equal to
the aggregate of its raw samples (the oracle: modd_plan.derive.aggregate on the
samples, not the merge under test); partial windows are bounded in number and age."""

from __future__ import annotations

import random
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from modd.subbroker import derivation
from modd.subbroker.derivation import Assembly
from modd.subbroker.fanout import FanOut
from modd_plan.derive import aggregate
from modd_plan.streams import Source, StreamKey

Q = Fraction(1, 4)


@settings(max_examples=200, deadline=None)
@given(
    factor=st.integers(1, 8),
    windows=st.integers(1, 40),
    seed=st.integers(0, 2**32),
    lost=st.sets(st.integers(1, 320), max_size=10),
)
def test_any_arrival_order_completes_each_window_once(
    factor: int, windows: int, seed: int, lost: set[int]
) -> None:
    rng = random.Random(seed)
    n = factor * windows
    order = [i for i in range(1, n + 1) if i not in lost]
    # late, not shuffled at random: each window at most ~3 s (12 quarters) late
    order.sort(key=lambda i: i + rng.uniform(0, 12))
    a = Assembly(((0, factor),), 250_000 * factor)
    done: list[int] = []
    for i in order:
        for j, parts in a.add(0, i, i):
            assert parts == [list(range((j - 1) * factor + 1, j * factor + 1))]
            done.append(j)
    covers = {j: set(range((j - 1) * factor + 1, j * factor + 1)) for j in range(1, windows + 1)}
    want = [j for j, c in covers.items() if not lost & c]
    assert sorted(done) == want  # every complete window, each once
    partial = [j for j, c in covers.items() if lost & c and c - lost]
    assert a.pending + a.given_up == len(partial)  # wait, or given up when too old


def test_a_late_window_then_its_twin_is_completed_once() -> None:
    a = Assembly(((0, 4),), 1_000_000)
    assert a.add(0, 1, 1) == a.add(0, 2, 2) == a.add(0, 4, 4) == []
    assert a.add(0, 5, 5) == []  # the next window begins: window 1 still waits for 3
    assert a.add(0, 3, 3) == [(1, [[1, 2, 3, 4]])]
    assert a.add(0, 3, 3) == []


def test_empty_source_windows_complete_the_derived_one() -> None:
    """An absent source window (no sample) arrived: it is not a lost one."""
    a = Assembly(((0, 2),), 500_000)
    assert a.add(0, 1, None) == []
    assert a.add(0, 2, None) == [(1, [[None, None]])]


def test_pending_windows_are_bounded_in_number_and_age() -> None:
    a = Assembly(((0, 2),), 500_000)
    for j in range(1, 1000):  # every other source window lost: nothing completes
        a.add(0, 2 * j, float(j))
    assert a.pending <= derivation.MAX_PENDING
    assert a.pending <= derivation.HOLD_US // 500_000 + 1
    assert a.given_up == 999 - a.pending
    assert a.add(0, 1, 0.0) == []  # far too late: given up, left to backfill


def test_pair_sources_of_other_periods() -> None:
    """AVERAGE over 1 s from SUM/0.5 s and COUNT/0.25 s, arriving out of order."""
    a = Assembly(((1, 2), (0, 4)), 1_000_000)
    arrivals = [(0, 1, 2), (1, 2, 6.0), (0, 4, 1), (0, 3, 0), (1, 1, 3.0), (0, 2, 1)]
    out = [o for sid, i, w in arrivals for o in a.add(sid, i, w)]
    assert out == [(1, [[3.0, 6.0], [2, 1, 0, 1]])]


@pytest.mark.parametrize("agg,source", [("AVERAGE", "AVERAGE"), ("MIN", "MIN"), ("SUM", "ALL")])
def test_fanout_derives_the_covering_window_of_a_late_slot(agg: str, source: str) -> None:
    """The fault of the lossy radio: quarter 3 comes 2.5 s late, after quarters 4..13;
    the 2 s window it belongs to is still delivered, once, equal to the raw aggregate."""
    rng = random.Random(5)
    sent = [StreamKey("d.s.x", source, Q)]
    fan = FanOut(sent)
    fan.route(StreamKey("d.s.x", agg, Fraction(2)), (Source(sent[0], 8),), "slow")
    quarters = {q: [rng.uniform(-9, 9) for _ in range(rng.randint(0, 5))] for q in range(1, 25)}
    order = [q for q in quarters if q != 3]
    order.insert(12, 3)
    outs = [
        o
        for q in order
        for o in fan.on_slot(q - 1, q * 250_000, {0: aggregate(source, quarters[q])})
    ]
    assert sorted(o.end_us for o in outs) == [2_000_000, 4_000_000, 6_000_000]
    for o in outs:
        k = o.end_us // 2_000_000
        raw = [x for q in range(8 * k - 7, 8 * k + 1) for x in quarters[q]]
        want = aggregate(agg, raw)
        if agg == "AVERAGE":
            assert o.value[0] == pytest.approx(want[0]) and o.value[1] == want[1]
        else:
            assert o.value == pytest.approx(want)
    assert fan.pending() == 0
