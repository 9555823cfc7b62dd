"""Backfill-frame vectors (docs/protocol.md, "Backfill"), written to backfill.json by
generate.py with the Python codec (modd.link.backfill). Both codecs decode every vector to
its message and encode it back byte for byte, and reject every frame of "invalid"."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from generate import event_json
from modd.link import backfill as bf
from modd.link import codec
from modd.link.frames import Aggregation, Value, ValueType
from modd_contracts.events import parse_label

EPOCH = 1_763_700_000_000_000_000


def _message(m: bf.BackfillMessage) -> dict[str, Any]:
    if isinstance(m, bf.BackfillRequest):
        return (
            {
                "type": "BACKFILL_REQUEST",
                "request_id": m.request_id,
                "topic": m.topic,
                "value_type": m.type.label,
                "aggregation": m.aggregation.name,
                "period_us": m.period_us,
                "from_ns": m.from_ns,
                "windows": m.windows,
                "resume": m.resume,
                "rate_bps": m.rate_bps,
            }
            | ({} if m.percentile is None else {"percentile": m.percentile})
            | (
                {}
                if m.event is None
                else {"event": event_json(m.event), "state_from_ns": m.state_from_ns}
            )
        )
    if isinstance(m, bf.BackfillProgress):
        return {
            "type": "BACKFILL_PROGRESS",
            "request_id": m.request_id,
            "next": m.next,
            "windows": m.windows,
            "bytes_sent": m.bytes_sent,
            "rate_bps": m.rate_bps,
        }
    if isinstance(m, bf.BackfillEnd):
        return {
            "type": "BACKFILL_END",
            "request_id": m.request_id,
            "status": m.status.name,
            "next": m.next,
            "message": m.message,
        }
    return {"type": "BACKFILL_CANCEL", "request_id": m.request_id}


def _data(d: bf.BackfillData, vtype: ValueType, agg: Aggregation) -> dict[str, Any]:
    return {
        "type": "BACKFILL_DATA",
        "request_id": d.request_id,
        "first": d.first,
        "value_type": vtype.label,
        "aggregation": agg.name,
        "values": [
            {
                "present": v.present,
                "number": v.number,
                "integer": v.integer,
                "count": v.count,
                "samples": v.samples,
            }
            for v in d.values
        ],
    }


def vectors() -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []

    def msg(name: str, meaning: str, m: bf.BackfillMessage) -> None:
        out.append(
            {"name": name, "meaning": meaning, "hex": bf.encode(m).hex(), "message": _message(m)}
        )

    def data(
        name: str, meaning: str, d: bf.BackfillData, vtype: ValueType, agg: Aggregation
    ) -> None:
        wire = bf.encode_data(d, bf.value_kind(vtype, agg))
        out.append(
            {"name": name, "meaning": meaning, "hex": wire.hex(), "message": _data(d, vtype, agg)}
        )

    msg(
        "request_min",
        "request 1: MIN of a float32 topic over 240 windows of 0.25 s from the "
        "epoch, from the start, at the broker's default pace",
        bf.BackfillRequest(
            1,
            "usv.accelerometer.accel_z",
            ValueType.FLOAT32,
            Aggregation.MIN,
            250_000,
            EPOCH,
            240,
            0,
            0,
        ),
    )
    msg(
        "request_all_resume",
        "request 300: ALL samples of an int topic, 1 s windows, 600 "
        "windows, resuming at window 137, capped at 3600 B/s",
        bf.BackfillRequest(
            300,
            "d.s.i",
            ValueType.INT,
            Aggregation.ALL,
            1_000_000,
            EPOCH + 250_000_000,
            600,
            137,
            3600,
        ),
    )
    msg(
        "request_percentile",
        "request 7: PERCENTILE(95) of a float32 topic, 1 s windows, 60 windows; "
        "p (f64le) follows the period",
        bf.BackfillRequest(
            7,
            "usv.accelerometer.accel_x",
            ValueType.FLOAT32,
            Aggregation.PERCENTILE,
            1_000_000,
            EPOCH,
            60,
            0,
            0,
            95.0,
        ),
    )
    msg(
        "request_on_change",
        "request 8: ON_CHANGE(0.5, 4) of a float32 topic, 1 s windows, 30 windows from "
        "10 s after the config's epoch, resuming at 3: the event parameters as CONFIG "
        "writes them, then state_from_ns (u64le, the epoch) follow the period",
        bf.BackfillRequest(
            8,
            "usv.accelerometer.accel_x",
            ValueType.FLOAT32,
            Aggregation.ON_CHANGE,
            1_000_000,
            EPOCH + 10_000_000_000,
            30,
            3,
            0,
            event=parse_label("ON_CHANGE(0.5, 4)"),
            state_from_ns=EPOCH,
        ),
    )
    msg(
        "request_threshold",
        "request 9: THRESHOLD(DOWN 5, 0.5) (N derived: 0) of an int topic, 0.5 s windows, "
        "from the epoch itself, at 600 B/s",
        bf.BackfillRequest(
            9,
            "d.s.i",
            ValueType.INT,
            Aggregation.THRESHOLD,
            500_000,
            EPOCH,
            120,
            0,
            600,
            event=parse_label("THRESHOLD(DOWN 5, 0.5)"),
            state_from_ns=EPOCH,
        ),
    )
    msg(
        "progress",
        "request 300: windows up to 199 sent of 600, 4711 bytes, pacing at 3000 B/s",
        bf.BackfillProgress(300, 200, 600, 4711, 3000),
    )
    msg("end_done", "request 1 done: every window sent", bf.BackfillEnd(1, bf.EndStatus.DONE, 240))
    msg(
        "end_unknown",
        "request 2 refused: the archive has no such topic",
        bf.BackfillEnd(2, bf.EndStatus.UNKNOWN_TOPIC, 0, "no topic 'x' in the archive"),
    )
    msg("cancel", "cancel request 300", bf.BackfillCancel(300))
    data(
        "data_average",
        "request 1, windows 5..8 of a float32 AVERAGE: window 7 empty",
        bf.BackfillData(
            1,
            5,
            [Value(True, 0.5, 0, 6), Value(True, -1.25, 0, 7), Value(), Value(True, 9.75, 0, 1)],
        ),
        ValueType.FLOAT32,
        Aggregation.AVERAGE,
    )
    data(
        "data_all_int",
        "request 300, windows 137..138 of int ALL: [3, -1, 300] and []",
        bf.BackfillData(300, 137, [Value(True, 0, 0, 3, [3, -1, 300]), Value(True, 0, 0, 0, [])]),
        ValueType.INT,
        Aggregation.ALL,
    )
    data(
        "data_max_f64",
        "request 9, window 130 (2-byte varint) of a float64 MAX",
        bf.BackfillData(9, 130, [Value(True, 2.5e-10)]),
        ValueType.FLOAT64,
        Aggregation.MAX,
    )
    return out


def invalid() -> list[dict[str, str]]:
    def fr(type_and_body: str) -> str:
        b = bytes.fromhex(type_and_body)
        return (codec.varint(len(b)) + b).hex()

    req = "01 0161 00 00 01 0000000000000000"
    return [
        {"name": "request_zero_windows", "hex": fr(f"50 {req} 00 00 00"), "why": "0 windows"},
        {
            "name": "request_resume_beyond",
            "hex": fr(f"50 {req} 02 03 00"),
            "why": "resume point 3 beyond 2 windows",
        },
        {
            "name": "request_bad_aggregation",
            "hex": fr("50 01 0161 00 7f 01 0000000000000000 01 00 00"),
            "why": "aggregation 127",
        },
        {
            "name": "request_zero_period",
            "hex": fr("50 01 0161 00 00 00 0000000000000000 01 00 00"),
            "why": "period 0",
        },
        {
            "name": "request_state_after_first",
            "hex": fr(
                "50 01 0161 00 0c 01 00 0000000000000000 00 0100000000000000 "
                "0000000000000000 01 00 00"
            ),
            "why": "an ON_CHANGE request whose state starts after its first window",
        },
        {
            "name": "request_event_bad_crossing",
            "hex": fr(
                "50 01 0161 00 0d 01 07 0000000000000000 0000000000000000 00 "
                "0000000000000000 0000000000000000 01 00 00"
            ),
            "why": "THRESHOLD crossing 7",
        },
        {"name": "end_bad_status", "hex": fr("53 01 09 00 00"), "why": "end status 9"},
        {"name": "cancel_trailing", "hex": fr("54 01 00"), "why": "trailing byte"},
        {"name": "data_zero_windows", "hex": fr("51 01 00 00"), "why": "0 windows in a frame"},
        {"name": "data_bit_beyond", "hex": fr("51 01 00 01 02"), "why": "presence bit beyond"},
        {"name": "data_truncated", "hex": fr("51 01 00 01 01 0000"), "why": "MIN f32 truncated"},
    ]


def write(here: Path) -> None:
    doc = {
        "name": "backfill",
        "meaning": "backfill frames; DATA values are decoded with the "
        "kind (value_type, aggregation) of the request; invalid DATA frames use float32 MIN",
        "vectors": vectors(),
        "invalid": invalid(),
    }
    (here / "backfill.json").write_text(json.dumps(doc, indent=1) + "\n")
