"""The Python codec against the shared vectors in contracts/vectors/link/ (C++ passes them too)."""

from __future__ import annotations

import hashlib
import json
import os
import time
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.auth import client_proof, is_keyed_nonce, keyed_nonce, resolve_key, server_proof
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
    ProtocolError,
    SensorHealth,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
    value_kind,
)
from modd.link.schedule import SlotIterator
from modd_contracts.events import EventLabel, EventSpec
from modd_contracts.link_wire_gen import MAX_EVENTS, Crossing, DeadbandMode, EventKind

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "link"
ALL = sorted(p for p in VECTORS.glob("*.json"))
MESSAGES = [p for p in ALL if "message" in json.loads(p.read_text())]


def from_json(m: dict[str, Any]) -> Message:
    t = m["type"]
    if t == "HELLO":
        return Hello(m["version"], bytes.fromhex(m["nonce"]))
    if t == "CHALLENGE":
        return Challenge(m["version"], bytes.fromhex(m["nonce"]))
    if t == "AUTH":
        return Auth(bytes.fromhex(m["mac"]))
    if t == "AUTH_OK":
        return AuthOk(bytes.fromhex(m["mac"]), m["config_id"], m["epoch_ns"])
    if t == "PING":
        return Ping(bytes.fromhex(m["payload"]))
    if t == "PONG":
        return Pong(bytes.fromhex(m["payload"]))
    if t == "CONFIG_ACK":
        return ConfigAck(m["config_id"], m["status"], m["epoch_ns"])
    if t == "ONBOARD":
        return Onboard(m["config_id"], bytes.fromhex(m["model"]))
    if t == "ONBOARD_ACK":
        return OnboardAck(m["config_id"], m["status"], bytes.fromhex(m["answers"]))
    if t == "STATUS":
        return Status(
            tuple(m["counters"]),
            tuple(SensorHealth(h["name"], tuple(h["fields"])) for h in m.get("sensors", [])),
        )
    if t == "ERROR":
        return ErrorMsg(m["code"], m["message"])
    if t == "CONFIG":
        return Config(
            m["config_id"],
            m["status_period_s"],
            tuple(
                TopicSpec(x["name"], ValueType.parse(x["type"]), x["buffer_size"], x["period_us"])
                for x in m["topics"]
            ),
            tuple(
                StreamSpec(
                    x["topic"],
                    Aggregation[x["aggregation"]],
                    x["period_us"],
                    x.get("percentile"),
                    _event(Aggregation[x["aggregation"]], x["event"]) if "event" in x else None,
                )
                for x in m["streams"]
            ),
            m.get("accepted_delay_ms"),
            tuple(m["resolutions"]) if "resolutions" in m else None,
        )
    raise AssertionError(t)


def _event(aggregation: Aggregation, e: dict[str, Any]) -> EventLabel:
    """A vector's event parameters, as the reference definition holds them."""
    n = e["max_events"] or MAX_EVENTS
    if aggregation == Aggregation.ON_CHANGE:
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


def test_vectors_exist() -> None:
    assert len(MESSAGES) >= 17


@pytest.mark.parametrize("path", MESSAGES, ids=lambda p: p.stem)
def test_vector_byte_for_byte(path: Path) -> None:
    v = json.loads(path.read_text())
    wire = bytes.fromhex(v["hex"])
    (raw,) = codec.FrameSplitter().feed(wire)
    m = v["message"]
    if m["type"] != "DATA":
        expected = from_json(m)
        assert codec.decode(raw) == expected
        assert codec.encode(expected) == wire
        return
    kinds = [
        value_kind(ValueType.parse(k["type"]), Aggregation[k["aggregation"]], k.get("resolution"))
        for k in v["kinds"]
    ]
    values = [
        Value(
            x["present"],
            x["number"],
            x["integer"],
            x["count"],
            x["samples"],
            x.get("times_us", []),
            x.get("coalesced", 0),
        )
        for x in m["values"]
    ]
    data = Data(m["sync"], m["config_id"], m["slot"], m["seq8"], values)
    assert codec.encode_data(data, kinds) == wire
    back = codec.decode_data(raw, kinds)
    assert back.sync == data.sync and back.seq8 == data.seq8
    if data.sync:
        assert (back.config_id, back.slot) == (data.config_id, data.slot)
    for got, want in zip(back.values, values, strict=True):
        assert got.present == want.present
        if want.present:
            assert (got.number, got.integer, got.count) == (want.number, want.integer, want.count)
            assert got.samples == want.samples
            assert (got.times_us, got.coalesced) == (want.times_us, want.coalesced)


