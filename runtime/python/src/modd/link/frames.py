"""Messages of the MoDD link protocol, apart from the codec (docs/protocol.md)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.aggregations_gen import Aggregation as Aggregation  # the wire codes, generated
from modd_contracts.events import EVENT_AGGREGATIONS, EventLabel

# The wire's codes and limits, generated from modd_contracts/wire.json.
from modd_contracts.link_wire_gen import MAX_ACCEPTED_DELAY_MS as MAX_ACCEPTED_DELAY_MS
from modd_contracts.link_wire_gen import MAX_FRAME as MAX_FRAME
from modd_contracts.link_wire_gen import MAX_HEALTH_FIELDS as MAX_HEALTH_FIELDS
from modd_contracts.link_wire_gen import MAX_HEALTH_NAME as MAX_HEALTH_NAME
from modd_contracts.link_wire_gen import MAX_HEALTH_SENSORS as MAX_HEALTH_SENSORS
from modd_contracts.link_wire_gen import VERSION as VERSION
from modd_contracts.link_wire_gen import ErrorCode as ErrorCode
from modd_contracts.link_wire_gen import MsgType as MsgType
from modd_contracts.link_wire_gen import StatusField as StatusField
from modd_contracts.link_wire_gen import ValueType as ValueType


class Scalar(IntEnum):
    F32 = 0
    F64 = 1
    ZIGZAG = 2
    BOOL = 3
    UVARINT = 4


@dataclass(frozen=True)
class ValueKind:
    """How a (topic type, aggregation) pair is written in DATA."""

    aggregation: Aggregation
    scalar: Scalar
    #: Declared resolution: float values go as integer steps (modd.link.quantise).
    resolution: float | None = None


def value_kind(vtype: ValueType, agg: Aggregation, resolution: float | None = None) -> ValueKind:
    """The wire type of the value is the aggregation table's result type for
    the topic type; a COUNT, never negative, is an unsigned varint rather than
    zigzag (the C++ ``value_kind`` reads the same table)."""
    if agg == Aggregation.COUNT:
        return ValueKind(agg, Scalar.UVARINT)
    scalar = _SCALAR[AGGREGATIONS[agg].result[vtype.label]]
    if agg.name in EVENT_AGGREGATIONS:  # events go exact (no declared resolution)
        return ValueKind(agg, scalar)
    return ValueKind(agg, scalar, resolution if scalar in (Scalar.F32, Scalar.F64) else None)


_SCALAR = {"float32": Scalar.F32, "float64": Scalar.F64, "int": Scalar.ZIGZAG, "bool": Scalar.BOOL}


class ProtocolError(Exception):
    """A malformed frame or a protocol violation; `offset` is the byte offset in the frame body."""

    def __init__(self, code: ErrorCode, message: str, offset: int | None = None) -> None:
        where = f" (at byte {offset})" if offset is not None else ""
        super().__init__(f"{code.name}: {message}{where}")
        self.code = code
        self.offset = offset


@dataclass(frozen=True)
class Hello:
    version: int
    nonce: bytes  # 16 bytes


@dataclass(frozen=True)
class Challenge:
    version: int
    nonce: bytes  # 16 bytes


@dataclass(frozen=True)
class Auth:
    mac: bytes  # 32 bytes


@dataclass(frozen=True)
class AuthOk:
    mac: bytes
    config_id: int
    epoch_ns: int


@dataclass(frozen=True)
class Ping:
    payload: bytes


@dataclass(frozen=True)
class Pong:
    payload: bytes


@dataclass(frozen=True)
class TopicSpec:
    name: str
    type: ValueType
    buffer_size: int
    period_us: int = 0


@dataclass(frozen=True)
class StreamSpec:
    topic: int
    aggregation: Aggregation
    period_us: int
    #: PERCENTILE's p (0..100), written after the period; None for the others.
    percentile: float | None = None
    #: ON_CHANGE's or THRESHOLD's parameters and declared N, written after the
    #: period (docs/protocol.md, "CONFIG"); None for the others.
    event: EventLabel | None = None


@dataclass(frozen=True)
class Config:
    config_id: int
    status_period_s: int
    topics: tuple[TopicSpec, ...]
    streams: tuple[StreamSpec, ...]
    #: Optional trailing field (datagram links): the accepted delay the PubBroker packs
    #: slots with; None = the delay of its config file (docs/protocol.md, "CONFIG").
    accepted_delay_ms: int | None = None
    #: Optional trailing field after the delay: each stream's declared resolution (None:
    #: sent as without one); None when no stream declares one (docs/protocol.md, "CONFIG").
    resolutions: tuple[float | None, ...] | None = None

    def kinds(self) -> list[ValueKind]:
        steps = self.resolutions or (None,) * len(self.streams)
        return [
            value_kind(self.topics[s.topic].type, s.aggregation, r)
            for s, r in zip(self.streams, steps, strict=True)
        ]


@dataclass(frozen=True)
class ConfigAck:
    config_id: int
    status: int
    epoch_ns: int


@dataclass(frozen=True)
class Onboard:
    """The on-board part of a deployed model, for modd-sensors and modd-mavlink
    (docs/protocol.md, "ONBOARD"): ``model`` is a zstd frame of its JSON document."""

    config_id: int
    model: bytes


@dataclass(frozen=True)
class OnboardAck:
    """What each on-board process did with an ONBOARD: ``answers`` is a zstd frame of
    a JSON object by process name; ``status`` 0 when the model file was written."""

    config_id: int
    status: int
    answers: bytes


# The PubBroker's counters in STATUS order (generated from wire.json, as the C++ side).
STATUS_FIELDS: tuple[str, ...] = tuple(f.label for f in StatusField)


# One instrument's health in STATUS (docs/protocol.md, "STATUS"), fields in this order; a
# newer modd-sensors may append fields (kept as field_<i>).
HEALTH_FIELDS: tuple[str, ...] = (
    "state",
    "lines_ok",
    "lines_bad",
    "reconnects",
    "last_value_ms",
    "values",
    "missing",
    "refused",
    "timeouts",
    "exceptions",
    "silences",
    "ignored",
    "no_fix",
)
HEALTH_STATES = ("closed", "open", "silent")  # `state`'s codes


@dataclass(frozen=True)
class SensorHealth:
    name: str
    fields: tuple[int, ...]

    def as_dict(self) -> dict[str, int]:
        return {
            (HEALTH_FIELDS[i] if i < len(HEALTH_FIELDS) else f"field_{i}"): v
            for i, v in enumerate(self.fields)
        }


@dataclass(frozen=True)
class Status:
    counters: tuple[int, ...]
    sensors: tuple[SensorHealth, ...] = ()  # after the counters, only when there is one

    def as_dict(self) -> dict[str, int]:
        """Known fields by name; fields a newer broker appends are kept as field_<i>."""
        return {
            (STATUS_FIELDS[i] if i < len(STATUS_FIELDS) else f"field_{i}"): v
            for i, v in enumerate(self.counters)
        }


@dataclass(frozen=True)
class ErrorMsg:
    code: int
    message: str


@dataclass
class Value:
    """One stream's value in a DATA frame. `number` holds floats and the AVERAGE mean,
    `integer` ints and bools, `count` the AVERAGE sample count and COUNT, `samples` ALL."""

    present: bool = False
    number: float = 0.0
    integer: int = 0
    count: int = 0
    samples: list[float | int] = field(default_factory=list)
    #: An event window's (ON_CHANGE, THRESHOLD): each event's time, µs after the
    #: window's start (its value in ``samples``), and the events coalesced beyond N.
    times_us: list[int] = field(default_factory=list)
    coalesced: int = 0


@dataclass
class Data:
    sync: bool
    config_id: int  # meaningful when sync
    slot: int  # full slot number when sync
    seq8: int  # slot mod 256
    values: list[Value]


Message = (
    Hello
    | Challenge
    | Auth
    | AuthOk
    | Ping
    | Pong
    | Config
    | ConfigAck
    | Onboard
    | OnboardAck
    | Status
    | ErrorMsg
)
