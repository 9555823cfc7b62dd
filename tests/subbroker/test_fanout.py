"""Fan-out: derived windows equal the aggregate of the raw samples they
cover; incomplete windows are never delivered."""

from __future__ import annotations

import random
from fractions import Fraction

import pytest
from modd.link.frames import Value
from modd.subbroker.fanout import FanOut, Output, period_us
from modd_plan.derive import aggregate
from modd_plan.streams import Source, StreamKey
from modd_plan.windows import window_of

Q = Fraction(1, 4)


def _drive(
    fan: FanOut,
    sent: list[StreamKey],
    samples_per_quarter: list[list[float]],
    start_quarter: int = 1,
) -> list[Output]:
    """Feed quarter-second windows of every sent stream (all of period 0.25 s)."""
    outs = []
    for q, samples in enumerate(samples_per_quarter, start=start_quarter):
        windows = {sid: aggregate(s.aggregation, samples) for sid, s in enumerate(sent)}
        outs += fan.on_slot(q - 1, q * 250_000, windows)
    return outs


@pytest.mark.parametrize(
    "agg,source",
    [
        ("MIN", "MIN"),
        ("MAX", "MAX"),
        ("AVERAGE", "AVERAGE"),
        ("FIRST", "FIRST"),
        ("LAST", "LAST"),
        ("COUNT", "AVERAGE"),
        ("SUM", "ALL"),
        ("MAX", "ALL"),
    ],
)
def test_derived_window_equals_aggregate_of_raw_samples(agg: str, source: str) -> None:
    rng = random.Random(7)
    sent = [StreamKey("d.s.x", source, Q)]
    target = StreamKey("d.s.x", agg, Fraction(2))
    fan = FanOut(sent)
    fan.route(target, (Source(sent[0], 8),), "slow")
    quarters = [[rng.uniform(-5, 5) for _ in range(rng.randint(0, 7))] for _ in range(32)]
    outs = _drive(fan, sent, quarters)
    assert [o.end_us for o in outs] == [2_000_000, 4_000_000, 6_000_000, 8_000_000]
    for k, out in enumerate(outs):
        raw = [x for q in quarters[8 * k : 8 * k + 8] for x in q]
        expected = aggregate(agg, raw)
        if agg == "AVERAGE" and expected is not None:
            assert out.value[0] == pytest.approx(expected[0], rel=1e-12)
            assert out.value[1] == expected[1]
        elif agg == "SUM":
            assert out.value == pytest.approx(expected, rel=1e-12)
        else:
            assert out.value == expected
        assert out.subscribers == ("slow",)


def test_pair_rule_average_from_sum_and_count() -> None:
    sent = [StreamKey("d.s.x", "COUNT", Q), StreamKey("d.s.x", "SUM", Fraction(1, 2))]
    target = StreamKey("d.s.x", "AVERAGE", Fraction(1))
    fan = FanOut(sent)
    fan.route(target, (Source(sent[1], 2), Source(sent[0], 4)), "avg")
    samples = [[1.0, 2.0], [3.0], [], [6.0]]
    outs = []
    for q, xs in enumerate(samples, start=1):
        windows: dict[int, float] = {0: len(xs)}
        if q % 2 == 0:
            windows[1] = sum(samples[q - 2]) + sum(xs)
        outs += fan.on_slot(q - 1, q * 250_000, windows)
    assert [(o.value, o.end_us) for o in outs] == [((3.0, 4), 1_000_000)]


def test_window_spanning_a_gap_is_not_delivered() -> None:
    sent = [StreamKey("d.s.x", "MIN", Q)]
    fan = FanOut(sent)
    fan.route(StreamKey("d.s.x", "MIN", Fraction(1)), (Source(sent[0], 4),), "s")
    fan.route(sent[0], (), "q")
    outs = []
    for q in (1, 2, 4, 5, 6, 7, 8):  # quarter 3 lost with the link
        outs += fan.on_slot(q - 1, q * 250_000, {0: float(q)})
    slow = [o for o in outs if o.stream.period == 1]
    assert [(o.end_us, o.value) for o in slow] == [(2_000_000, 5.0)]
    assert len([o for o in outs if o.stream.period == Q]) == 7


def test_subscription_starting_inside_a_window_waits_for_a_complete_one() -> None:
    sent = [StreamKey("d.s.x", "MAX", Q)]
    fan = FanOut(sent)
    outs = fan.on_slot(0, 250_000, {0: 1.0})
    fan.route(StreamKey("d.s.x", "MAX", Fraction(1, 2)), (Source(sent[0], 2),), "late")
    outs += fan.on_slot(1, 500_000, {0: 9.0})
    assert outs == []  # the first quarter arrived before the route kept history
    for q in (3, 4):
        outs += fan.on_slot(q - 1, q * 250_000, {0: float(q)})
    assert [(o.end_us, o.value) for o in outs] == [(1_000_000, 4.0)]


def test_absent_sent_window_is_delivered_as_none_and_unroute() -> None:
    sent = [StreamKey("d.s.x", "MIN", Q)]
    fan = FanOut(sent)
    fan.route(sent[0], (), "a")
    fan.route(sent[0], (), "b")
    (out,) = fan.on_slot(0, 250_000, {0: None})
    assert out.value is None and out.subscribers == ("a", "b")
    assert fan.unroute("a") and not fan.unroute("a")
    assert fan.routes() == {"d.s.x/MIN/0.25": ("b",)}
    assert fan.unroute("b") and fan.routes() == {}


def test_route_rejects_a_stream_not_sent() -> None:
    fan = FanOut([StreamKey("d.s.x", "MIN", Q)])
    with pytest.raises(ValueError, match="not sent"):
        fan.route(StreamKey("d.s.x", "MAX", Q), (), "s")


def test_period_us_and_window_of() -> None:
    assert period_us(StreamKey("d.s.x", "MIN", Fraction(1, 4))) == 250_000
    with pytest.raises(ValueError):
        period_us(StreamKey("d.s.x", "MIN", Fraction(1, 3)))
    assert window_of(Value(present=False), "MIN", "float32") is None
    assert window_of(Value(True, number=2.5, count=4), "AVERAGE", "float32") == (2.5, 4)
    assert window_of(Value(True, count=0), "AVERAGE", "float32") is None
    assert window_of(Value(True, count=9), "COUNT", "int") == 9
    assert window_of(Value(True, integer=1), "LAST", "bool") is True
    assert window_of(Value(True, integer=-3), "SUM", "int") == -3
    assert window_of(Value(True, samples=[1, 0]), "ALL", "bool") == [True, False]
