"""Encoder and decoder of link frames: varint length, type byte, body (docs/protocol.md).

Every encode has its decode. Decoders raise ProtocolError(BAD_FRAME) with the byte offset
within the frame body.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass

from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.events import EVENT_AGGREGATIONS, EventLabel, EventSpec
from modd_contracts.link_wire_gen import (
    MAX_BUFFER_SIZE,
    MAX_EVENTS,
    MAX_LIST,
    MAX_NAME,
    MAX_ONBOARD_WIRE,
    MAX_PERIOD_US,
    MAX_PING,
    MAX_STATUS_PERIOD_S,
    MAX_VARINT_BYTES,
    Crossing,
    DeadbandMode,
    EventKind,
)

from modd.link.frames import (
    MAX_ACCEPTED_DELAY_MS,
    MAX_FRAME,
    MAX_HEALTH_FIELDS,
    MAX_HEALTH_NAME,
    MAX_HEALTH_SENSORS,
    Aggregation,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Data,
    ErrorCode,
    ErrorMsg,
    Hello,
    Message,
    MsgType,
    Onboard,
    OnboardAck,
    Ping,
    Pong,
    ProtocolError,
    Scalar,
    SensorHealth,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueKind,
    ValueType,
)
from modd.link.quantise import ESCAPE, MAX_DELTA, MAX_STEPS, steps


def varint(v: int) -> bytes:
    if v < 0:
        raise ValueError("varint of a negative number")
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def zigzag(v: int) -> int:
    return (v << 1) ^ (v >> 63) if v < 0 else v << 1


def unzigzag(v: int) -> int:
    return (v >> 1) ^ -(v & 1)


def string(s: str) -> bytes:
    b = s.encode()
    return varint(len(b)) + b


class Reader:
    """Reads a frame body; errors carry the offset (base + position)."""

    def __init__(self, data: bytes, base: int = 0) -> None:
        self.data = data
        self.pos = 0
        self.base = base

    def fail(self, what: str) -> ProtocolError:
        return ProtocolError(ErrorCode.BAD_FRAME, what, self.base + self.pos)

    def need(self, n: int) -> None:
        if len(self.data) - self.pos < n:
            raise self.fail(f"truncated: need {n} more bytes")

    def remaining(self) -> int:
        return len(self.data) - self.pos

    def u8(self) -> int:
        self.need(1)
        b = self.data[self.pos]
        self.pos += 1
        return b

    def varint(self) -> int:
        v = 0
        for shift in range(0, 7 * MAX_VARINT_BYTES, 7):
            b = self.u8()
            if shift == 63 and b > 1:
                self.pos -= 1
                raise self.fail("varint overflows 64 bits")
            v |= (b & 0x7F) << shift
            if not b & 0x80:
                return v
        raise self.fail(f"varint longer than {MAX_VARINT_BYTES} bytes")

    def fixed(self, fmt: str) -> float | int:
        n = struct.calcsize(fmt)
        self.need(n)
        (v,) = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += n
        return v  # type: ignore[no-any-return]

    def take(self, n: int) -> bytes:
        self.need(n)
        b = self.data[self.pos : self.pos + n]
        self.pos += n
        return b

    def string(self, max_len: int) -> str:
        n = self.varint()
        if n > max_len:
            raise self.fail(f"string longer than {max_len}")
        raw = self.take(n)
        try:
            return raw.decode()
        except UnicodeDecodeError as e:
            raise self.fail("string is not UTF-8") from e

    def end(self) -> None:
        if self.pos != len(self.data):
            raise self.fail(f"{len(self.data) - self.pos} trailing bytes")


def _frame(mtype: int, body: bytes) -> bytes:
    return varint(len(body) + 1) + bytes([mtype]) + body


def encode(m: Message) -> bytes:
    """One whole frame, length prefix included."""
    if isinstance(m, Hello | Challenge):
        if len(m.nonce) != 16:
            raise ValueError("nonce must be 16 bytes")
        mt = MsgType.HELLO if isinstance(m, Hello) else MsgType.CHALLENGE
        return _frame(mt, bytes([m.version]) + m.nonce)
    if isinstance(m, Auth):
        return _frame(MsgType.AUTH, m.mac)
    if isinstance(m, AuthOk):
        return _frame(MsgType.AUTH_OK, m.mac + bytes([m.config_id]) + struct.pack("<Q", m.epoch_ns))
    if isinstance(m, Ping):
        return _frame(MsgType.PING, m.payload)
    if isinstance(m, Pong):
        return _frame(MsgType.PONG, m.payload)
    if isinstance(m, Config):
        b = bytearray([m.config_id])
        b += varint(m.status_period_s) + varint(len(m.topics))
        for t in m.topics:
            b += string(t.name) + bytes([t.type]) + varint(t.buffer_size) + varint(t.period_us)
        b += varint(len(m.streams))
        for s in m.streams:
            b += varint(s.topic) + bytes([s.aggregation]) + varint(s.period_us)
            b += percentile_field(s.aggregation, s.percentile)
            b += event_field(s.aggregation, s.event)
        if m.accepted_delay_ms is not None:
            if not 0 <= m.accepted_delay_ms <= MAX_ACCEPTED_DELAY_MS:
                raise ValueError(
                    f"accepted delay {m.accepted_delay_ms} ms out of 0..{MAX_ACCEPTED_DELAY_MS}"
                )
            b += varint(m.accepted_delay_ms)
        b += _resolutions(m)
        return _frame(MsgType.CONFIG, bytes(b))
    if isinstance(m, ConfigAck):
        body = bytes([m.config_id, m.status]) + struct.pack("<Q", m.epoch_ns)
        return _frame(MsgType.CONFIG_ACK, body)
    if isinstance(m, Onboard):
        _check_onboard(len(m.model))
        return _frame(MsgType.ONBOARD, bytes([m.config_id]) + m.model)
    if isinstance(m, OnboardAck):
        _check_onboard(len(m.answers))
        return _frame(MsgType.ONBOARD_ACK, bytes([m.config_id, m.status]) + m.answers)
    if isinstance(m, Status):
        body = varint(len(m.counters)) + b"".join(varint(c) for c in m.counters)
        if m.sensors:
            body += encode_sensor_health(m.sensors)
        return _frame(MsgType.STATUS, body)
    if isinstance(m, ErrorMsg):
        return _frame(MsgType.ERROR, bytes([m.code]) + string(m.message))
    raise TypeError(f"not a link message: {m!r}")


def _check_onboard(n: int) -> None:
    if n > MAX_ONBOARD_WIRE:
        raise ValueError(f"on-board payload of {n} B above the frame's {MAX_ONBOARD_WIRE} B")


def _rest_onboard(r: Reader) -> bytes:
    if r.remaining() > MAX_ONBOARD_WIRE:
        raise r.fail(f"on-board payload above {MAX_ONBOARD_WIRE} bytes")
    return r.take(r.remaining())


def _put_scalar(b: bytearray, k: Scalar, number: float, integer: int, count: int) -> None:
    if k == Scalar.F32:
        b += struct.pack("<f", number)
    elif k == Scalar.F64:
        b += struct.pack("<d", number)
    elif k == Scalar.ZIGZAG:
        b += varint(zigzag(integer))
    elif k == Scalar.BOOL:
        b.append(1 if integer else 0)
    else:
        b += varint(count)


def put_number(b: bytearray, chain: dict[int, int], key: int, x: float, resolution: float) -> None:
    """One value of a stream with a declared resolution (modd.link.quantise): its
    steps against the unit's ``chain`` (updated), or the escape and the exact value.

    >>> b, chain = bytearray(), {}
    >>> put_number(b, chain, 0, 1.234, 0.01); put_number(b, chain, 0, 1.25, 0.01)
    >>> bytes(b).hex()
    'f70105'
    >>> r = Reader(bytes(b)); back: dict[int, int] = {}
    >>> [round(get_number(r, back, 0, 0.01), 6) for _ in range(2)]
    [1.23, 1.25]
    """
    q = steps(x, resolution)
    if q is None:
        b += varint(ESCAPE) + struct.pack("<d", x)
        return
    prev = chain.get(key)
    b += varint(zigzag(q - prev if prev is not None else q) + 1)
    chain[key] = q


def get_number(r: Reader, chain: dict[int, int], key: int, resolution: float) -> float:
    code = r.varint()
    if code == ESCAPE:
        return float(r.fixed("<d"))
    delta = unzigzag(code - 1)
    if abs(delta) > MAX_DELTA:
        raise r.fail(f"quantised delta {delta} beyond 2^54 steps")
    prev = chain.get(key)
    q = prev + delta if prev is not None else delta
    if abs(q) > MAX_STEPS:
        raise r.fail(f"quantised value of {q} steps beyond 2^53")
    chain[key] = q
    return q * resolution


def _put_value(
    b: bytearray, k: ValueKind, v: Value, chain: dict[int, int] | None = None, key: int = 0
) -> None:
    """``chain``: the unit's last step counts by stream (declared resolution)."""
    links = {} if chain is None else chain
    if k.aggregation.name in EVENT_AGGREGATIONS:
        _put_events(b, k, v)
        return
    if k.aggregation == Aggregation.ALL:
        b += varint(len(v.samples))
        for s in v.samples:
            if k.resolution is not None:
                put_number(b, links, key, float(s), k.resolution)
            else:
                _put_scalar(b, k.scalar, float(s), int(s), 0)
        return
    if k.resolution is not None:
        put_number(b, links, key, v.number, k.resolution)
    else:
        _put_scalar(b, k.scalar, v.number, v.integer, v.count)
    if k.aggregation == Aggregation.AVERAGE:
        b += varint(v.count)


