"""Datagram transports (udp, serial): the shared vectors in
contracts/vectors/link/datagram.json checked against an independent computation of
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
from hypothesis import given
from hypothesis import strategies as st
from modd.link import codec
from modd.link.datagram import (
    BASE_TO_DRONE,
    DRONE_TO_BASE,
    ControlPieces,
    Forged,
    ReplayWindow,
    decode_nack,
    encode_control_fragments,
    encode_fragments,
    extend16,
    session_key,
    slot_bitmap_body,
    verify_control,
    verify_control_fragment,
    verify_data,
    verify_fragment,
    verify_slot_body,
)
from modd.link.dgreceiver import DatagramReceiver, Reassembly
from modd.link.frames import Aggregation, ProtocolError, ValueType, value_kind
from modd.link.serialframe import Deframer, cobs_decode, cobs_encode, crc16, encode_frame

LINK_VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "link"
VECTORS = json.loads((LINK_VECTORS / "datagram.json").read_text())
KEY = bytes.fromhex(VECTORS["session_key"])
BY_NAME: dict[str, dict[str, Any]] = {v["name"]: v for v in VECTORS["vectors"]}
S1_KINDS = [
    value_kind(ValueType.FLOAT32, a)
    for a in (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)
]
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
    counter, frame = verify_control(
        bytes.fromhex(BY_NAME["control_ping"]["hex"]), KEY, BASE_TO_DRONE
    )
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
    if case.get("kind") == "control_fragment":
        if case["name"] == "control_fragment_index_beyond_count":
            with pytest.raises(ProtocolError) as err:
                verify_control_fragment(raw, KEY, DIRS[case["direction"]])
            assert err.value.offset == 3
            return
        with pytest.raises(Forged):
            verify_control_fragment(raw, KEY, DIRS[case["direction"]])
        return
    verify = verify_fragment if case.get("kind") == "fragment" else verify_data
    if case["name"] == "fragment_index_beyond_count":
        with pytest.raises(ProtocolError) as err:
            verify(raw, KEY, DIRS[case["direction"]], case["expected_slot"])
        assert err.value.offset == 4
        return
    with pytest.raises(Forged):
        verify(raw, KEY, DIRS[case["direction"]], case["expected_slot"])


def test_control_fragment_vector_layout_and_reassembly() -> None:
    """A control message larger than the packet, checked byte by byte against an
    independent layout (varint by hand, hmac directly) and put back together."""
    v = BY_NAME["control_fragments_of_a_config"]
    frames, frags = bytes.fromhex(v["frames"]), [bytes.fromhex(f) for f in v["fragments"]]
    room = v["max_datagram"] - 15
    assert len(frags) == -(-len(frames) // room) > 1
    for i, f in enumerate(frags):
        counter = v["counter"] + i
        head = bytes([0x42, 0x80 | (counter & 0x7F), counter >> 7, i << 4 | (len(frags) - 1)])
        assert f[:4] == head and len(f) <= v["max_datagram"]
        assert f[4:-8] == frames[i * room : (i + 1) * room]
        assert f[-8:] == _hmac_tag(b"B", counter, f[:-8], 8)
    assert (
        encode_control_fragments(v["counter"], frames, v["max_datagram"], KEY, BASE_TO_DRONE)
        == frags
    )
    pieces = ControlPieces()
    got = [pieces.add(verify_control_fragment(f, KEY, BASE_TO_DRONE)) for f in frags[::-1]]
    assert got[:-1] == [None] * (len(frags) - 1) and got[-1] == frames
    assert codec.split_frame(frames) is not None  # a whole CONFIG frame


def test_control_pieces_are_bounded_and_refuse_a_changed_count() -> None:
    frames = bytes(range(200))
    pieces = ControlPieces()
    messages = [
        encode_control_fragments(100 * k, frames, 60, KEY, BASE_TO_DRONE) for k in range(1, 7)
    ]
    for m in messages:  # the first piece of six messages: the oldest two given up
        assert pieces.add(verify_control_fragment(m[0], KEY, BASE_TO_DRONE)) is None
    assert pieces.given_up == 2
    for f in messages[0][1:]:  # the rest of a message given up: never whole
        assert pieces.add(verify_control_fragment(f, KEY, BASE_TO_DRONE)) is None
    done = [pieces.add(verify_control_fragment(f, KEY, BASE_TO_DRONE)) for f in messages[5][1:]]
    assert done[-1] == frames
    other = encode_control_fragments(500, bytes(300), 60, KEY, BASE_TO_DRONE)  # first 500 too
    assert pieces.add(verify_control_fragment(other[1], KEY, BASE_TO_DRONE)) is None
    assert pieces.malformed == 1  # message 500 has 5 pieces, this one says 7
    with pytest.raises(ValueError, match="at most 16"):
        encode_control_fragments(1, bytes(17 * 45), 60, KEY, BASE_TO_DRONE)


def test_fragment_vector_layout_and_reassembly() -> None:
    """The pieces of a slot larger than the packet, checked byte by byte against
    an independent layout (hmac directly) and put back together."""
    v = BY_NAME["fragments_of_one_slot"]
    frags = [bytes.fromhex(f) for f in v["fragments"]]
    body = bytes.fromhex(v["body"])
    assert body == bytes([1, 4, 0b1101]) + bytes.fromhex(v["values"])
    assert body == slot_bitmap_body(v["presence"], bytes.fromhex(v["values"]))
    room = v["max_datagram"] - 5 - 4
    assert len(frags) == -(-len(body) // room) and all(len(f) <= v["max_datagram"] for f in frags)
    for i, raw in enumerate(frags):
        head = bytes([0x32, 1, 0x01, 0x00, i << 4 | (len(frags) - 1)])
        assert raw[:5] == head and raw[5:-4] == body[i * room : (i + 1) * room]
        assert raw[-4:] == _hmac_tag(b"D", 65537, raw[:-4], 4)
    assert encode_fragments(1, 65537, body, v["max_datagram"], KEY, DRONE_TO_BASE) == frags
    got = [verify_fragment(f, KEY, DRONE_TO_BASE, v["expected_slot"]) for f in frags]
    assert {(g.slot, g.count) for g in got} == {(65537, len(frags))}
    whole = verify_slot_body(1, 65537, b"".join(g.piece for g in got))
    assert whole.presence == bytes([0b1101]) and whole.values == bytes.fromhex(v["values"])


def test_fragments_reassemble_in_any_order_duplicates_and_replays_dropped() -> None:
    v = BY_NAME["fragments_of_one_slot"]
    frags = [bytes.fromhex(f) for f in v["fragments"]]
    rx = DatagramReceiver(KEY, 1, [250_000] * 4, S1_KINDS)
    rx.gaps.next = v["expected_slot"]
    order = [2, 0, 2, 1, 3] if len(frags) > 3 else [2, 0, 2, 1]
    got = []
    for i in order:
        got += rx.on_datagram(frags[i], 0.0)
    assert [slot for slot, _ in got] == [65537]
    values = got[0][1]
    assert [x.present for x in values] == v["presence"]
    assert values[0].number == 0.5 and values[0].count == 6 and values[3].number == 10.5
    assert rx.on_datagram(frags[0], 0.1) == [] and rx.stats.replayed == 1  # slot delivered
    bad = bytearray(frags[1])
    bad[-1] ^= 1
    assert rx.on_datagram(bytes(bad), 0.2) == [] and rx.stats.forged == 1


def test_reassembly_memory_is_bounded() -> None:
    rx = DatagramReceiver(KEY, 1, [250_000] * 4, S1_KINDS)
    for slot in range(100, 140):  # the first piece of 40 slots, never the second
        rx.on_datagram(encode_fragments(1, slot, bytes(30), 20, KEY, DRONE_TO_BASE)[0], 0.0)
    assert len(rx.reassembly.partial) <= rx.reassembly.max_slots
    assert rx.reassembly.given_up == 40 - rx.reassembly.max_slots
    with pytest.raises(ValueError, match="at most 16"):
        encode_fragments(1, 5, bytes(17 * 11), 20, KEY, DRONE_TO_BASE)


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


@given(
    st.binary(min_size=1, max_size=400),
    st.integers(14, 250),
    st.integers(0, 2**20),
    st.randoms(use_true_random=False),
)
def test_fragments_round_trip_in_any_order(
    body: bytes, max_datagram: int, slot: int, rng: random.Random
) -> None:
    room = max_datagram - 9
    if -(-len(body) // room) > 16:
        return
    frags = encode_fragments(7, slot, body, max_datagram, KEY, DRONE_TO_BASE)
    assert all(len(f) <= max_datagram for f in frags)
    rng.shuffle(frags)
    r = Reassembly()
    out = [r.add(verify_fragment(f, KEY, DRONE_TO_BASE, slot + 5)) for f in frags]
    assert out[:-1] == [None] * (len(frags) - 1) and out[-1] == body


@given(st.lists(st.binary(min_size=1, max_size=60), max_size=20))
def test_fuzzed_fragments_never_deliver(raws: list[bytes]) -> None:
    """Arbitrary bytes after a 0x32 never verify, never raise, never deliver a slot."""
    rx = DatagramReceiver(KEY, 1, [250_000] * 4, S1_KINDS)
    for raw in raws:
        assert rx.on_datagram(b"\x32" + raw, 0.0) == []
    assert rx.stats.forged + rx.stats.malformed == len(raws)


@given(
    st.binary(min_size=1, max_size=1200),
    st.integers(16, 250),
    st.integers(0, 2**34),
    st.randoms(use_true_random=False),
)
def test_control_fragments_round_trip_in_any_order(
    frames: bytes, max_datagram: int, counter: int, rng: random.Random
) -> None:
    if -(-len(frames) // (max_datagram - 15)) > 16:
        with pytest.raises(ValueError, match="at most 16"):
            encode_control_fragments(counter, frames, max_datagram, KEY, BASE_TO_DRONE)
        return
    frags = encode_control_fragments(counter, frames, max_datagram, KEY, BASE_TO_DRONE)
    assert all(len(f) <= max_datagram for f in frags)
    rng.shuffle(frags)
    pieces = ControlPieces()
    out = [pieces.add(verify_control_fragment(f, KEY, BASE_TO_DRONE)) for f in frags]
    assert out[:-1] == [None] * (len(frags) - 1) and out[-1] == frames


@given(st.binary(max_size=80))
def test_fuzzed_control_fragments_never_verify(raw: bytes) -> None:
    """Arbitrary bytes after a 0x42 never verify: Forged or a located BAD_FRAME."""
    with pytest.raises((Forged, ProtocolError)):
        verify_control_fragment(b"\x42" + raw, KEY, BASE_TO_DRONE)
