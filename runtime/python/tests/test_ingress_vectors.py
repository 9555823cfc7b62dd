"""The shared ingress vectors (contracts/vectors/ingress/replies.json) with the Python codec:
decode to the listed message, encode back to the same bytes (the C++ side: test_ingress.cpp)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from modd.ingress import (
    Ack,
    Catalogue,
    Reject,
    convert,
    decode_reply,
    encode_ack,
    encode_catalogue,
    encode_hello,
    encode_reject,
    resolve,
)
from modd.link import codec
from modd.link.frames import ValueType

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "ingress" / "replies.json"


def expected(m: dict[str, Any]) -> Catalogue | Ack | Reject:
    if m["type"] == "CATALOGUE":
        return Catalogue(
            m["drone"],
            m["max_future_ms"],
            m["max_past_ms"],
            m["accept_unknown"],
            {n: ValueType.parse(t) for n, t in m["topics"]},
        )
    if m["type"] == "ACK":
        return Ack(m["received"], m["settled"], m["archived"])
    return Reject(m["local_id"], m["reason"], m["count"], m["detail"])


def test_every_vector_decodes_and_encodes_byte_for_byte() -> None:
    vectors = json.loads(VECTORS.read_text())
    assert {v["name"] for v in vectors} == {"hello_v2", "catalogue", "ack", "reject"}
    for v in vectors:
        wire = bytes.fromhex(v["hex"])
        m = v["message"]
        if m["type"] == "HELLO":
            assert encode_hello(m["publisher"], m["version"]) == wire
            continue
        frames = codec.FrameSplitter().feed(wire)
        assert len(frames) == 1
        msg = decode_reply(frames[0].type, frames[0].body)
        assert msg == expected(m), v["name"]
        enc = (
            encode_catalogue(msg)
            if isinstance(msg, Catalogue)
            else encode_ack(msg)
            if isinstance(msg, Ack)
            else encode_reject(msg)
        )
        assert enc == wire, v["name"]


def test_conversion_rule_and_short_names() -> None:
    assert convert(2.5, ValueType.INT) == 3 and convert(-2.5, ValueType.INT) == -3
    assert convert(True, ValueType.FLOAT32) == 1.0 and convert(1, ValueType.BOOL) is True
    for bad, t in [
        (1e39, ValueType.FLOAT32),
        (float("nan"), ValueType.FLOAT64),
        (2**63, ValueType.INT),
        (2, ValueType.BOOL),
    ]:
        try:
            convert(bad, t)
        except ValueError:
            continue
        raise AssertionError(f"{bad} accepted as {t.label}")
    f64 = ValueType.FLOAT64
    cat = Catalogue(
        "usv", topics={"usv.imu.accel_z": ValueType.FLOAT32, "usv.a.temp": f64, "usv.b.temp": f64}
    )
    assert resolve(cat, "accel_z") == resolve(cat, "imu.accel_z") == "usv.imu.accel_z"
    for given, words in [("temp", "ambiguous"), ("accel_zz", "unknown topic 'accel_zz'")]:
        try:
            resolve(cat, given)
        except KeyError as e:
            assert words in e.args[0]
        else:
            raise AssertionError(given)
