"""Frame sizes and predicted link bytes."""

from __future__ import annotations

from fractions import Fraction

from modd_plan.linkcost import (
    EXACT_WALK_LIMIT,
    data_frame_bytes,
    plain_message_bytes,
    predict,
    varint_size,
    window_value_bytes,
)
from modd_plan.schedule import Schedule


def test_varint_and_frame_sizes() -> None:
    assert [varint_size(n) for n in (0, 127, 128, 16383, 16384)] == [1, 1, 2, 2, 3]
    assert data_frame_bytes(18, 4) == 1 + 2 + 18
    assert data_frame_bytes(18, 9, some_absent=True) == 1 + 2 + 2 + 18
    assert data_frame_bytes(126, 1) == 2 + 2 + 126  # body 128 B needs a 2-byte length
    assert data_frame_bytes(125, 1) == 1 + 2 + 125


def test_window_value_bytes_per_aggregation() -> None:
    six = Fraction(6)
    assert window_value_bytes("MIN", "float32", six) == 4
    assert window_value_bytes("MAX", "float64", six) == 8
    assert window_value_bytes("AVERAGE", "float32", six) == 5
    assert window_value_bytes("AVERAGE", "int", six) == 9
    assert window_value_bytes("AVERAGE", "bool", six) == 5
    assert window_value_bytes("COUNT", "bool", Fraction(300)) == 2
    assert window_value_bytes("SUM", "bool", six) == 1
    assert window_value_bytes("SUM", "int", six) == 4
    assert window_value_bytes("ALL", "float32", Fraction(25, 2)) == 1 + 50
    assert window_value_bytes("FIRST", "bool", six) == 1


def test_predict_walks_small_schedules_and_estimates_large_ones() -> None:
    sched = Schedule.from_periods_us([500_000, 1_000_000])
    cost = predict(sched, [Fraction(4), Fraction(4)], {"a": (Fraction(1, 10), 10)})
    # per second: frame at 0.5 (1 value) and at 1.0 (2 values)
    assert cost.frames_per_s == 2
    assert cost.drone_to_base == (1 + 2 + 4) + (1 + 2 + 8) + 2 * 52
    assert cost.base_to_drone == 2 * 52
    assert cost.plain_pubsub == 10 * (52 + 10)
    assert cost.plain_pubsub_acks == 10 * 52
    coprime = [p * 1000 for p in (3, 7, 11, 13, 17, 19, 23)]
    big = Schedule.from_periods_us(coprime)
    assert big.messages_per_hyperperiod > EXACT_WALK_LIMIT
    estimate = predict(big, [Fraction(4)] * 7, {})
    values_per_s = sum(4 / (p / 1e6) for p in coprime)
    expected = values_per_s + estimate.frames_per_s * (1 + 2 + 52)
    assert abs(estimate.drone_to_base - expected) < 1e-6 * expected


def test_plain_message_carries_the_topic_name() -> None:
    assert plain_message_bytes("usv.a.x", "float32") == 4 + 7 + 4


TYPES = ["float32", "float64", "int", "bool"]
AGGS = ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM"]


def test_frame_size_matches_the_python_link_codec() -> None:
    """Cross-check against the real encoder (runtime/python, docs/protocol.md):
    one frame per (type, aggregation), 6 samples per window, ints whose
    zigzag varint takes INT_VALUE_BYTES."""
    import modd.link.codec as codec
    import modd.link.frames as frames

    big_int = 2**21  # zigzag 2**22: a 4-byte varint
    for vtype in TYPES:
        for agg in AGGS:
            kind = frames.value_kind(frames.ValueType.parse(vtype), frames.Aggregation[agg])
            sample: float | int = big_int if vtype == "int" else 1 if vtype == "bool" else 1.5
            integer = 6 if agg == "SUM" and vtype == "bool" else int(sample)
            value = frames.Value(
                present=True, number=float(sample), integer=integer, count=6, samples=[sample] * 6
            )
            data = frames.Data(sync=False, config_id=0, slot=0, seq8=0, values=[value])
            encoded = codec.encode_data(data, [kind])
            predicted = data_frame_bytes(int(window_value_bytes(agg, vtype, Fraction(6))), 1)
            assert len(encoded) == predicted, (vtype, agg)


def test_ceil_of_sums_is_the_ceiling_of_the_fraction_sum() -> None:
    """The slot walks' integer sums on a common denominator against the
    Fraction sum they replace, the fallback for huge denominators included."""
    import math
    import random
    from fractions import Fraction

    from modd_plan.linkcost import ceil_of_sums

    rng = random.Random(3)
    for case in range(400):
        dens = (
            [1, 2, 3, 4, 7, 10, 25, 1000]
            if case % 2
            else [rng.randrange(2, 10**40) | 1 for _ in range(3)]
        )
        values = {k: Fraction(rng.randrange(0, 10**6), rng.choice(dens)) for k in range(12)}
        ceil_sum = ceil_of_sums(values)
        for _ in range(5):
            keys = rng.sample(range(12), rng.randint(0, 12))
            assert ceil_sum(keys) == math.ceil(sum((values[k] for k in keys), Fraction(0)))
    assert ceil_of_sums({})([]) == 0
