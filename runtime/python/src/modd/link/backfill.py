"""Backfill frames of the link protocol (docs/protocol.md, "Backfill"): messages and codec.

The SubBroker asks the PubBroker for the windows of one topic and aggregation over a past
time range (BACKFILL_REQUEST); the PubBroker recomputes them from its MCAP archive and sends
them in BACKFILL_DATA frames, paced within a byte rate, with BACKFILL_PROGRESS now and then
and one BACKFILL_END. The request carries the first window still wanted (`resume`), so a
backfill cut by a link drop or a PubBroker restart resumes without sending a window twice.

Example::

    from modd.link import backfill as bf
    from modd.link.codec import FrameSplitter
    from modd.link.frames import Aggregation, Value, ValueType
    req = bf.BackfillRequest(1, "usv.imu.x", ValueType.FLOAT32, Aggregation.MIN,
                             250_000, 1_763_700_000_000_000_000, 240, 0, 1200)
    (raw,) = FrameSplitter().feed(bf.encode(req))
    assert bf.decode(raw) == req
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.events import EventLabel

# The backfill frames' codes and limits, generated from modd_contracts/wire.json.
from modd_contracts.link_wire_gen import MAX_BATCH as MAX_BATCH
from modd_contracts.link_wire_gen import MAX_NAME, MAX_PERIOD_US
from modd_contracts.link_wire_gen import MAX_WINDOWS as MAX_WINDOWS
from modd_contracts.link_wire_gen import BackfillType as BackfillType
from modd_contracts.link_wire_gen import EndStatus as EndStatus

from modd.link.codec import (
    RawFrame,
    Reader,
    _frame,
    _get_value,
    _put_value,
    event_field,
    percentile_field,
    read_event,
    read_percentile,
    string,
    varint,
)
from modd.link.frames import (
    Aggregation,
    ErrorCode,
    ProtocolError,
    Value,
    ValueKind,
    ValueType,
    value_kind,
)


@dataclass(frozen=True)
class BackfillRequest:
    """Windows [from_ns + k·P, from_ns + (k+1)·P) for k = resume .. windows-1."""

    request_id: int
    topic: str
    type: ValueType
    aggregation: Aggregation
    period_us: int
    from_ns: int
    windows: int
    resume: int = 0
    rate_bps: int = 0  # 0: the PubBroker's default pace
    #: PERCENTILE's p (0..100), f64le after the period; None for the others.
    percentile: float | None = None
    #: ON_CHANGE's and THRESHOLD's parameters (as CONFIG writes them) after the period,
    #: then ``state_from_ns`` (u64le): the date the detector's state starts from, the
    #: config's epoch; the PubBroker replays its archive from there to the first window
    #: asked (docs/protocol.md, "Backfill of events"). None for the others.
    event: EventLabel | None = None
    state_from_ns: int | None = None

    def window_start_ns(self, k: int) -> int:
        return self.from_ns + k * self.period_us * 1000

    def kind(self) -> ValueKind:
        return value_kind(self.type, self.aggregation)


@dataclass
class BackfillData:
    """Windows first .. first+len(values)-1 of a request; an absent value: no sample."""

    request_id: int
    first: int
    values: list[Value] = field(default_factory=list)


@dataclass(frozen=True)
class BackfillProgress:
    request_id: int
    next: int  # first window not sent yet
    windows: int  # windows of the request
    bytes_sent: int  # link bytes of this request's BACKFILL_DATA frames so far
    rate_bps: int  # the pace the broker applies


@dataclass(frozen=True)
class BackfillEnd:
    request_id: int
    status: EndStatus
    next: int  # first window not sent (== windows when DONE)
    message: str = ""


@dataclass(frozen=True)
class BackfillCancel:
    request_id: int


BackfillMessage = BackfillRequest | BackfillProgress | BackfillEnd | BackfillCancel


def is_backfill_type(t: int) -> bool:
    return 0x50 <= t <= 0x54


def encode(m: BackfillMessage) -> bytes:
    """One whole frame (length prefix included) of any backfill message but DATA."""
    if isinstance(m, BackfillRequest):
        b = varint(m.request_id) + string(m.topic) + bytes([m.type, m.aggregation])
        b += varint(m.period_us) + percentile_field(m.aggregation, m.percentile)
        b += _state_field(m)
        b += struct.pack("<Q", m.from_ns)
        b += varint(m.windows) + varint(m.resume) + varint(m.rate_bps)
        return _frame(BackfillType.REQUEST, b)
    if isinstance(m, BackfillProgress):
        b = varint(m.request_id) + varint(m.next) + varint(m.windows)
        return _frame(BackfillType.PROGRESS, b + varint(m.bytes_sent) + varint(m.rate_bps))
    if isinstance(m, BackfillEnd):
        b = varint(m.request_id) + bytes([m.status]) + varint(m.next) + string(m.message)
        return _frame(BackfillType.END, b)
    if isinstance(m, BackfillCancel):
        return _frame(BackfillType.CANCEL, varint(m.request_id))
    raise TypeError(f"not a backfill message: {m!r}")


def encode_data(d: BackfillData, kind: ValueKind) -> bytes:
    n = len(d.values)
    if not 1 <= n <= MAX_BATCH:
        raise ValueError(f"BACKFILL_DATA holds 1..{MAX_BATCH} windows, not {n}")
    b = bytearray(varint(d.request_id) + varint(d.first) + varint(n))
    bm = bytearray((n + 7) // 8)
    for i, v in enumerate(d.values):
        if v.present:
            bm[i // 8] |= 1 << (i % 8)
    b += bm
    for v in d.values:
        if v.present:
            _put_value(b, kind, v)
    return _frame(BackfillType.DATA, bytes(b))


def _state_field(m: BackfillRequest) -> bytes:
    """An event request's parameters and the start of its detector's state."""
    b = event_field(m.aggregation, m.event)
    if (m.event is None) != (m.state_from_ns is None):
        raise ValueError("an event request has its parameters and state_from_ns, no other one")
    return b if m.state_from_ns is None else b + struct.pack("<Q", m.state_from_ns)


def _check_windows(r: Reader, windows: int, resume: int) -> None:
    if not 1 <= windows <= MAX_WINDOWS:
        raise r.fail(f"window count {windows} out of 1..{MAX_WINDOWS}")
    if resume > windows:
        raise r.fail(f"resume point {resume} beyond the {windows} windows")


def decode(f: RawFrame) -> BackfillMessage:
    """Any backfill frame but DATA; raises ProtocolError(BAD_FRAME) with the offset."""
    r = Reader(f.body)
    m: BackfillMessage
    if f.type == BackfillType.REQUEST:
        rid = r.varint()
        topic = r.string(MAX_NAME)
        ty = r.u8()
        if ty >= len(ValueType):
            raise r.fail(f"unknown value type {ty}")
        agg = r.u8()
        if agg >= len(AGGREGATIONS):
            raise r.fail(f"unknown aggregation {agg}")
        period = r.varint()
        if not 1 <= period <= MAX_PERIOD_US:
            raise r.fail("window period out of range")
        pct = read_percentile(r, "request") if agg == Aggregation.PERCENTILE else None
        event = read_event(r, Aggregation(agg), "request")
        state_from = int(r.fixed("<Q")) if event is not None else None
        from_ns = int(r.fixed("<Q"))
        if state_from is not None and state_from > from_ns:
            raise r.fail("the events' state starts after the first window")
        windows = r.varint()
        resume = r.varint()
        _check_windows(r, windows, resume)
        m = BackfillRequest(
            rid,
            topic,
            ValueType(ty),
            Aggregation(agg),
            period,
            from_ns,
            windows,
            resume,
            r.varint(),
            pct,
            event,
            state_from,
        )
    elif f.type == BackfillType.PROGRESS:
        rid, nxt, windows = r.varint(), r.varint(), r.varint()
        _check_windows(r, windows, nxt)
        m = BackfillProgress(rid, nxt, windows, r.varint(), r.varint())
    elif f.type == BackfillType.END:
        rid = r.varint()
        st = r.u8()
        if st > max(EndStatus):
            raise r.fail(f"unknown backfill end status {st}")
        m = BackfillEnd(rid, EndStatus(st), r.varint(), r.string(1024))
    elif f.type == BackfillType.CANCEL:
        m = BackfillCancel(r.varint())
    else:
        raise ProtocolError(ErrorCode.BAD_FRAME, f"not a backfill message type 0x{f.type:02x}", 0)
    r.end()
    return m


def data_request_id(f: RawFrame) -> int:
    """The request a BACKFILL_DATA frame answers (which tells the value kind)."""
    if f.type != BackfillType.DATA:
        raise ProtocolError(ErrorCode.BAD_FRAME, "not a BACKFILL_DATA frame", 0)
    return Reader(f.body).varint()


def decode_data(f: RawFrame, kind: ValueKind) -> BackfillData:
    rid = data_request_id(f)
    r = Reader(f.body)
    r.varint()
    first = r.varint()
    n = r.varint()
    if not 1 <= n <= MAX_BATCH:
        raise r.fail(f"window count {n} out of 1..{MAX_BATCH}")
    if first + n > MAX_WINDOWS:
        raise r.fail("windows beyond the largest request")
    bm = r.take((n + 7) // 8)
    for i in range(n, len(bm) * 8):
        if bm[i // 8] >> (i % 8) & 1:
            raise r.fail("presence bit set beyond the frame's windows")
    values = [_get_value(r, kind) if bm[i // 8] >> (i % 8) & 1 else Value() for i in range(n)]
    r.end()
    return BackfillData(rid, first, values)