def encode_data(d: Data, kinds: Sequence[ValueKind]) -> bytes:
    if len(d.values) != len(kinds):
        raise ValueError(f"DATA has {len(d.values)} values for {len(kinds)} streams")
    all_present = all(v.present for v in d.values)
    b = bytearray()
    if d.sync:
        b.append(d.config_id)
        b += varint(d.slot)
    else:
        b.append(d.seq8 & 0xFF)
    if not all_present:
        bm = bytearray((len(d.values) + 7) // 8)
        for i, v in enumerate(d.values):
            if v.present:
                bm[i // 8] |= 1 << (i % 8)
        b += bm
    chain: dict[int, int] = {}  # a DATA frame decodes on its own
    for i, (v, k) in enumerate(zip(d.values, kinds, strict=True)):
        if v.present:
            _put_value(b, k, v, chain, i)
    t = MsgType.DATA | (0 if all_present else 1) | (2 if d.sync else 0)
    return _frame(t, bytes(b))


def encode_slot_values(
    values: Sequence[Value],
    kinds: Sequence[ValueKind],
    streams: Sequence[int],
    chain: dict[int, int],
) -> bytes:
    """A slot's present values as a DATA datagram lays them out, quantised ones
    against ``chain`` (the datagram's last steps by stream id, updated)."""
    b = bytearray()
    for v, k, s in zip(values, kinds, streams, strict=True):
        if v.present:
            _put_value(b, k, v, chain, s)
    return bytes(b)


@dataclass(frozen=True)
class RawFrame:
    type: int
    body: bytes
    size: int  # whole frame, length prefix included


def split_frame(buf: bytes | bytearray, max_frame: int = MAX_FRAME) -> RawFrame | None:
    """The next frame at the front of buf, or None if more bytes are needed."""
    length = 0
    i = 0
    shift = 0
    while True:
        if i >= len(buf):
            return None
        if i >= 4:
            raise ProtocolError(ErrorCode.BAD_FRAME, "frame length varint longer than 4 bytes", 0)
        b = buf[i]
        i += 1
        length |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            break
    if length == 0:
        raise ProtocolError(ErrorCode.BAD_FRAME, "frame length 0", 0)
    if length > max_frame:
        raise ProtocolError(
            ErrorCode.BAD_FRAME, f"frame length {length} above limit {max_frame}", 0
        )
    if len(buf) - i < length:
        return None
    return RawFrame(buf[i], bytes(buf[i + 1 : i + length]), i + length)


class FrameSplitter:
    """Accumulates stream bytes and yields whole frames."""

    def __init__(self, max_frame: int = MAX_FRAME) -> None:
        self.buf = bytearray()
        self.max_frame = max_frame

    def feed(self, data: bytes) -> list[RawFrame]:
        self.buf += data
        out: list[RawFrame] = []
        while (f := self.pop()) is not None:
            out.append(f)
        return out

    def pop(self) -> RawFrame | None:
        """The next whole frame already received, if any."""
        f = split_frame(self.buf, self.max_frame)
        if f is not None:
            del self.buf[: f.size]
        return f


def is_data_type(t: int) -> bool:
    return 0x10 <= t <= 0x13


def decode(f: RawFrame) -> Message:
    """Any frame but DATA."""
    r = Reader(f.body)
    m: Message
    t = f.type
    if t in (MsgType.HELLO, MsgType.CHALLENGE):
        version = r.u8()
        nonce = r.take(16)
        m = Hello(version, nonce) if t == MsgType.HELLO else Challenge(version, nonce)
    elif t == MsgType.AUTH:
        m = Auth(r.take(32))
    elif t == MsgType.AUTH_OK:
        m = AuthOk(r.take(32), r.u8(), int(r.fixed("<Q")))
    elif t in (MsgType.PING, MsgType.PONG):
        if len(f.body) > MAX_PING:
            raise r.fail("PING/PONG payload above 64 bytes")
        r.pos = len(f.body)
        m = Ping(f.body) if t == MsgType.PING else Pong(f.body)
    elif t == MsgType.CONFIG:
        m = _decode_config(r)
    elif t == MsgType.CONFIG_ACK:
        m = ConfigAck(r.u8(), r.u8(), int(r.fixed("<Q")))
    elif t == MsgType.ONBOARD:
        cid = r.u8()
        m = Onboard(cid, _rest_onboard(r))
    elif t == MsgType.ONBOARD_ACK:
        cid, status = r.u8(), r.u8()
        m = OnboardAck(cid, status, _rest_onboard(r))
    elif t == MsgType.STATUS:
        n = r.varint()
        if n > r.remaining():
            raise r.fail("counter count exceeds frame")
        counters = tuple(r.varint() for _ in range(n))
        m = Status(counters, read_sensor_health(r) if r.remaining() else ())
    elif t == MsgType.ERROR:
        m = ErrorMsg(r.u8(), r.string(1024))
    else:
        raise ProtocolError(ErrorCode.BAD_FRAME, f"unknown message type 0x{t:02x}", 0)
    r.end()
    return m


def encode_sensor_health(sensors: Sequence[SensorHealth]) -> bytes:
    """STATUS's tail and the ingress's HEALTH body: count, then name, n, n fields."""
    out = bytearray(varint(len(sensors)))
    for s in sensors:
        out += string(s.name) + varint(len(s.fields)) + b"".join(varint(f) for f in s.fields)
    return bytes(out)


def read_sensor_health(r: Reader) -> tuple[SensorHealth, ...]:
    n = r.varint()
    if n > MAX_HEALTH_SENSORS:
        raise r.fail(f"more than {MAX_HEALTH_SENSORS} sensors' health")
    out = []
    for _ in range(n):
        name = r.string(MAX_HEALTH_NAME)
        if not name:
            raise r.fail("empty sensor name")
        k = r.varint()
        if k > MAX_HEALTH_FIELDS:
            raise r.fail(f"more than {MAX_HEALTH_FIELDS} health fields")
        out.append(SensorHealth(name, tuple(r.varint() for _ in range(k))))
    return tuple(out)


def _decode_config(r: Reader) -> Config:
    config_id = r.u8()
    sp = r.varint()
    if sp > MAX_STATUS_PERIOD_S:
        raise r.fail("status period above one day")
    nt = r.varint()
    if nt > MAX_LIST or nt > r.remaining():
        raise r.fail(f"topic count {nt} too large")
    topics = []
    for _ in range(nt):
        name = r.string(MAX_NAME)
        ty = r.u8()
        if ty >= len(ValueType):
            raise r.fail(f"unknown value type {ty}")
        bs = r.varint()
        if not 1 <= bs <= MAX_BUFFER_SIZE:
            raise r.fail(f"buffer size {bs} out of 1..{MAX_BUFFER_SIZE}")
        topics.append(TopicSpec(name, ValueType(ty), bs, r.varint()))
    ns = r.varint()
    if ns > MAX_LIST or ns > r.remaining():
        raise r.fail(f"stream count {ns} too large")
    streams = []
    for i in range(ns):
        topic = r.varint()
        if topic >= nt:
            raise r.fail(f"stream {i} names topic {topic} of {nt}")
        a = r.u8()
        if a >= len(AGGREGATIONS):
            raise r.fail(f"unknown aggregation {a}")
        p = r.varint()
        if p == 0 or p > MAX_PERIOD_US:
            raise r.fail("stream period out of range")
        pct = read_percentile(r, f"stream {i}") if a == Aggregation.PERCENTILE else None
        ev = read_event(r, Aggregation(a), f"stream {i}")
        streams.append(StreamSpec(topic, Aggregation(a), p, pct, ev))
    delay = None
    if r.remaining():
        delay = r.varint()
        if delay > MAX_ACCEPTED_DELAY_MS:
            raise r.fail("accepted delay above one hour")
    resolutions = _read_resolutions(r, ns) if r.remaining() else None
    return Config(config_id, sp, tuple(topics), tuple(streams), delay, resolutions)


def percentile_field(aggregation: Aggregation, p: float | None) -> bytes:
    """PERCENTILE's p after its period (f64le, 0..100), in CONFIG and
    BACKFILL_REQUEST; nothing for the other aggregations."""
    if (aggregation == Aggregation.PERCENTILE) != (p is not None):
        raise ValueError(f"{aggregation.name}: a percentile goes with PERCENTILE, and only with it")
    if p is None:
        return b""
    if not 0 <= p <= 100:
        raise ValueError(f"percentile {p!r} out of 0..100")
    return struct.pack("<d", p)


def event_field(aggregation: Aggregation, event: EventLabel | None) -> bytes:
    """ON_CHANGE's (mode u8, deadband f64le) or THRESHOLD's (crossing u8, level
    and hysteresis f64le) parameters and N (varint, 0: derived) after the period,
    in CONFIG; nothing for the other aggregations."""
    if (aggregation.name in EVENT_AGGREGATIONS) != (event is not None):
        raise ValueError(f"{aggregation.name}: event parameters go with ON_CHANGE or THRESHOLD")
    if event is None:
        return b""
    s, n = event.spec, varint(event.max_events or 0)
    if aggregation == Aggregation.ON_CHANGE:
        return bytes([s.mode]) + struct.pack("<d", s.deadband) + n
    return bytes([s.crossing]) + struct.pack("<dd", s.level, s.hysteresis) + n


def read_event(r: Reader, aggregation: Aggregation, what: str) -> EventLabel | None:
    """The event parameters :func:`event_field` writes, checked (located)."""
    if aggregation.name not in EVENT_AGGREGATIONS:
        return None
    code = r.u8()
    numbers = [
        float(r.fixed("<d")) for _ in range(1 if aggregation == Aggregation.ON_CHANGE else 2)
    ]
    n = r.varint()
    if not all(math.isfinite(x) for x in numbers) or n > MAX_EVENTS:
        raise r.fail(f"{what}: event parameters out of range")
    try:
        if aggregation == Aggregation.ON_CHANGE:
            spec = EventSpec(
                EventKind.ON_CHANGE, n or MAX_EVENTS, deadband=numbers[0], mode=DeadbandMode(code)
            )
        else:
            level, h = numbers
            spec = EventSpec(
                EventKind.THRESHOLD,
                n or MAX_EVENTS,
                level=level,
                hysteresis=h,
                crossing=Crossing(code),
            )
    except ValueError as exc:
        raise r.fail(f"{what}: {exc}") from None
    return EventLabel(spec, n > 0)


def _put_events(b: bytearray, k: ValueKind, v: Value) -> None:
    """An event window: count, each event's time (µs after the window's start)
    and value, the coalesced count (docs/protocol.md, "Event values")."""
    if len(v.times_us) != len(v.samples):
        raise ValueError(f"{len(v.samples)} events with {len(v.times_us)} times")
    b += varint(len(v.samples))
    for t, x in zip(v.times_us, v.samples, strict=True):
        b += varint(t)
        _put_scalar(b, k.scalar, float(x), int(x), 0)
    b += varint(v.coalesced)


def _get_events(r: Reader, k: ValueKind, v: Value) -> Value:
    n = r.varint()
    if not 1 <= n <= min(MAX_EVENTS, r.remaining()):
        raise r.fail(f"event count {n} out of 1..{MAX_EVENTS} or beyond the frame")
    for _ in range(n):
        v.times_us.append(r.varint())
        v.samples.append(_get_scalar(r, k.scalar))
    v.coalesced = r.varint()
    v.count = n + v.coalesced
    return v


def read_percentile(r: Reader, what: str) -> float:
    p = float(r.fixed("<d"))
    if not 0 <= p <= 100:  # NaN too
        raise r.fail(f"{what}: percentile {p!r} out of 0..100")
    return p


def _resolutions(m: Config) -> bytes:
    """The optional resolution field (after the accepted delay, which it needs)."""
    if m.resolutions is None:
        return b""
    if m.accepted_delay_ms is None:
        raise ValueError("a CONFIG with resolutions carries the accepted delay too")
    if len(m.resolutions) != len(m.streams):
        raise ValueError(f"{len(m.resolutions)} resolutions for {len(m.streams)} streams")
    declared = [(i, x) for i, x in enumerate(m.resolutions) if x is not None]
    b = bytearray(varint(len(declared)))
    last = -1
    for i, x in declared:
        if not (math.isfinite(x) and x > 0):
            raise ValueError(f"stream {i}: resolution {x} is not a positive number")
        b += varint(i - last - 1) + struct.pack("<d", x)
        last = i
    return bytes(b)


def _read_resolutions(r: Reader, streams: int) -> tuple[float | None, ...]:
    n = r.varint()
    if not 1 <= n <= streams:
        raise r.fail(f"resolution count {n} out of 1..{streams}")
    out: list[float | None] = [None] * streams
    i = -1
    for _ in range(n):
        i += r.varint() + 1
        if i >= streams:
            raise r.fail(f"resolution of stream {i} of {streams}")
        x = float(r.fixed("<d"))
        if not (math.isfinite(x) and x > 0):
            raise r.fail(f"resolution {x} of stream {i} is not a positive number")
        out[i] = x
    return tuple(out)


@dataclass(frozen=True)
class DataHeader:
    sync: bool
    bitmap: bool
    config_id: int
    slot: int
    seq8: int
    values_offset: int


def decode_data_header(f: RawFrame) -> DataHeader:
    if not is_data_type(f.type):
        raise ProtocolError(ErrorCode.BAD_FRAME, "not a DATA frame", 0)
    r = Reader(f.body)
    sync = bool(f.type & 2)
    if sync:
        cid = r.u8()
        slot = r.varint()
        return DataHeader(True, bool(f.type & 1), cid, slot, slot & 0xFF, r.pos)
    seq8 = r.u8()
    return DataHeader(False, bool(f.type & 1), 0, 0, seq8, r.pos)


def _get_scalar(r: Reader, k: Scalar) -> float | int:
    if k == Scalar.F32:
        return r.fixed("<f")
    if k == Scalar.F64:
        return r.fixed("<d")
    if k == Scalar.ZIGZAG:
        return unzigzag(r.varint())
    if k == Scalar.BOOL:
        b = r.u8()
        if b > 1:
            raise r.fail("bool value not 0 or 1")
        return b
    return r.varint()


def _get_value(r: Reader, k: ValueKind, chain: dict[int, int] | None = None, key: int = 0) -> Value:
    v = Value(present=True)
    is_float = k.scalar in (Scalar.F32, Scalar.F64)
    links = {} if chain is None else chain
    res = k.resolution
    if k.aggregation.name in EVENT_AGGREGATIONS:
        return _get_events(r, k, v)
    if k.aggregation == Aggregation.ALL:
        n = r.varint()
        if n > r.remaining():
            raise r.fail("ALL count exceeds frame")
        v.samples = [
            get_number(r, links, key, res) if res is not None else _get_scalar(r, k.scalar)
            for _ in range(n)
        ]
        v.count = n
        return v
    if res is not None:
        x: float | int = get_number(r, links, key, res)
    else:
        x = _get_scalar(r, k.scalar)
    if k.scalar == Scalar.UVARINT:
        v.count = int(x)
    elif is_float:
        v.number = float(x)
    else:
        v.integer = int(x)
    if k.aggregation == Aggregation.AVERAGE:
        v.count = r.varint()
    return v


def decode_data(f: RawFrame, kinds: Sequence[ValueKind]) -> Data:
    h = decode_data_header(f)
    r = Reader(f.body[h.values_offset :], h.values_offset)
    present = [True] * len(kinds)
    if h.bitmap:
        bm = r.take((len(kinds) + 7) // 8)
        present = [bool(bm[i // 8] >> (i % 8) & 1) for i in range(len(kinds))]
        for i in range(len(kinds), len(bm) * 8):
            if bm[i // 8] >> (i % 8) & 1:
                raise r.fail("presence bit set beyond the slot's streams")
    chain: dict[int, int] = {}
    values = [
        _get_value(r, k, chain, i) if p else Value()
        for i, (k, p) in enumerate(zip(kinds, present, strict=True))
    ]
    r.end()
    return Data(h.sync, h.config_id, h.slot, h.seq8, values)
