# ruff: noqa: E501  (the vector table reads best one vector per line)
"""Writes the shared link-protocol test vectors (one JSON file each) with the Python codec.

Run: .venv/bin/python contracts/vectors/generate.py (the one writer: this and the ingress vectors)
The C++ codec (runtime/cpp/tests/test_vectors.cpp) and the Python codec
(runtime/python/tests/test_vectors.py) both decode every vector's hex to the listed message
and encode the message back to the same hex. Values are exactly representable in float32.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import zstandard
from modd.link import codec
from modd.link.auth import client_proof, keyed_nonce, server_proof
from modd.link.frames import (
    Aggregation,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Data,
    ErrorMsg,
    Hello,
    Message,
    Onboard,
    OnboardAck,
    Ping,
    Pong,
    SensorHealth,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
)
from modd_contracts.link_wire_gen import MAX_ONBOARD_WIRE

HERE = Path(__file__).parent
KEY = b"modd-test-key"
CN = bytes(range(16))
SN = bytes(range(0xA0, 0xB0))

S1_TOPICS = (
    TopicSpec("usv.accelerometer.accel_x", ValueType.FLOAT32, 28, 40000),
    TopicSpec("usv.accelerometer.accel_y", ValueType.FLOAT32, 28, 40000),
    TopicSpec("usv.accelerometer.accel_z", ValueType.FLOAT32, 6, 40000),
)
S1_STREAMS = (
    StreamSpec(0, Aggregation.AVERAGE, 250000),
    StreamSpec(1, Aggregation.AVERAGE, 250000),
    StreamSpec(2, Aggregation.MIN, 250000),
    StreamSpec(2, Aggregation.MAX, 250000),
)
S1 = Config(1, 30, S1_TOPICS, S1_STREAMS)


def msg_json(m: Message) -> dict[str, Any]:
    if isinstance(m, Hello | Challenge):
        return {
            "type": "HELLO" if isinstance(m, Hello) else "CHALLENGE",
            "version": m.version,
            "nonce": m.nonce.hex(),
        }
    if isinstance(m, Auth):
        return {"type": "AUTH", "mac": m.mac.hex()}
    if isinstance(m, AuthOk):
        return {
            "type": "AUTH_OK",
            "mac": m.mac.hex(),
            "config_id": m.config_id,
            "epoch_ns": m.epoch_ns,
        }
    if isinstance(m, Ping | Pong):
        return {"type": "PING" if isinstance(m, Ping) else "PONG", "payload": m.payload.hex()}
    if isinstance(m, Config):
        return {
            "type": "CONFIG",
            "config_id": m.config_id,
            "status_period_s": m.status_period_s,
            "topics": [
                {
                    "name": t.name,
                    "type": t.type.label,
                    "buffer_size": t.buffer_size,
                    "period_us": t.period_us,
                }
                for t in m.topics
            ],
            "streams": [
                {"topic": s.topic, "aggregation": s.aggregation.name, "period_us": s.period_us}
                | ({} if s.percentile is None else {"percentile": s.percentile})
                | ({} if s.event is None else {"event": event_json(s.event)})
                for s in m.streams
            ],
            **({} if m.accepted_delay_ms is None else {"accepted_delay_ms": m.accepted_delay_ms}),
            **({} if m.resolutions is None else {"resolutions": list(m.resolutions)}),
        }
    if isinstance(m, ConfigAck):
        return {
            "type": "CONFIG_ACK",
            "config_id": m.config_id,
            "status": m.status,
            "epoch_ns": m.epoch_ns,
        }
    if isinstance(m, Onboard):
        return {"type": "ONBOARD", "config_id": m.config_id, "model": m.model.hex()}
    if isinstance(m, OnboardAck):
        return {
            "type": "ONBOARD_ACK",
            "config_id": m.config_id,
            "status": m.status,
            "answers": m.answers.hex(),
        }
    if isinstance(m, Status):
        return {
            "type": "STATUS",
            "counters": list(m.counters),
            **(
                {"sensors": [{"name": h.name, "fields": list(h.fields)} for h in m.sensors]}
                if m.sensors
                else {}
            ),
        }
    if isinstance(m, ErrorMsg):
        return {"type": "ERROR", "code": m.code, "message": m.message}
    raise TypeError(m)


def event_json(e: EventLabel) -> dict[str, Any]:
    """An event stream's CONFIG parameters (code: the mode or the crossing)."""
    s = e.spec
    code = s.mode if s.kind == EventKind.ON_CHANGE else s.crossing
    return {
        "code": int(code),
        "deadband": s.deadband,
        "level": s.level,
        "hysteresis": s.hysteresis,
        "max_events": e.max_events or 0,
    }


