"""Round trips, sizes and malformed input of the Python link codec."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st
from modd.link import codec
from modd.link.frames import (
    MAX_ACCEPTED_DELAY_MS,
    Aggregation,
    Config,
    ConfigAck,
    Data,
    Ping,
    ProtocolError,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
    value_kind,
)

S1_KINDS = [
    value_kind(ValueType.FLOAT32, a)
    for a in (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)
]


def test_scenario_frame_sizes() -> None:
    d = Data(
        False,
        0,
        0,
        1,
        [Value(True, 1.0, 0, 6), Value(True, 1.0, 0, 7), Value(True, 1.0), Value(True, 1.0)],
    )
    assert len(codec.encode_data(d, S1_KINDS)) == 21
    k2 = [value_kind(ValueType.FLOAT32, Aggregation.MIN)] * 19
    d2 = Data(False, 0, 0, 1, [Value(True, 1.0)] * 19)
    assert len(codec.encode_data(d2, k2)) == 79


@given(st.lists(st.integers(0, 2**64 - 1), max_size=30), st.integers(1, 255))
def test_status_and_ack_round_trip(counters: list[int], cid: int) -> None:
    for m in (Status(tuple(counters)), ConfigAck(cid, 0, 2**63)):
        (raw,) = codec.FrameSplitter().feed(codec.encode(m))
        assert codec.decode(raw) == m


@given(st.one_of(st.none(), st.integers(0, MAX_ACCEPTED_DELAY_MS)), st.integers(1, 255))
def test_config_accepted_delay_round_trip(delay: int | None, cid: int) -> None:
    """The optional trailing accepted delay (docs/protocol.md, "CONFIG"): absent, the
    frame is byte for byte the old one; present, one trailing varint."""
    topics = (TopicSpec("d.s.t", ValueType.FLOAT32, 4, 250_000),)
    streams = (StreamSpec(0, Aggregation.AVERAGE, 1_000_000),)
    m = Config(cid, 30, topics, streams, delay)
    wire = codec.encode(m)
    old = codec.encode(Config(cid, 30, topics, streams))
    if delay is None:
        assert wire == old
    else:  # one more varint, and the length prefix counts it
        assert wire[-len(codec.varint(delay)) :] == codec.varint(delay)
        assert len(wire) - len(old) in (len(codec.varint(delay)), len(codec.varint(delay)) + 1)
    (raw,) = codec.FrameSplitter().feed(wire)
    assert codec.decode(raw) == m


def test_config_accepted_delay_out_of_range() -> None:
    c = Config(
        1,
        0,
        (TopicSpec("a", ValueType.FLOAT32, 1),),
        (StreamSpec(0, Aggregation.MIN, 1),),
        MAX_ACCEPTED_DELAY_MS + 1,
    )
    with pytest.raises(ValueError, match="accepted delay"):
        codec.encode(c)


@given(
    st.lists(
        st.tuples(st.booleans(), st.floats(width=32, allow_nan=False), st.integers(1, 10000)),
        min_size=4,
        max_size=4,
    ),
    st.integers(0, 10**9),
    st.booleans(),
)
def test_data_round_trip(vals: list[tuple[bool, float, int]], slot: int, sync: bool) -> None:
    values = [
        Value(p, x, 0, n if i < 2 else 0) if p else Value() for i, (p, x, n) in enumerate(vals)
    ]
    d = Data(sync, 3, slot, slot & 0xFF, values)
    wire = codec.encode_data(d, S1_KINDS)
    (raw,) = codec.FrameSplitter().feed(wire)
    back = codec.decode_data(raw, S1_KINDS)
    assert [v.present for v in back.values] == [v.present for v in values]
    for a, b in zip(back.values, values, strict=True):
        if b.present:
            assert a.number == b.number and a.count == b.count


def test_splitter_handles_byte_by_byte() -> None:
    wire = codec.encode(Ping(b"ab")) + codec.encode(Ping(b"c"))
    s = codec.FrameSplitter()
    got = []
    for b in wire:
        got += s.feed(bytes([b]))
    assert [codec.decode(f) for f in got] == [Ping(b"ab"), Ping(b"c")]


def test_truncated_and_trailing_data_rejected() -> None:
    d = Data(False, 0, 0, 1, [Value(True, 1.0, 0, 6)] * 2 + [Value(True, 1.0)] * 2)
    wire = codec.encode_data(d, S1_KINDS)
    (raw,) = codec.FrameSplitter().feed(wire)
    with pytest.raises(ProtocolError, match="truncated"):
        codec.decode_data(codec.RawFrame(raw.type, raw.body[:-1], 0), S1_KINDS)
    with pytest.raises(ProtocolError, match="trailing"):
        codec.decode_data(codec.RawFrame(raw.type, raw.body + b"\0", 0), S1_KINDS)
