"""Datagram-transport vectors (udp, serial: docs/protocol.md, "Datagram
transports"), written to datagram.json by generate.py with the Python codec
(modd.link.datagram, modd.link.serialframe)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from modd.link import codec
from modd.link.datagram import (
    BASE_TO_DRONE,
    DRONE_TO_BASE,
    DataDatagram,
    encode_control,
    encode_control_fragments,
    encode_data,
    encode_fragments,
    encode_handshake,
    encode_nack,
    session_key,
    slot_bitmap_body,
    tag,
)
from modd.link.frames import Aggregation, Data, Hello, Ping, Value, ValueType, value_kind
from modd.link.serialframe import encode_frame

KEY = b"modd-test-key"
CN = bytes(range(16))
SN = bytes(range(0xA0, 0xB0))
S1_KINDS = [
    value_kind(ValueType.FLOAT32, a)
    for a in (Aggregation.AVERAGE, Aggregation.AVERAGE, Aggregation.MIN, Aggregation.MAX)
]


def slot_values(values: Sequence[Value]) -> bytes:
    """The value bytes of one slot (a DATA frame's body after seq8 and bitmap)."""
    present = [v for v in values if v.present]
    kinds = [k for k, v in zip(S1_KINDS, values, strict=True) if v.present]
    frame = codec.encode_data(Data(False, 0, 0, 0, list(present)), kinds)
    return frame[3:]  # length (1 B here), type, seq8


def _slot(i: int) -> list[Value]:
    return [
        Value(True, 0.5 + i, 0, 6),
        Value(True, -1.25, 0, 7),
        Value(True, 9.75 - i),
        Value(True, 10.5 + i),
    ]


def write(here: Path) -> None:
    skey = session_key(KEY, CN, SN)
    five = [slot_values(_slot(i)) for i in range(5)]
    data = encode_data(DataDatagram(1, 70000, five), skey, DRONE_TO_BASE)
    absent = [_slot(0), [Value(True, 1.0, 0, 6), Value(), Value(True, 2.0), Value()]]
    presence = [v.present for s in absent for v in s]
    bitmap = encode_data(
        DataDatagram(1, 65535, [slot_values(s) for s in absent], presence), skey, DRONE_TO_BASE
    )
    nack = encode_control(3, encode_nack([(69990, 5), (70010, 1)]), skey, BASE_TO_DRONE)
    ping = encode_control(4, codec.encode(Ping(b"\x07\x01")), skey, BASE_TO_DRONE)
    hello = encode_handshake(codec.encode(Hello(1, CN)))
    big_presence = [True, False, True, True]
    big_values = slot_values(
        [Value(True, 0.5, 0, 6), Value(), Value(True, 9.75), Value(True, 10.5)]
    )
    big_body = slot_bitmap_body(big_presence, big_values)
    frags = encode_fragments(1, 65537, big_body, 15, skey, DRONE_TO_BASE)
    bad_index = bytes([0x32, 1, 1, 0, 0x21, 0xAA])  # piece 2 of 2
    bad_index += tag(skey, DRONE_TO_BASE, 65537, bad_index, 4)
    forged_frag = bytearray(frags[1])
    forged_frag[5] ^= 0x80
    forged = bytearray(data)
    forged[5] ^= 0x01
    # scenario 1's CONFIG frame (config_scenario1.json) cut for 40-byte datagrams
    config = bytes.fromhex(json.loads((here / "config_scenario1.json").read_text())["hex"])
    cfrags = encode_control_fragments(1000, config, 40, skey, BASE_TO_DRONE)
    forged_cfrag = bytearray(cfrags[2])
    forged_cfrag[6] ^= 0x01
    cbad_index = bytes([0x42]) + bytes.fromhex("e807") + bytes([0x21, 0xAA])  # piece 2 of 2
    cbad_index += tag(skey, BASE_TO_DRONE, 1000, cbad_index, 8)
    cases: list[dict[str, Any]] = [
        {
            "name": "data_scenario1_5_slots",
            "direction": "D",
            "expected_slot": 69990,
            "meaning": "config 1, slots 70000..70004 of scenario 1 (slot i: AVERAGE 0.5+i count 6,"
            " AVERAGE -1.25 count 7, MIN 9.75-i, MAX 10.5+i), all present, 4-byte tag",
            "hex": data.hex(),
            "config_id": 1,
            "slot": 70000,
            "slots": [s.hex() for s in five],
        },
        {
            "name": "data_bitmap",
            "direction": "D",
            "expected_slot": 65534,
            "meaning": "config 1, slots 65535 and 65536 (low 16 bits 0xffff), the second with "
            "streams 1 and 3 absent: 8-stream presence bitmap 0b01011111 "
            "(bit i = stream i mod 4 of slot i div 4)",
            "hex": bitmap.hex(),
            "config_id": 1,
            "slot": 65535,
            "presence": presence,
            "slots": [slot_values(s).hex() for s in absent],
        },
        {
            "name": "control_nack",
            "direction": "B",
            "counter": 3,
            "meaning": "base asks for slots 69990..69994 and 70010 (NACK in control datagram 3)",
            "hex": nack.hex(),
            "ranges": [[69990, 5], [70010, 1]],
        },
        {
            "name": "control_ping",
            "direction": "B",
            "counter": 4,
            "meaning": "keepalive PING (payload 07 01) in control datagram 4, 8-byte tag",
            "hex": ping.hex(),
        },
        {
            "name": "handshake_hello",
            "meaning": "HELLO version 1, nonce 00..0f, no tag",
            "hex": hello.hex(),
        },
        {
            "name": "fragments_of_one_slot",
            "direction": "D",
            "expected_slot": 65530,
            "meaning": "slot 65537 (low 16 bits 0x0001) of config 1 (streams 0, 2, 3 of scenario 1"
            " present) cut for a 15-byte datagram: its one-slot 0x31 body (k=1, n=4,"
            " bitmap 0b1101, values) in pieces of 6 B, frag = index << 4 | count - 1",
            "config_id": 1,
            "slot": 65537,
            "max_datagram": 15,
            "body": big_body.hex(),
            "presence": big_presence,
            "values": big_values.hex(),
            "fragments": [f.hex() for f in frags],
        },
        {
            "name": "control_fragments_of_a_config",
            "direction": "B",
            "counter": 1000,
            "meaning": "scenario 1's CONFIG frame (config_scenario1.json) too large for a "
            "40-byte datagram, cut into control fragments (0x42) under counters "
            "1000, 1001, ...: counter varint, frag = index << 4 | count - 1, the "
            "piece (at most 40 - 15 B), the 8-byte CONTROL tag with the counter as seq",
            "max_datagram": 40,
            "frames": config.hex(),
            "fragments": [f.hex() for f in cfrags],
        },
        {
            "name": "serial_data_scenario1_5_slots",
            "meaning": "data_scenario1_5_slots framed for serial: COBS(datagram + CRC-16 LE) 00",
            "hex": encode_frame(data).hex(),
            "datagram": data.hex(),
        },
    ]
    invalid = [
        {
            "name": "forged",
            "direction": "D",
            "expected_slot": 69990,
            "hex": forged.hex(),
            "why": "one value bit flipped: the tag does not verify (dropped, counted as forged)",
        },
        {
            "name": "wrong_direction",
            "direction": "B",
            "expected_slot": 69990,
            "hex": data.hex(),
            "why": "a drone->base datagram reflected to the drone: the tag covers the direction",
        },
        {
            "name": "fragment_forged",
            "direction": "D",
            "expected_slot": 65530,
            "hex": forged_frag.hex(),
            "kind": "fragment",
            "why": "a fragment with one piece bit flipped: the tag does not verify",
        },
        {
            "name": "fragment_index_beyond_count",
            "direction": "D",
            "expected_slot": 65530,
            "hex": bad_index.hex(),
            "kind": "fragment",
            "why": "a fragment whose tag verifies but says piece 2 of 2: refused (BAD_FRAME at 4)",
        },
        {
            "name": "control_fragment_forged",
            "direction": "B",
            "hex": forged_cfrag.hex(),
            "kind": "control_fragment",
            "why": "a control fragment with one piece bit flipped: the tag does not verify",
        },
        {
            "name": "control_fragment_index_beyond_count",
            "direction": "B",
            "hex": cbad_index.hex(),
            "kind": "control_fragment",
            "why": "a control fragment whose tag verifies but says piece 2 of 2: refused "
            "(BAD_FRAME at 3)",
        },
        {
            "name": "replay",
            "direction": "D",
            "expected_slot": 69990,
            "hex": data.hex(),
            "why": "the valid datagram again after it was accepted: refused by the replay window",
        },
    ]
    doc = {
        "name": "datagram",
        "key": KEY.hex(),
        "client_nonce": CN.hex(),
        "server_nonce": SN.hex(),
        "session_key": skey.hex(),
        "vectors": cases,
        "invalid": invalid,
    }
    (here / "datagram.json").write_text(json.dumps(doc, indent=1) + "\n")