def data_json(d: Data) -> dict[str, Any]:
    return {
        "type": "DATA",
        "sync": d.sync,
        "config_id": d.config_id,
        "slot": d.slot,
        "seq8": d.seq8,
        "values": [
            {
                "present": v.present,
                "number": v.number,
                "integer": v.integer,
                "count": v.count,
                "samples": v.samples,
            }
            | ({"times_us": v.times_us, "coalesced": v.coalesced} if v.times_us else {})
            for v in d.values
        ],
    }


Kind = tuple[ValueType, Aggregation] | tuple[ValueType, Aggregation, float]


def write(
    name: str, meaning: str, wire: bytes, message: dict[str, Any], kinds: list[Kind] | None = None
) -> None:
    doc: dict[str, Any] = {"name": name, "meaning": meaning, "hex": wire.hex(), "message": message}
    if kinds is not None:  # a third item: the stream's declared resolution
        doc["kinds"] = [
            {
                "type": k[0].label,
                "aggregation": k[1].name,
                **({"resolution": k[2]} if len(k) > 2 else {}),
            }
            for k in kinds
        ]
    (HERE / f"{name}.json").write_text(json.dumps(doc, indent=1) + "\n")


#: zstd (level 19, content size written) of ``{"drone": {"name": "usv", "sensors": []}}``
#: and of ``{"sensors": {"ok": true}}``, as modd.onboard.pack and the PubBroker write them
ONBOARD_MODEL = (
    zstandard.ZstdCompressor(level=19, write_content_size=True)
    .compress(b'{"drone": {"name": "usv", "sensors": []}}\n')
    .hex()
)
ONBOARD_ANSWERS = (
    zstandard.ZstdCompressor(level=19, write_content_size=True)
    .compress(b'{"sensors": {"ok": true}}')
    .hex()
)


from modd_contracts.events import EventLabel, parse_label  # noqa: E402
from modd_contracts.link_wire_gen import EventKind  # noqa: E402


def simple(name: str, meaning: str, m: Message) -> None:
    write(name, meaning, codec.encode(m), msg_json(m))


def data(name: str, meaning: str, d: Data, kinds: list[Kind]) -> None:
    from modd.link.frames import value_kind

    wire = codec.encode_data(
        d, [value_kind(k[0], k[1], k[2] if len(k) > 2 else None) for k in kinds]
    )
    write(name, meaning, wire, data_json(d), kinds)


