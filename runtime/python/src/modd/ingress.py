"""The PubBroker's ingress protocol, version 2 (docs/ingress.md): frames both ways, the
publisher contract's value conversion and topic-name resolution.

Shared by the Python publisher client (``modd.publisher``) and the tests; the C++ side is
``runtime/cpp/src/ingress/codec.cpp`` (broker) and ``src/client/publisher.cpp`` (client),
checked against the same vectors (contracts/vectors/ingress/replies.json).

Example::

    >>> encode_ack(Ack(received=3, settled=3, archived=2)).hex()
    '0482030302'
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field

from modd_contracts.ingress_wire_gen import MAX_FRAME as MAX_FRAME
from modd_contracts.ingress_wire_gen import MAX_LOCAL_ID, MAX_NAME, VERSION, MsgType, RejectReason

from modd.link.codec import Reader, encode_sensor_health, string, varint
from modd.link.frames import SensorHealth, ValueType

INGRESS_VERSION = VERSION
HELLO, REGISTER, SAMPLES, HEALTH = MsgType.HELLO, MsgType.REGISTER, MsgType.SAMPLES, MsgType.HEALTH
CATALOGUE, ACK, REJECT = MsgType.CATALOGUE, MsgType.ACK, MsgType.REJECT
# What a REJECT's reason code says to the publisher's user (codes: RejectReason, the
# contract wire.json; a newer broker's code outside it is shown by its number).
REASONS: dict[int, str] = {
    RejectReason.UNKNOWN_TOPIC: "unknown topic",
    RejectReason.WRONG_TYPE: "wrong type",
    RejectReason.NOT_FINITE: "value not finite",
    RejectReason.TIMESTAMP: "timestamp out of bounds",
    RejectReason.OVERFLOW: "archive queue full",
    RejectReason.MALFORMED: "malformed",
    RejectReason.QUOTA: "over its fair share of the archive queue",
}
_VALUE_FORMAT = {
    ValueType.FLOAT32: "<f",
    ValueType.FLOAT64: "<d",
    ValueType.INT: "<q",
    ValueType.BOOL: "<B",
}
FLT_MAX = 3.4028234663852886e38
Number = float | int | bool


def frame(mtype: int, body: bytes) -> bytes:
    return varint(len(body) + 1) + bytes([mtype]) + body


def encode_hello(publisher: str, version: int = INGRESS_VERSION) -> bytes:
    return frame(HELLO, bytes([version]) + string(publisher))


def encode_register(local_id: int, vtype: ValueType, topic: str) -> bytes:
    return frame(REGISTER, varint(local_id) + bytes([vtype]) + string(topic))


def encode_samples(records: Sequence[tuple[int, int, Number]], types: Sequence[ValueType]) -> bytes:
    """records: (local id, timestamp ns, value); types[local id] gives each value's encoding."""
    parts = [varint(len(records))]
    for lid, ts, value in records:
        t = types[lid]
        v: Number = (1 if value else 0) if t == ValueType.BOOL else value
        parts.append(varint(lid) + struct.pack("<q", ts) + struct.pack(_VALUE_FORMAT[t], v))
    return frame(SAMPLES, b"".join(parts))


def encode_health(sensors: Sequence[SensorHealth]) -> bytes:
    """HEALTH: the publisher's instruments (modd-sensors), forwarded in the link's STATUS
    while the connection lasts; each replaces the one before."""
    return frame(HEALTH, encode_sensor_health(sensors))


@dataclass
class Catalogue:
    drone: str
    max_future_ms: int = 0  # 0: no bound
    max_past_ms: int = 0
    accept_unknown: bool = False
    topics: dict[str, ValueType] = field(default_factory=dict)


@dataclass(frozen=True)
class Ack:
    """Cumulative counts of the connection's records: every record before `settled` is
    refused (told in a REJECT) or in the archive file; `archived` of them are on disk."""

    received: int
    settled: int
    archived: int


@dataclass(frozen=True)
class Reject:
    local_id: int
    reason: int
    count: int
    detail: str

    @property
    def reason_text(self) -> str:
        return REASONS.get(self.reason, f"reason {self.reason}")


Reply = Catalogue | Ack | Reject


