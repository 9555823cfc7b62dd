"""Datagram transports (udp, serial): the shared vectors in
runtime/vectors/datagram.json checked against an independent computation of
the tags (hashlib/hmac directly) and the stream codec's values, plus forged,
reflected, replayed and corrupt datagrams, which are dropped before decoding."""

from __future__ import annotations

import hashlib
import hmac
import json
import random
import struct
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.datagram import (
    BASE_TO_DRONE,
    DRONE_TO_BASE,
    Forged,
    ReplayWindow,
    decode_nack,
    extend16,
    session_key,
    verify_control,
    verify_data,
)
from modd.link.frames import Aggregation, ProtocolError, ValueType, value_kind
from modd.link.serialframe import Deframer, cobs_decode, cobs_encode, crc16, encode_frame

VECTORS = json.loads((Path(__file__).resolve().parents[2] / "vectors" / "datagram.json")
                     .read_text())
KEY = bytes.fromhex(VECTORS["session_key"])
BY_NAME: dict[str, dict[str, Any]] = {v["name"]: v for v in VECTORS["vectors"]}
S1_KINDS = [value_kind(ValueType.FLOAT32, a) for a in
            (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)]
DIRS = {"D": DRONE_TO_BASE, "B": BASE_TO_DRONE}


def _hmac_tag(direction: bytes, seq: int, body: bytes, n: int) -> bytes:
    return hmac.new(KEY, direction + seq.to_bytes(8, "little") + body, hashlib.sha256).digest()[:n]


def test_session_key_is_hmac_of_the_handshake_nonces() -> None:
    psk = bytes.fromhex(VECTORS["key"])
    cn, sn = bytes.fromhex(VECTORS["client_nonce"]), bytes.fromhex(VECTORS["server_nonce"])
    assert session_key(psk, cn, sn) == KEY
    assert hmac.new(psk, b"MODD1K" + cn + sn, hashlib.sha256).digest() == KEY


def test_data_datagram_layout_and_tag() -> None:
    v = BY_NAME["data_scenario1_5_slots"]
    raw = bytes.fromhex(v["hex"])
    assert raw[0] == 0x30 and raw[1] == 1 and struct.unpack_from("<H", raw, 2)[0] == 70000 & 0xFFFF
    assert raw[-4:] == _hmac_tag(b"D", 70000, raw[:-4], 4)
    assert len(raw) == 4 + 5 * 18 + 4  # the planner's 98 B (linkbudget)
    got = verify_data(raw, KEY, DRONE_TO_BASE, v["expected_slot"])
    assert (got.config_id, got.slot, got.slot_count) == (1, 70000, None)
    assert got.values == b"".join(bytes.fromhex(s) for s in v["slots"])
    # each slot decodes with the stream codec's value layout (docs/protocol.md, DATA)
    r = codec.Reader(got.values)
    for i in range(5):
        vals = [codec._get_value(r, k) for k in S1_KINDS]
        assert vals[0].number == 0.5 + i and vals[0].count == 6 and vals[2].number == 9.75 - i
    r.end()


def test_bitmap_datagram_crosses_the_16_bit_wrap() -> None:
    v = BY_NAME["data_bitmap"]
    raw = bytes.fromhex(v["hex"])
    got = verify_data(raw, KEY, DRONE_TO_BASE, v["expected_slot"])
    assert got.slot == 65535 and got.slot_count == 2 and got.stream_count == 8
    assert got.presence == bytes([0b01011111])
    assert got.values == b"".join(bytes.fromhex(s) for s in v["slots"])


def test_control_datagrams() -> None:
    nack = BY_NAME["control_nack"]
    raw = bytes.fromhex(nack["hex"])
    assert raw[-8:] == _hmac_tag(b"B", 3, raw[:-8], 8)
    counter, frame = verify_control(raw, KEY, BASE_TO_DRONE)
    f = codec.split_frame(frame)
    assert counter == 3 and f is not None and f.type == 0x09
    assert decode_nack(f.body) == [tuple(r) for r in nack["ranges"]]
    counter, frame = verify_control(bytes.fromhex(BY_NAME["control_ping"]["hex"]), KEY,
                                    BASE_TO_DRONE)
    f = codec.split_frame(frame)
    assert counter == 4 and f is not None and f.type == 0x05 and f.body == b"\x07\x01"
    hello = bytes.fromhex(BY_NAME["handshake_hello"]["hex"])
    assert hello[0] == 0x41 and codec.split_frame(hello[1:]) is not None