def main() -> None:
    simple("hello", "base station opens: version 1, client nonce 00..0f", Hello(1, CN))
    simple("challenge", "broker answers: version 1, server nonce a0..af", Challenge(1, SN))
    simple(
        "auth",
        "client proof HMAC-SHA256(key 'modd-test-key', 'MODD1C'||sn||cn)",
        Auth(client_proof(KEY, CN, SN)),
    )
    simple(
        "auth_ok",
        "server proof HMAC-SHA256(key, 'MODD1S'||cn||sn), running config 1, epoch",
        AuthOk(server_proof(KEY, CN, SN), 1, 1_763_700_000_123_456_789),
    )
    simple("ping", "PING with a 2-byte payload (the sender's sequence)", Ping(b"\x07\x01"))
    simple("pong", "PONG echoing the PING payload", Pong(b"\x07\x01"))
    simple("config_scenario1", "scenario 1: 3 float32 topics (28, 28, 6), 4 streams at 0.25 s", S1)
    simple(
        "config_scenario1_delay",
        "scenario 1 on a datagram link, with the optional "
        "trailing accepted delay (250 ms): the PubBroker packs slots with it",
        Config(1, 30, S1_TOPICS, S1_STREAMS, 250),
    )
    simple(
        "config_scenario1_resolution",
        "scenario 1 with declared resolutions (after the "
        "delay: 3 streams, the gaps 0 0 1 before streams 0, 1, 3): 0.01 m/s2 on the "
        "AVERAGEs, 0.05 on MAX z, MIN z unquantised",
        Config(1, 30, S1_TOPICS, S1_STREAMS, 1000, (0.01, 0.01, None, 0.05)),
    )
    simple(
        "config_mixed",
        "every type and aggregation, one topic of each type",
        Config(
            200,
            0,
            (
                TopicSpec("d.s.f64", ValueType.FLOAT64, 1, 0),
                TopicSpec("d.s.i", ValueType.INT, 1000, 10000),
                TopicSpec("d.s.b", ValueType.BOOL, 3, 1_000_000),
            ),
            tuple(
                StreamSpec(t, a, p)
                for t, a, p in [
                    (0, Aggregation.FIRST, 1_000_000),
                    (0, Aggregation.LAST, 1_000_000),
                    (1, Aggregation.ALL, 500_000),
                    (1, Aggregation.COUNT, 2_000_000),
                    (1, Aggregation.SUM, 2_000_000),
                    (2, Aggregation.AVERAGE, 26 * 86400 * 1_000_000),
                ]
            ),
        ),
    )
    simple(
        "config_statistics",
        "the exact window statistics: f32 MEDIAN and STDDEV, int MEDIAN and RANGE",
        Config(
            201,
            0,
            (
                TopicSpec("d.s.turbidity", ValueType.FLOAT32, 1, 0),
                TopicSpec("d.s.count", ValueType.INT, 1000, 10000),
            ),
            tuple(
                StreamSpec(t, a, p)
                for t, a, p in [
                    (0, Aggregation.MEDIAN, 1_000_000),
                    (0, Aggregation.STDDEV, 1_000_000),
                    (1, Aggregation.MEDIAN, 2_000_000),
                    (1, Aggregation.RANGE, 2_000_000),
                ]
            ),
        ),
    )
    simple(
        "config_percentile",
        "PERCENTILE(p): p (f64le) after the stream's period, f32 PERCENTILE(95), int PERCENTILE(2.5)",
        Config(
            202,
            0,
            (
                TopicSpec("d.s.turbidity", ValueType.FLOAT32, 1, 0),
                TopicSpec("d.s.count", ValueType.INT, 1000, 10000),
            ),
            (
                StreamSpec(0, Aggregation.MEDIAN, 1_000_000),
                StreamSpec(0, Aggregation.PERCENTILE, 1_000_000, 95.0),
                StreamSpec(1, Aggregation.PERCENTILE, 2_000_000, 2.5),
            ),
        ),
    )
    simple(
        "config_ack",
        "CONFIG 1 accepted, takes effect at the epoch",
        ConfigAck(1, 0, 1_763_700_000_250_000_000),
    )
    # the zstd frames as written (content size in the header), kept as bytes: the
    # codecs carry them as they are; onboard.pack / onboard_ack make and read them
    simple(
        "onboard",
        "ONBOARD for config 2: a zstd frame of the on-board model file's bytes",
        Onboard(2, bytes.fromhex(ONBOARD_MODEL)),
    )
    simple(
        "onboard_ack",
        "ONBOARD_ACK for config 2: written; a zstd frame of each process's answer",
        OnboardAck(2, 0, bytes.fromhex(ONBOARD_ANSWERS)),
    )
    simple(
        "config_ack_busy",
        "CONFIG 2 refused: BUSY (another waits for its switch date)",
        ConfigAck(2, 6, 0),
    )
    simple(
        "status",
        "STATUS with 20 counters (docs/protocol.md order)",
        Status(
            (3600, 270000, 269990, 1, 2, 3, 4, 0, 0, 0, 1, 1, 14400, 0, 317000, 51200, 42, 2, 1, 1)
        ),
    )
    simple(
        "status_sensors",
        "STATUS with 3 counters and two instruments' health "
        "(state, lines_ok, lines_bad, reconnects, last_value_ms...)",
        Status(
            (60, 1200, 1190),
            (
                SensorHealth("ctd", (1, 600, 2, 0, 1_763_700_000_500)),
                SensorHealth("gnss", (2, 590, 0, 1, 1_763_700_000_000, 590)),
            ),
        ),
    )
    simple(
        "error_auth", "ERROR AUTH_FAILED with a message", ErrorMsg(3, "HMAC proof does not verify")
    )

    s1_kinds = [(ValueType.FLOAT32, Aggregation.AVERAGE)] * 2 + [
        (ValueType.FLOAT32, Aggregation.MIN),
        (ValueType.FLOAT32, Aggregation.MAX),
    ]
    data(
        "data_scenario1",
        "scenario 1 slot 5 (seq8 5): 2 AVERAGE (value, count) + MIN + MAX, all present",
        Data(
            False,
            0,
            0,
            5,
            [
                Value(True, 0.5, 0, 6),
                Value(True, -1.25, 0, 7),
                Value(True, 9.75),
                Value(True, 10.5),
            ],
        ),
        s1_kinds,
    )
    data(
        "data_scenario1_absent",
        "scenario 1 slot 300 (seq8 44): accel_y absent -> bitmap 0b1101",
        Data(
            False, 0, 0, 44, [Value(True, 0.5, 0, 6), Value(), Value(True, 9.75), Value(True, 10.5)]
        ),
        s1_kinds,
    )
    data(
        "data_sync",
        "first frame after a gap: config 1, full slot number 1000, all present",
        Data(
            True,
            1,
            1000,
            1000 & 0xFF,
            [
                Value(True, 0.5, 0, 6),
                Value(True, -1.25, 0, 7),
                Value(True, 9.75),
                Value(True, 10.5),
            ],
        ),
        s1_kinds,
    )
    data(
        "data_sync_absent",
        "sync frame with a bitmap: config 7, slot 3, only stream 2 present",
        Data(True, 7, 3, 3, [Value(), Value(), Value(True, -2.0), Value()]),
        s1_kinds,
    )
    q_kinds: list[Kind] = [(ValueType.FLOAT32, Aggregation.AVERAGE, 0.01)] * 2 + [
        (ValueType.FLOAT32, Aggregation.MIN),
        (ValueType.FLOAT32, Aggregation.MAX, 0.05),
    ]
    data(
        "data_scenario1_quantised",
        "scenario 1 slot 5 with declared resolutions: the AVERAGEs "
        "as steps of 0.01 (50 -> zigzag 100 + 1 = 0x65, then its count; -125 -> 249 + 1 = "
        "0xfa 0x01), MIN unquantised (f32), MAX 10.5 as 210 steps of 0.05 (421 = 0xa5 0x03)",
        Data(
            False,
            0,
            0,
            5,
            [
                Value(True, 0.5, 0, 6),
                Value(True, -1.25, 0, 7),
                Value(True, 9.75),
                Value(True, 10.5),
            ],
        ),
        q_kinds,
    )
    mixed = [
        (ValueType.FLOAT64, Aggregation.FIRST),
        (ValueType.INT, Aggregation.ALL),
        (ValueType.INT, Aggregation.COUNT),
        (ValueType.INT, Aggregation.SUM),
        (ValueType.BOOL, Aggregation.AVERAGE),
        (ValueType.BOOL, Aggregation.MAX),
        (ValueType.FLOAT64, Aggregation.AVERAGE),
        (ValueType.INT, Aggregation.MIN),
        (ValueType.FLOAT32, Aggregation.LAST),
    ]
    data(
        "data_mixed",
        "9 streams: f64 FIRST, int ALL [3,-1,300], int COUNT, int SUM, bool AVERAGE,"
        " bool MAX, f64 AVERAGE, int MIN (absent), f32 LAST -> 2-byte bitmap",
        Data(
            False,
            0,
            0,
            255,
            [
                Value(True, 3.141592653589793),
                Value(True, 0, 0, 3, [3, -1, 300]),
                Value(True, 0, 0, 12),
                Value(True, 0, -70000),
                Value(True, 0.75, 0, 4),
                Value(True, 0, 1),
                Value(True, 2.5e-10, 0, 200),
                Value(),
                Value(True, -0.0),
            ],
        ),
        mixed,
    )

    data(
        "data_statistics",
        "4 streams: f32 MEDIAN 20.5, f32 STDDEV 0.25, int MEDIAN 2.5 (a float64: the mean"
        " of the two middle samples), int RANGE 19",
        Data(
            False,
            0,
            0,
            7,
            [Value(True, 20.5), Value(True, 0.25), Value(True, 2.5), Value(True, 0, 19)],
        ),
        [
            (ValueType.FLOAT32, Aggregation.MEDIAN),
            (ValueType.FLOAT32, Aggregation.STDDEV),
            (ValueType.INT, Aggregation.MEDIAN),
            (ValueType.INT, Aggregation.RANGE),
        ],
    )

    simple(
        "config_events",
        "ON_CHANGE and THRESHOLD: after the period, ON_CHANGE's mode (u8) and deadband "
        "(f64le), THRESHOLD's crossing (u8), level and hysteresis (f64le), then N (varint, "
        "0: derived); f32 ON_CHANGE(0.5, 4), f32 ON_CHANGE(10%), int THRESHOLD(DOWN 5, 0.2, 2)",
        Config(
            203,
            0,
            (
                TopicSpec("d.s.temperature", ValueType.FLOAT32, 1, 0),
                TopicSpec("d.s.count", ValueType.INT, 1000, 10000),
            ),
            (
                StreamSpec(0, Aggregation.LAST, 1_000_000),
                StreamSpec(
                    0, Aggregation.ON_CHANGE, 1_000_000, None, parse_label("ON_CHANGE(0.5, 4)")
                ),
                StreamSpec(
                    0, Aggregation.ON_CHANGE, 2_000_000, None, parse_label("ON_CHANGE(10%)")
                ),
                StreamSpec(
                    1,
                    Aggregation.THRESHOLD,
                    1_000_000,
                    None,
                    parse_label("THRESHOLD(DOWN 5, 0.2, 2)"),
                ),
            ),
        ),
    )
    data(
        "data_events",
        "3 event streams: f32 THRESHOLD, 2 events (at 10 us and 0.9 s after the window's "
        "start) and 3 coalesced; int ON_CHANGE absent; bool ON_CHANGE, 1 event",
        Data(
            False,
            0,
            0,
            9,
            [
                Value(True, count=5, samples=[4.5, 5.5], times_us=[10, 900_000], coalesced=3),
                Value(),
                Value(True, count=1, samples=[1], times_us=[250_000], coalesced=0),
            ],
        ),
        [
            (ValueType.FLOAT32, Aggregation.THRESHOLD),
            (ValueType.INT, Aggregation.ON_CHANGE),
            (ValueType.BOOL, Aggregation.ON_CHANGE),
        ],
    )

    handshake = {
        "name": "handshake",
        "meaning": "HMAC-SHA256 proofs for key 'modd-test-key'",
        "key": KEY.hex(),
        "client_nonce": CN.hex(),
        "server_nonce": SN.hex(),
        "client_proof": client_proof(KEY, CN, SN).hex(),
        "server_proof": server_proof(KEY, CN, SN).hex(),
        "keyed_random": CN[:8].hex(),
        "keyed_nonce": keyed_nonce(KEY, CN[:8]).hex(),
    }
    (HERE / "handshake.json").write_text(json.dumps(handshake, indent=1) + "\n")

    from modd.link.schedule import SlotIterator

    it = SlotIterator([250000, 250000, 2_000_000, 750000])
    slots = [next(it) for _ in range(12)]
    (HERE / "slots.json").write_text(
        json.dumps(
            {
                "name": "slots",
                "meaning": "first 12 slots of streams with periods 0.25, 0.25, 2, 0.75 s",
                "periods_us": [250000, 250000, 2_000_000, 750000],
                "slots": [
                    {"index": s.index, "offset_us": s.offset_us, "streams": list(s.streams)}
                    for s in slots
                ],
            },
            indent=1,
        )
        + "\n"
    )

    def fr(type_and_body: str) -> str:
        b = bytes.fromhex(type_and_body)
        return (codec.varint(len(b)) + b).hex()

    invalid = [
        ("zero_length", "00", "frame length 0"),
        ("long_length", "ffffffff01", "length varint longer than 4 bytes"),
        ("unknown_type", fr("55"), "unknown message type 0x55"),
        ("truncated_hello", fr("0101020304"), "HELLO nonce truncated"),
        (
            "config_bad_topic_ref",
            fr("07 01 00 01 0161 00 01 00 01 05 00 01"),
            "stream names topic 5 of 1",
        ),
        ("config_bad_buffer", fr("07 01 00 01 0161 00 00 00 00"), "buffer size 0"),
        ("config_bad_aggregation", fr("07 01 00 01 0161 00 01 00 01 00 7f 01"), "aggregation 127"),
        ("config_zero_period", fr("07 01 00 01 0161 00 01 00 01 00 00 00"), "stream period 0"),
        (
            "config_percentile_above_100",
            fr("07 01 00 01 0161 00 01 00 01 00 0b 01 0000000000205940"),
            "PERCENTILE(100.5)",
        ),
        (
            "config_percentile_nan",
            fr("07 01 00 01 0161 00 01 00 01 00 0b 01 000000000000f87f"),
            "PERCENTILE(NaN)",
        ),
        (
            "config_percentile_truncated",
            fr("07 01 00 01 0161 00 01 00 01 00 0b 01 00000000"),
            "PERCENTILE's p cut short",
        ),
        (
            "config_event_bad_crossing",
            fr("07 01 00 01 0161 00 01 00 01 00 0d 01 04 0000000000001440 0000000000000000 00"),
            "THRESHOLD crossing 4",
        ),
        (
            "config_event_nan_deadband",
            fr("07 01 00 01 0161 00 01 00 01 00 0c 01 00 000000000000f87f 00"),
            "ON_CHANGE(NaN)",
        ),
        (
            "config_event_bound_above_max",
            fr("07 01 00 01 0161 00 01 00 01 00 0c 01 00 0000000000000000 808004"),
            "ON_CHANGE with N = 65536",
        ),
        (
            "config_event_truncated",
            fr("07 01 00 01 0161 00 01 00 01 00 0d 01 02 00000000"),
            "THRESHOLD's level cut short",
        ),
        ("trailing_byte", fr("08 01 00 0000000000000000 ff"), "CONFIG_ACK with a trailing byte"),
        (
            "config_delay_above_one_hour",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 81dddb01"),
            "accepted delay 3600001 ms (above one hour)",
        ),
        (
            "config_two_trailing_fields",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 01"),
            "a byte after the accepted delay",
        ),
        (
            "config_resolution_count_zero",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 00"),
            "a resolution field declaring no stream",
        ),
        (
            "config_resolution_beyond_streams",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 01 01 7b14ae47e17a843f"),
            "resolution of stream 1 of 1",
        ),
        (
            "config_resolution_negative",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 01 00 7b14ae47e17a84bf"),
            "resolution -0.01",
        ),
        (
            "config_resolution_nan",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 01 00 000000000000f87f"),
            "resolution NaN",
        ),
        (
            "config_resolution_zero",
            fr("07 01 00 01 0161 00 01 00 01 00 00 01 01 01 00 0000000000000000"),
            "resolution 0",
        ),
        (
            "onboard_above_limit",
            fr("0b 02" + "00" * (MAX_ONBOARD_WIRE + 1)),
            f"ONBOARD payload of {MAX_ONBOARD_WIRE + 1} bytes (above {MAX_ONBOARD_WIRE})",
        ),
        ("onboard_ack_truncated", fr("0c 02"), "ONBOARD_ACK without its status"),
        (
            "status_overlong_varint",
            fr("20 01 ffffffffffffffffffff7f"),
            "varint longer than 64 bits",
        ),
    ]
    (HERE / "invalid.json").write_text(
        json.dumps(
            {
                "name": "invalid",
                "meaning": "frames both decoders must reject with BAD_FRAME",
                "frames": [{"name": n, "hex": h, "why": w} for n, h, w in invalid],
            },
            indent=1,
        )
        + "\n"
    )

    import sys

    sys.path.insert(0, str(Path(__file__).parent))  # gen_datagrams.py, beside this script
    from gen_datagrams import write as write_datagrams

    write_datagrams(HERE)
    from gen_backfill import write as write_backfill

    write_backfill(HERE)
    from gen_quantised import write as write_quantised

    write_quantised(HERE)


if __name__ == "__main__":
    main()
