"""NACK recovery: a sender with its resend ring and a receiver with its gap
tracker over a lossy, reordering, duplicating channel (seeded); the oracle is
the set of slots sent."""

from __future__ import annotations

import random

from modd.link.datagram import DRONE_TO_BASE, DataDatagram, ReplayWindow, encode_data, verify_data
from modd.link.resend import GapTracker, ResendRing

KEY = bytes(32)


def _run(loss: float, seed: int, slots: int = 2000, per_datagram: int = 4) -> tuple[set[int], int]:
    rng = random.Random(seed)
    ring = ResendRing(max_datagrams=64)
    gaps = GapTracker(max_asks=5)
    window = ReplayWindow(1024)
    got: set[int] = set()
    in_flight: list[tuple[float, bytes]] = []
    replayed = 0
    t = 0.0

    def channel(raw: bytes, now: float) -> None:
        if rng.random() < loss:
            return
        in_flight.append((now + rng.uniform(0.05, 0.4), raw))  # jitter reorders
        if rng.random() < 0.02:
            in_flight.append((now + rng.uniform(0.05, 0.4), raw))  # duplicated

    for first in range(0, slots, per_datagram):
        t = first * 0.25
        raw = encode_data(DataDatagram(1, first, [b"\x01"] * per_datagram), KEY, DRONE_TO_BASE)
        ring.add(first, per_datagram, raw)
        channel(raw, t)
        # deliver what is due, then NACK
        in_flight.sort()
        while in_flight and in_flight[0][0] <= t:
            _, d = in_flight.pop(0)
            v = verify_data(d, KEY, DRONE_TO_BASE, max(gaps.next, 0))
            if not window.accept(v.slot):
                replayed += 1
                continue
            got.update(range(v.slot, v.slot + per_datagram))
            gaps.received(v.slot, per_datagram, t)
        ranges = gaps.due(t, every=1.0)
        if ranges and rng.random() >= loss:  # the NACK itself may be lost
            for d in ring.lookup(ranges):
                channel(d, t)
    return got, replayed


def test_no_loss_no_nack() -> None:
    gaps = GapTracker()
    for first in range(0, 100, 4):
        gaps.received(first, 4, first * 0.25)
    assert gaps.due(100.0, 1.0) == [] and gaps.missing == 0


def test_recovery_at_5_and_20_percent_loss() -> None:
    for loss, target in ((0.05, 0.999), (0.20, 0.99)):
        got, _ = _run(loss, seed=14)
        expected = set(range(0, 1990))  # the tail may still be in flight
        share = len(got & expected) / len(expected)
        assert share >= target, (loss, share)


def test_duplicates_and_reordering_are_counted_not_delivered_twice() -> None:
    got, replayed = _run(0.0, seed=3)
    assert replayed > 0
    assert len(got) >= 1990


def test_ring_is_bounded_and_reports_slots_too_old() -> None:
    ring = ResendRing(max_datagrams=4, max_bytes=1000)
    for first in range(0, 40, 4):
        ring.add(first, 4, bytes([first]) * 10)
    assert len(ring.ring) == 4 and ring.bytes == 40
    assert ring.lookup([(0, 4)]) == [] and ring.too_old == 1
    assert ring.lookup([(30, 6)]) == [bytes([28]) * 10, bytes([32]) * 10]


def test_gap_given_up_after_max_asks() -> None:
    gaps = GapTracker(max_asks=2)
    gaps.received(0, 1, 0.0)
    gaps.received(10, 1, 0.0)
    assert gaps.due(0.0, 1.0) == [(1, 9)]
    assert gaps.due(0.5, 1.0) == []
    assert gaps.due(1.0, 1.0) == [(1, 9)]
    assert gaps.due(2.0, 1.0) == [] and gaps.lost == 9 and gaps.missing == 0


def test_an_answer_in_progress_is_not_asked_again() -> None:
    """A resend that arrives in pieces (a slow radio) moves the next ask of what is
    left of the gap to a full interval after the latest piece: no duplicate NACK
    while the answer is on its way."""
    gaps = GapTracker(max_asks=5)
    gaps.received(0, 1, 0.0)
    gaps.received(100, 1, 0.0)
    assert gaps.due(0.0, 1.0) == [(1, 99)]
    gaps.received(1, 30, 0.9)  # the first pieces of the answer
    assert gaps.due(1.0, 1.0) == []  # the rest is still coming
    gaps.received(31, 30, 1.8)
    assert gaps.due(2.5, 1.0) == []
    assert gaps.due(2.9, 1.0) == [(61, 39)]  # silent for a full interval: asked again
    assert gaps.lost == 0


def test_docstring_examples() -> None:
    import doctest

    from modd.link import datagram, resend, serialframe

    for module in (datagram, resend, serialframe):
        result = doctest.testmod(module)
        assert result.attempted > 0 and result.failed == 0, module.__name__