def test_serial_frame_vector() -> None:
    v = BY_NAME["serial_data_scenario1_5_slots"]
    frame, datagram = bytes.fromhex(v["hex"]), bytes.fromhex(v["datagram"])
    assert frame[-1] == 0 and 0 not in frame[:-1]
    body = cobs_decode(frame[:-1])
    assert body[:-2] == datagram and body[-2:] == crc16(datagram).to_bytes(2, "little")
    assert len(frame) == len(datagram) + 4  # the planner's serial framing (linkbudget)
    assert Deframer(252).feed(frame) == [datagram]


@pytest.mark.parametrize("case", VECTORS["invalid"], ids=lambda c: c["name"])
def test_invalid_datagrams_are_dropped(case: dict[str, Any]) -> None:
    raw = bytes.fromhex(case["hex"])
    window = ReplayWindow()
    if case["name"] == "replay":
        first = verify_data(raw, KEY, DIRS[case["direction"]], case["expected_slot"])
        assert window.accept(first.slot)
        again = verify_data(raw, KEY, DIRS[case["direction"]], case["expected_slot"])
        assert not window.accept(again.slot)
        return
    with pytest.raises(Forged):
        verify_data(raw, KEY, DIRS[case["direction"]], case["expected_slot"])


def test_random_datagrams_never_verify() -> None:
    rng = random.Random(14)
    forged = 0
    for _ in range(3000):
        raw = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 80)))
        try:
            verify_data(raw, KEY, DRONE_TO_BASE, 70000)
        except Forged:
            forged += 1
        except ProtocolError:
            pass
        else:
            pytest.fail(f"random bytes verified: {raw.hex()}")
    assert forged > 0


def test_extend16_and_replay_window() -> None:
    assert extend16(0xFFFF, 0x10002) == 0xFFFF
    assert extend16(2, 0xFFFE) == 0x10002
    assert extend16(5, 0) == 5
    w = ReplayWindow(size=8)
    assert w.accept(10) and w.accept(12) and w.accept(11)
    assert not w.accept(11)
    assert w.accept(30)
    assert not w.accept(22)  # older than the window
    assert w.accept(23) and len(w.seen) <= 9


def test_cobs_round_trip_and_bounded_deframer() -> None:
    rng = random.Random(3)
    for n in [1, 2, 253, 254, 255, 508, 600]:
        d = bytes(rng.choice([0, rng.randrange(1, 256)]) for _ in range(n))
        assert cobs_decode(cobs_encode(d)) == d
        assert Deframer(1000).feed(encode_frame(d)) == [d]
    df = Deframer(16)
    good = encode_frame(b"ok")
    stream = bytes(range(1, 60)) + b"\x00" + good + bytearray(good[:-3]) + b"\x55\x00" + good
    assert df.feed(stream) == [b"ok", b"ok"]
    assert df.oversized == 1 and df.corrupt == 1


def test_planner_serial_and_datagram_sizes_match_the_codec() -> None:
    """linkbudget's size formulas (the plan's bytes/s) against real encodings."""
    from modd.link.datagram import DataDatagram, encode_data
    from modd_plan.linkbudget import DGRAM_HEADER_BYTES, TAG_BYTES, serial_frame_bytes

    for n in range(1, 700):
        worst = bytes([0x55]) * n  # no zero byte: COBS's largest overhead
        assert len(encode_frame(worst)) == serial_frame_bytes(n), n
        assert len(encode_frame(bytes(n))) <= serial_frame_bytes(n)
    for slots in (1, 4, 5):
        raw = encode_data(DataDatagram(1, 9, [b"\x01" * 18] * slots), KEY, DRONE_TO_BASE)
        assert len(raw) == DGRAM_HEADER_BYTES + 18 * slots + TAG_BYTES