def encode_catalogue(c: Catalogue) -> bytes:
    body = string(c.drone) + varint(c.max_future_ms) + varint(c.max_past_ms)
    body += bytes([1 if c.accept_unknown else 0]) + varint(len(c.topics))
    body += b"".join(bytes([t]) + string(n) for n, t in c.topics.items())
    return frame(CATALOGUE, body)


def encode_ack(a: Ack) -> bytes:
    return frame(ACK, varint(a.received) + varint(a.settled) + varint(a.archived))


def encode_reject(r: Reject) -> bytes:
    return frame(
        REJECT,
        varint(r.local_id) + bytes([r.reason]) + varint(r.count) + string(r.detail[:MAX_NAME]),
    )


def decode_reply(mtype: int, body: bytes) -> Reply:
    """One broker → publisher frame; raises ProtocolError with the offset."""
    r = Reader(body, 1)
    out: Reply
    if mtype == CATALOGUE:
        c = Catalogue(r.string(MAX_NAME), r.varint(), r.varint())
        flag = r.u8()
        if flag > 1:
            raise r.fail("accept_unknown not 0 or 1")
        c.accept_unknown = flag == 1
        for _ in range(r.varint()):
            t = r.u8()
            if t >= len(ValueType):
                raise r.fail(f"unknown value type {t}")
            c.topics[r.string(MAX_NAME)] = ValueType(t)
        out = c
    elif mtype == ACK:
        out = Ack(r.varint(), r.varint(), r.varint())
        if out.settled > out.received or out.archived > out.settled:
            raise r.fail("ACK counts out of order")
    elif mtype == REJECT:
        lid = r.varint()
        if lid > MAX_LOCAL_ID:
            raise r.fail(f"local topic id above {MAX_LOCAL_ID}")
        out = Reject(lid, r.u8(), r.varint(), r.string(MAX_NAME))
    else:
        raise r.fail(f"unknown ingress reply type {mtype}")
    r.end()
    return out


class OutOfRange(ValueError):
    """A value that does not fit the topic's declared type (the contract's rule)."""


def convert(value: Number, vtype: ValueType) -> Number:
    """Any number to the declared type: float32 when finite and within ±FLT_MAX (nearest),
    float64 when finite, int when finite and within int64 after rounding to nearest (ties
    away from zero), bool from 0 or 1 only. Raises OutOfRange otherwise."""
    if isinstance(value, bool):
        value = int(value)
    if not isinstance(value, int | float):
        raise OutOfRange(f"not a number: {value!r}")
    if vtype == ValueType.INT:
        if isinstance(value, int):
            if not -(1 << 63) <= value < (1 << 63):
                raise OutOfRange(f"{value} beyond int64")
            return value
        if not math.isfinite(value):
            raise OutOfRange("NaN or infinite")
        rounded = math.floor(value + 0.5) if value >= 0 else math.ceil(value - 0.5)
        if not -(1 << 63) <= rounded < (1 << 63):
            raise OutOfRange(f"{value} beyond int64")
        return int(rounded)
    if vtype == ValueType.BOOL:
        if value not in (0, 1):
            raise OutOfRange("a bool takes 0 or 1")
        return bool(value)
    x = float(value)
    if not math.isfinite(x):
        raise OutOfRange("NaN or infinite")
    if vtype == ValueType.FLOAT32:
        if abs(x) > FLT_MAX:
            raise OutOfRange(f"{x} beyond ±FLT_MAX")
        return float(struct.unpack("<f", struct.pack("<f", x))[0])
    return x


def resolve(catalogue: Catalogue, given: str) -> str:
    """The full topic name for `given` (full, or a dotted suffix matching exactly one topic).
    Raises KeyError with a message naming what exists."""
    if given in catalogue.topics:
        return given
    hits = [n for n in catalogue.topics if n.endswith("." + given)]
    if len(hits) == 1:
        return hits[0]
    if not hits and catalogue.accept_unknown:
        return given
    if hits:
        raise KeyError(
            f"ambiguous topic {given!r}: matches {', '.join(sorted(hits))} (use the full name)"
        )
    known = ", ".join(sorted(catalogue.topics)) or "no topic"
    raise KeyError(f"unknown topic {given!r}: drone {catalogue.drone!r} publishes {known}")
