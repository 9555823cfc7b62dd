"""The base-station receiver: slot numbering, windows, sync frames, config switches."""

from __future__ import annotations

import pytest
from modd.link import codec
from modd.link.frames import (
    Aggregation,
    Config,
    Data,
    ProtocolError,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
)
from modd.link.receiver import Receiver
from modd.link.schedule import SlotIterator

CFG = Config(
    1,
    0,
    (TopicSpec("x", ValueType.FLOAT32, 1),),
    (StreamSpec(0, Aggregation.MIN, 500_000), StreamSpec(0, Aggregation.COUNT, 1_000_000)),
)
EPOCH = 1_000_000_000_000


def frame(d: Data, slot_streams: tuple[int, ...], cfg: Config = CFG) -> codec.RawFrame:
    kinds = [cfg.kinds()[s] for s in slot_streams]
    (raw,) = codec.FrameSplitter().feed(codec.encode_data(d, kinds))
    return raw


def test_windows_are_labelled_from_the_epoch() -> None:
    rx = Receiver()
    rx.add_config(CFG, EPOCH)
    w = rx.on_frame(frame(Data(True, 1, 0, 0, [Value(True, 2.0)]), (0,)))
    assert [(x.stream, x.start_ns, x.end_ns, x.value.number) for x in w] == [
        (0, EPOCH, EPOCH + 500_000_000, 2.0)
    ]
    w = rx.on_frame(frame(Data(False, 0, 0, 1, [Value(True, 1.0), Value(True, count=50)]), (0, 1)))
    assert [(x.stream, x.start_ns) for x in w] == [(0, EPOCH + 500_000_000), (1, EPOCH)]
    assert w[1].value.count == 50


def test_gap_needs_a_sync_frame() -> None:
    rx = Receiver()
    rx.add_config(CFG, EPOCH)
    rx.on_frame(frame(Data(True, 1, 0, 0, [Value(True, 2.0)]), (0,)))
    with pytest.raises(ProtocolError, match="sequence"):
        rx.on_frame(frame(Data(False, 0, 0, 2, [Value(True, 1.0)]), (0,)))
    w = rx.on_frame(frame(Data(True, 1, 6, 6, [Value(True, 1.0)]), (0,)))
    assert w[0].slot == 6 and w[0].end_ns == EPOCH + 3_500_000_000


def test_data_before_sync_and_unknown_config() -> None:
    rx = Receiver()
    with pytest.raises(ProtocolError):
        rx.on_frame(frame(Data(False, 0, 0, 0, [Value(True, 2.0)]), (0,)))
    with pytest.raises(ProtocolError, match="unknown config"):
        rx.on_frame(frame(Data(True, 9, 0, 0, [Value(True, 2.0)]), (0,)))


def test_slot_iterator_never_materialises_the_hyperperiod() -> None:
    it = SlotIterator([1_000_003, 999_983])
    last = 0
    for _ in range(20000):
        s = next(it)
        assert s.offset_us > last
        last = s.offset_us
    with pytest.raises(ValueError):
        SlotIterator([0])