def test_invalid_frames_rejected() -> None:
    v = json.loads((VECTORS / "invalid.json").read_text())
    for f in v["frames"]:
        with pytest.raises(ProtocolError):
            raw = codec.split_frame(bytes.fromhex(f["hex"]))
            if raw is None:
                raise ProtocolError(1, "incomplete")  # type: ignore[arg-type]
            codec.decode(raw)


def test_handshake_proofs() -> None:
    v = json.loads((VECTORS / "handshake.json").read_text())
    key, cn, sn = (bytes.fromhex(v[k]) for k in ("key", "client_nonce", "server_nonce"))
    assert client_proof(key, cn, sn).hex() == v["client_proof"]
    assert server_proof(key, cn, sn).hex() == v["server_proof"]


def _rfc2104(key: bytes, msg: bytes) -> bytes:
    """HMAC-SHA256 written out from RFC 2104 (an oracle apart from :mod:`hmac`)."""
    k = key.ljust(64, b"\0")
    inner = hashlib.sha256(bytes(b ^ 0x36 for b in k) + msg).digest()
    return hashlib.sha256(bytes(b ^ 0x5C for b in k) + inner).digest()


def test_keyed_hello_nonce() -> None:
    """The keyed HELLO nonce (docs/protocol.md, "Keyed HELLO"): the vector (which the C++
    side checks too) and the tag by RFC 2104; a random nonce or another key is not keyed."""
    v = json.loads((VECTORS / "handshake.json").read_text())
    key, head = bytes.fromhex(v["key"]), bytes.fromhex(v["keyed_random"])
    assert v["keyed_nonce"] == (head + _rfc2104(key, b"MODDHL" + head)[:8]).hex()
    assert keyed_nonce(key, head).hex() == v["keyed_nonce"]
    assert is_keyed_nonce(key, bytes.fromhex(v["keyed_nonce"]))
    assert not is_keyed_nonce(b"another-key", bytes.fromhex(v["keyed_nonce"]))
    assert not any(is_keyed_nonce(key, os.urandom(16)) for _ in range(1000))
    made = keyed_nonce(key)  # the SubBroker's: its clock in seconds first
    assert is_keyed_nonce(key, made)
    assert abs(int.from_bytes(made[:4], "big") - int(time.time())) <= 2
    with pytest.raises(ValueError, match="8 random bytes"):
        keyed_nonce(key, b"short")


def test_slot_table() -> None:
    v = json.loads((VECTORS / "slots.json").read_text())
    it = SlotIterator(v["periods_us"])
    for s in v["slots"]:
        got = next(it)
        assert (got.index, got.offset_us, list(got.streams)) == (
            s["index"],
            s["offset_us"],
            s["streams"],
        )


def test_vectors_are_current(tmp_path: Path) -> None:
    """The one writer (contracts/vectors/generate.py) reproduces the committed link and
    ingress vectors (they are not edited by hand)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("gen", VECTORS.parent / "generate.py")
    assert spec and spec.loader
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    gen.main(tmp_path)
    written = sorted(tmp_path.glob("*/*.json"))
    assert {p.parent.name for p in written} == {"link", "ingress"}
    assert len(written) == len(ALL) + 1
    for p in written:
        committed = VECTORS.parent / p.parent.name / p.name
        assert p.read_text() == committed.read_text(), p.relative_to(tmp_path)


def test_link_key_file_is_a_small_regular_file(tmp_path: Path) -> None:
    """``file:/dev/zero`` was read without a bound (MemoryError); a link to
    the key, or a key of more than 64 KiB, is refused too."""
    key = tmp_path / "link.key"
    key.write_text("a-secret-of-16-bytes\n")
    key.chmod(0o600)
    assert resolve_key(f"file:{key}") == b"a-secret-of-16-bytes"
    (tmp_path / "via-link").symlink_to(key)
    big = tmp_path / "big.key"
    big.write_bytes(b"k" * (64 * 1024 + 1))
    for ref in (
        "file:/dev/zero",
        f"file:{tmp_path / 'via-link'}",
        f"file:{big}",
        f"file:{tmp_path}",
    ):
        with pytest.raises(ValueError, match="link key"):
            resolve_key(ref)


def test_a_link_key_shorter_than_16_bytes_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A 1-byte key was accepted: the PubBroker and the SubBroker refuse keys under 16 bytes."""
    short = tmp_path / "short.key"
    short.write_text("0123456789abcde\n")  # 15 bytes
    short.chmod(0o600)
    monkeypatch.setenv("MODD_TEST_KEY", "k")
    for ref in (f"file:{short}", "env:MODD_TEST_KEY"):
        with pytest.raises(ValueError, match="at least 16"):
            resolve_key(ref)
    monkeypatch.setenv("MODD_TEST_KEY", "0123456789abcdef")
    assert resolve_key("env:MODD_TEST_KEY") == b"0123456789abcdef"
