"""The Python backfill codec against contracts/vectors/link/backfill.json (C++ passes them too)."""

from __future__ import annotations

import dataclasses
import json
import struct
from pathlib import Path
from typing import Any

import pytest
from modd.link import backfill as bf
from modd.link.codec import FrameSplitter
from modd.link.frames import Aggregation, ProtocolError, Value, ValueType, value_kind
from modd_contracts.events import Crossing, DeadbandMode, EventKind, EventLabel, EventSpec
from modd_contracts.link_wire_gen import MAX_EVENTS

LINK_VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "link"
DOC = json.loads((LINK_VECTORS / "backfill.json").read_text())


def _from_json(m: dict[str, Any]) -> bf.BackfillMessage:
    t = m["type"]
    if t == "BACKFILL_REQUEST":
        return bf.BackfillRequest(
            m["request_id"],
            m["topic"],
            ValueType.parse(m["value_type"]),
            Aggregation[m["aggregation"]],
            m["period_us"],
            m["from_ns"],
            m["windows"],
            m["resume"],
            m["rate_bps"],
            m.get("percentile"),
            _event(m["aggregation"], m.get("event")),
            m.get("state_from_ns"),
        )
    if t == "BACKFILL_PROGRESS":
        return bf.BackfillProgress(
            m["request_id"], m["next"], m["windows"], m["bytes_sent"], m["rate_bps"]
        )
    if t == "BACKFILL_END":
        return bf.BackfillEnd(m["request_id"], bf.EndStatus[m["status"]], m["next"], m["message"])
    assert t == "BACKFILL_CANCEL"
    return bf.BackfillCancel(m["request_id"])


def _event(aggregation: str, e: dict[str, Any] | None) -> EventLabel | None:
    """An event request's parameters as the vector spells them (code: mode or crossing)."""
    if e is None:
        return None
    n = e["max_events"] or MAX_EVENTS
    if aggregation == "ON_CHANGE":
        spec = EventSpec(
            EventKind.ON_CHANGE, n, deadband=e["deadband"], mode=DeadbandMode(e["code"])
        )
    else:
        spec = EventSpec(
            EventKind.THRESHOLD,
            n,
            level=e["level"],
            hysteresis=e["hysteresis"],
            crossing=Crossing(e["code"]),
        )
    return EventLabel(spec, e["max_events"] > 0)


@pytest.mark.parametrize("v", DOC["vectors"], ids=lambda v: v["name"])
def test_vector_byte_for_byte(v: dict[str, Any]) -> None:
    wire = bytes.fromhex(v["hex"])
    (raw,) = FrameSplitter().feed(wire)
    assert bf.is_backfill_type(raw.type)
    m = v["message"]
    if m["type"] == "BACKFILL_DATA":
        kind = value_kind(ValueType.parse(m["value_type"]), Aggregation[m["aggregation"]])
        assert bf.data_request_id(raw) == m["request_id"]
        d = bf.decode_data(raw, kind)
        expected = bf.BackfillData(
            m["request_id"],
            m["first"],
            [
                Value(x["present"], x["number"], x["integer"], x["count"], x["samples"])
                for x in m["values"]
            ],
        )
        assert d == expected
        assert bf.encode_data(d, kind) == wire
    else:
        decoded = bf.decode(raw)
        assert decoded == _from_json(m)
        assert bf.encode(decoded) == wire


@pytest.mark.parametrize("v", DOC["invalid"], ids=lambda v: v["name"])
def test_invalid_frames_rejected(v: dict[str, str]) -> None:
    (raw,) = FrameSplitter().feed(bytes.fromhex(v["hex"]))
    with pytest.raises(ProtocolError):
        if raw.type == bf.BackfillType.DATA:
            bf.decode_data(raw, value_kind(ValueType.FLOAT32, Aggregation.MIN))
        else:
            bf.decode(raw)


def test_window_times_are_the_original_ones() -> None:
    req = bf.BackfillRequest(1, "t", ValueType.FLOAT32, Aggregation.MIN, 250_000, 10**18, 8)
    assert req.window_start_ns(0) == 10**18
    assert req.window_start_ns(3) == 10**18 + 750_000_000


def test_encode_refuses_empty_and_oversized_batches() -> None:
    kind = value_kind(ValueType.FLOAT32, Aggregation.MIN)
    with pytest.raises(ValueError):
        bf.encode_data(bf.BackfillData(1, 0, []), kind)
    with pytest.raises(ValueError):
        bf.encode_data(bf.BackfillData(1, 0, [Value()] * (bf.MAX_BATCH + 1)), kind)


def test_a_percentile_request_carries_its_p() -> None:
    """PERCENTILE's p (f64le) follows the period, read back; out of 0..100 refused;
    a C++ PubBroker reads the same bytes (runtime/cpp/src/link/backfill.cpp)."""
    req = bf.BackfillRequest(
        3, "t", ValueType.FLOAT32, Aggregation.PERCENTILE, 250_000, 10**18, 8, 0, 0, 99.5
    )
    raw = bf.encode(req)
    assert struct.pack("<d", 99.5) in raw
    (frame,) = FrameSplitter().feed(raw)
    assert bf.decode(frame) == req
    (bad,) = FrameSplitter().feed(raw.replace(struct.pack("<d", 99.5), struct.pack("<d", 100.5)))
    with pytest.raises(ProtocolError, match="percentile"):
        bf.decode(bad)
    with pytest.raises(ValueError):
        bf.encode(dataclasses.replace(req, percentile=None))
