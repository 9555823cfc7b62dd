"""Datagram form of the MoDD link (udp and serial transports; docs/protocol.md,
"Datagram transports").

A datagram carries one or more consecutive schedule slots (DATA), a control
frame (CONFIG, PING, NACK, ... under a counter) or a handshake frame. DATA and
control datagrams end with a truncated HMAC-SHA256 tag under the session key
derived from the handshake's nonces; the tag covers the direction, the full
(64-bit) sequence number and every byte before it, so a forged, corrupt or
replayed datagram is dropped (and counted) before anything is decoded.

>>> key = session_key(b"k", bytes(16), bytes(16))
>>> d = DataDatagram(config_id=1, slot=70000, slots=[b"\\x01\\x02", b"\\x03"])
>>> raw = encode_data(d, key, DRONE_TO_BASE)
>>> verify_data(raw, key, DRONE_TO_BASE, expected_slot=69990).slot
70000
"""

from __future__ import annotations

import hashlib
import hmac
import struct
from collections.abc import Sequence
from dataclasses import dataclass

# Types, tags and limits, generated from modd_contracts/wire.json (re-exported: the
# transports import them from here).
from modd_contracts.link_wire_gen import (
    CONTROL_TAG_BYTES as CONTROL_TAG_BYTES,
)
from modd_contracts.link_wire_gen import (
    DGRAM_CONTROL as DGRAM_CONTROL,
)
from modd_contracts.link_wire_gen import (
    DGRAM_CONTROL_FRAGMENT as DGRAM_CONTROL_FRAGMENT,
)
from modd_contracts.link_wire_gen import (
    DGRAM_DATA as DGRAM_DATA,
)
from modd_contracts.link_wire_gen import (
    DGRAM_DATA_BITMAP as DGRAM_DATA_BITMAP,
)
from modd_contracts.link_wire_gen import (
    DGRAM_FRAGMENT as DGRAM_FRAGMENT,
)
from modd_contracts.link_wire_gen import (
    DGRAM_HANDSHAKE as DGRAM_HANDSHAKE,
)
from modd_contracts.link_wire_gen import (
    FRAGMENT_HEAD as FRAGMENT_HEAD,
)
from modd_contracts.link_wire_gen import (
    MAX_DATAGRAM_SLOTS as MAX_DATAGRAM_SLOTS,
)
from modd_contracts.link_wire_gen import (
    MAX_FRAGMENTS as MAX_FRAGMENTS,
)
from modd_contracts.link_wire_gen import (
    MAX_NACK_RANGE_SLOTS as MAX_NACK_RANGE_SLOTS,
)
from modd_contracts.link_wire_gen import (
    MAX_NACK_RANGES as MAX_NACK_RANGES,
)
from modd_contracts.link_wire_gen import (
    NACK as NACK,
)
from modd_contracts.link_wire_gen import (
    TAG_BYTES as TAG_BYTES,
)

from .codec import Reader, varint
from .frames import ErrorCode, ProtocolError

SESSION_LABEL = b"MODD1K"
DRONE_TO_BASE = b"D"
BASE_TO_DRONE = b"B"


def session_key(psk: bytes, client_nonce: bytes, server_nonce: bytes) -> bytes:
    """The key of a session's datagram tags, from the handshake's nonces."""
    return hmac.new(psk, SESSION_LABEL + client_nonce + server_nonce, hashlib.sha256).digest()


def tag(key: bytes, direction: bytes, seq: int, body: bytes, length: int) -> bytes:
    """HMAC-SHA256(key, direction ‖ u64le(seq) ‖ body) truncated to ``length``."""
    msg = direction + struct.pack("<Q", seq & 0xFFFFFFFFFFFFFFFF) + body
    return hmac.new(key, msg, hashlib.sha256).digest()[:length]


def extend16(low: int, expected: int) -> int:
    """The full slot number ≡ ``low`` (mod 2^16) nearest to ``expected`` (the
    receiver's next slot, or the slot its clock says is due).

    >>> extend16(3, 65533), extend16(65533, 65540)
    (65539, 65533)
    """
    base = expected - (expected & 0xFFFF) + low
    candidates = (base - 0x10000, base, base + 0x10000)
    return min((c for c in candidates if c >= 0), key=lambda c: abs(c - expected))


@dataclass
class DataDatagram:
    """Consecutive slots ``slot``, ``slot + 1``, ... each as its encoded values
    (the body of a DATA frame after seq8 and bitmap: docs/protocol.md, DATA).
    ``presence`` is None when every stream of every slot is present, else one
    bool per stream of the slots, in order."""

    config_id: int
    slot: int
    slots: list[bytes]
    presence: list[bool] | None = None


class Forged(Exception):
    """A datagram whose tag does not verify: dropped and counted, never decoded."""


def encode_data(d: DataDatagram, key: bytes, direction: bytes) -> bytes:
    """One DATA datagram (tag included)."""
    if not 1 <= d.config_id <= 255 or not d.slots:
        raise ValueError("a DATA datagram needs a config id 1..255 and at least one slot")
    head = bytearray()
    if d.presence is None:
        head.append(DGRAM_DATA)
        head.append(d.config_id)
        head += struct.pack("<H", d.slot & 0xFFFF)
    else:
        if len(d.slots) > MAX_DATAGRAM_SLOTS:
            raise ValueError(
                f"at most {MAX_DATAGRAM_SLOTS} slots in a datagram with a presence bitmap"
            )
        head.append(DGRAM_DATA_BITMAP)
        head.append(d.config_id)
        head += struct.pack("<H", d.slot & 0xFFFF)
        head.append(len(d.slots))
        bm = bytearray((len(d.presence) + 7) // 8)
        for i, p in enumerate(d.presence):
            if p:
                bm[i // 8] |= 1 << (i % 8)
        head += varint(len(d.presence)) + bm
    body = bytes(head) + b"".join(d.slots)
    return body + tag(key, direction, d.slot, body, TAG_BYTES)


@dataclass(frozen=True)
class VerifiedData:
    """A DATA datagram whose tag verified: the full slot and the undecoded values
    (decode them with the schedule's value kinds, slot by slot)."""

    config_id: int
    slot: int
    slot_count: int | None  # None: every stream present, count the slots while decoding
    presence: bytes | None
    stream_count: int
    values: bytes


def verify_data(raw: bytes, key: bytes, direction: bytes, expected_slot: int) -> VerifiedData:
    """Check a DATA datagram's tag before anything else; raises Forged or
    ProtocolError (offsets in the datagram)."""
    if len(raw) < 4 + TAG_BYTES or raw[0] not in (DGRAM_DATA, DGRAM_DATA_BITMAP):
        raise ProtocolError(ErrorCode.BAD_FRAME, "not a DATA datagram", 0)
    body, got = raw[:-TAG_BYTES], raw[-TAG_BYTES:]
    (low,) = struct.unpack_from("<H", raw, 2)
    slot = extend16(low, expected_slot)
    if not hmac.compare_digest(tag(key, direction, slot, body, TAG_BYTES), got):
        raise Forged(f"tag of the datagram of slot {slot} does not verify")
    r = Reader(body)
    r.u8()
    config_id = r.u8()
    r.take(2)
    if raw[0] == DGRAM_DATA:
        return VerifiedData(config_id, slot, None, None, 0, bytes(body[r.pos :]))
    count = r.u8()
    streams = r.varint()
    if count == 0 or streams > 8 * r.remaining():
        raise r.fail("presence bitmap longer than the datagram")
    bm = r.take((streams + 7) // 8)
    for i in range(streams, len(bm) * 8):
        if bm[i // 8] >> (i % 8) & 1:
            raise r.fail("presence bit set beyond the datagram's streams")
    return VerifiedData(config_id, slot, count, bytes(bm), streams, bytes(body[r.pos :]))


def slot_bitmap_body(streams: Sequence[bool], values: bytes) -> bytes:
    """The bytes of a one-slot 0x31 datagram between its slot16 and its tag
    (``k = 1``, the stream count, the presence bitmap, the values): what the
    fragments of a slot carry, cut in pieces."""
    bm = bytearray((len(streams) + 7) // 8)
    for i, p in enumerate(streams):
        if p:
            bm[i // 8] |= 1 << (i % 8)
    return b"\x01" + varint(len(streams)) + bytes(bm) + values


def encode_fragments(
    config_id: int, slot: int, body: bytes, max_datagram: int, key: bytes, direction: bytes
) -> list[bytes]:
    """The 0x32 datagrams of one slot too large for a packet: ``body`` (see
    :func:`slot_bitmap_body`) in at most 16 pieces, each datagram at most
    ``max_datagram`` bytes, each tagged with the full slot as its sequence.

    >>> key = session_key(b"k", bytes(16), bytes(16))
    >>> [len(d) for d in encode_fragments(1, 9, bytes(25), 19, key, DRONE_TO_BASE)]
    [19, 19, 14]
    """
    room = max_datagram - FRAGMENT_HEAD - TAG_BYTES
    if not 1 <= config_id <= 255 or room < 1 or not body:
        raise ValueError("a fragment needs a config id 1..255, a body and room for a piece")
    count = -(-len(body) // room)
    if count > MAX_FRAGMENTS:
        raise ValueError(
            f"a slot of {len(body)} B needs {count} fragments of {room} B (at most {MAX_FRAGMENTS})"
        )
    out = []
    for i in range(count):
        head = bytes([DGRAM_FRAGMENT, config_id]) + struct.pack("<H", slot & 0xFFFF)
        frag = head + bytes([i << 4 | (count - 1)]) + body[i * room : (i + 1) * room]
        out.append(frag + tag(key, direction, slot, frag, TAG_BYTES))
    return out


@dataclass(frozen=True)
class Fragment:
    """A fragment whose tag verified: piece ``index`` of ``count`` of a slot."""

    config_id: int
    slot: int
    index: int
    count: int
    piece: bytes


def verify_fragment(raw: bytes, key: bytes, direction: bytes, expected_slot: int) -> Fragment:
    """Check a fragment's tag before anything else; raises Forged or ProtocolError."""
    if len(raw) < FRAGMENT_HEAD + 1 + TAG_BYTES or raw[0] != DGRAM_FRAGMENT:
        raise ProtocolError(ErrorCode.BAD_FRAME, "not a fragment datagram", 0)
    body, got = raw[:-TAG_BYTES], raw[-TAG_BYTES:]
    (low,) = struct.unpack_from("<H", raw, 2)
    slot = extend16(low, expected_slot)
    if not hmac.compare_digest(tag(key, direction, slot, body, TAG_BYTES), got):
        raise Forged(f"tag of the fragment of slot {slot} does not verify")
    index, count = raw[4] >> 4, (raw[4] & 0x0F) + 1
    if index >= count:
        raise ProtocolError(ErrorCode.BAD_FRAME, f"fragment {index} of {count}", 4)
    return Fragment(raw[1], slot, index, count, bytes(body[FRAGMENT_HEAD:]))


def verify_slot_body(config_id: int, slot: int, body: bytes) -> VerifiedData:
    """A reassembled slot (the pieces of its fragments in order) read as the
    one-slot 0x31 datagram it is; raises ProtocolError."""
    r = Reader(body)
    count = r.u8()
    streams = r.varint()
    if count != 1 or streams > 8 * r.remaining():
        raise r.fail("a reassembled slot holds one slot and its presence bitmap")
    bm = r.take((streams + 7) // 8)
    for i in range(streams, len(bm) * 8):
        if bm[i // 8] >> (i % 8) & 1:
            raise r.fail("presence bit set beyond the slot's streams")
    return VerifiedData(config_id, slot, 1, bytes(bm), streams, bytes(body[r.pos :]))


def encode_control(counter: int, frame: bytes, key: bytes, direction: bytes) -> bytes:
    """A control datagram: counter, one link frame (docs/protocol.md), 8 B tag."""
    body = bytes([DGRAM_CONTROL]) + varint(counter) + frame
    return body + tag(key, direction, counter, body, CONTROL_TAG_BYTES)


def _verified_control(
    raw: bytes, key: bytes, direction: bytes, kind: int, min_body: int, what: str
) -> tuple[Reader, int]:
    """A control datagram or control fragment (``kind``) whose tag verified:
    a reader of its body after the counter, and the counter. The tag is
    checked before anything after the counter is read."""
    if len(raw) < min_body + CONTROL_TAG_BYTES or raw[0] != kind:
        raise ProtocolError(ErrorCode.BAD_FRAME, f"not a {what}", 0)
    body, got = raw[:-CONTROL_TAG_BYTES], raw[-CONTROL_TAG_BYTES:]
    r = Reader(body)
    r.u8()
    counter = r.varint()
    if not hmac.compare_digest(tag(key, direction, counter, body, CONTROL_TAG_BYTES), got):
        raise Forged(f"tag of {what} {counter} does not verify")
    return r, counter


def verify_control(raw: bytes, key: bytes, direction: bytes) -> tuple[int, bytes]:
    """(counter, frame) of a control datagram whose tag verifies."""
    r, counter = _verified_control(raw, key, direction, DGRAM_CONTROL, 3, "control datagram")
    return counter, bytes(r.take(r.remaining()))


#: Bytes of a control fragment around its piece: type, counter (a varint of
#: at most 5 bytes: counters below 2^35), frag, tag.
CONTROL_FRAGMENT_OVERHEAD = 1 + 5 + 1 + CONTROL_TAG_BYTES


def encode_control_fragments(
    counter: int, frames: bytes, max_datagram: int, key: bytes, direction: bytes
) -> list[bytes]:
    """The 0x42 datagrams of a control message too large for one packet:
    ``frames`` cut in order into at most 16 pieces, piece ``i`` under counter
    ``counter + i`` (consecutive: the receiver finds a message's first
    counter as ``counter - index``), each datagram at most ``max_datagram``
    bytes, each tagged as CONTROL.

    >>> key = session_key(b"k", bytes(16), bytes(16))
    >>> [len(d) for d in encode_control_fragments(7, bytes(40), 30, key, BASE_TO_DRONE)]
    [26, 26, 21]
    """
    room = max_datagram - CONTROL_FRAGMENT_OVERHEAD
    if room < 1 or not frames or counter + MAX_FRAGMENTS >= 1 << 35:
        raise ValueError(
            "a control fragment needs frames, room for a piece and a counter below 2^35"
        )
    count = -(-len(frames) // room)
    if count > MAX_FRAGMENTS:
        raise ValueError(
            f"a control message of {len(frames)} B needs {count} fragments of "
            f"{room} B (at most {MAX_FRAGMENTS})"
        )
    out = []
    for i in range(count):
        head = bytes([DGRAM_CONTROL_FRAGMENT]) + varint(counter + i)
        body = head + bytes([i << 4 | (count - 1)]) + frames[i * room : (i + 1) * room]
        out.append(body + tag(key, direction, counter + i, body, CONTROL_TAG_BYTES))
    return out


@dataclass(frozen=True)
class ControlFragment:
    """A control fragment whose tag verified: piece ``index`` of ``count`` of
    the message whose first fragment has counter ``counter - index``."""

    counter: int
    index: int
    count: int
    piece: bytes

    @property
    def first(self) -> int:
        return self.counter - self.index


def verify_control_fragment(raw: bytes, key: bytes, direction: bytes) -> ControlFragment:
    """Check a control fragment's tag before anything else; raises Forged or
    ProtocolError."""
    r, counter = _verified_control(
        raw, key, direction, DGRAM_CONTROL_FRAGMENT, 4, "control fragment"
    )
    frag = r.u8()
    index, count = frag >> 4, (frag & 0x0F) + 1
    if index >= count or counter < index:
        raise ProtocolError(ErrorCode.BAD_FRAME, f"control fragment {index} of {count}", r.pos - 1)
    return ControlFragment(counter, index, count, bytes(r.take(r.remaining())))


class ControlPieces:
    """Control messages put back together from their fragments, bounded: at
    most :data:`MAX_PARTIAL` messages in progress (the oldest given up), 16
    pieces each. :meth:`add` returns the message's frames once every piece
    is there; a piece whose count differs from its message's is counted
    ``malformed`` and dropped. Replays are the replay window's business (each
    piece has its own counter)."""

    MAX_PARTIAL = 4

    def __init__(self) -> None:
        self._partial: dict[int, tuple[int, dict[int, bytes]]] = {}
        self.malformed = 0
        self.given_up = 0

    def add(self, f: ControlFragment) -> bytes | None:
        count, pieces = self._partial.get(f.first, (f.count, {}))
        if count != f.count:
            self.malformed += 1
            return None
        pieces[f.index] = f.piece
        if len(pieces) == count:
            self._partial.pop(f.first, None)
            return b"".join(pieces[i] for i in range(count))
        if f.first not in self._partial and len(self._partial) >= self.MAX_PARTIAL:
            del self._partial[min(self._partial)]  # the oldest message: given up
            self.given_up += 1
        self._partial[f.first] = (count, pieces)
        return None


def encode_handshake(frame: bytes) -> bytes:
    """A handshake datagram (HELLO, CHALLENGE, AUTH, AUTH_OK, ERROR): the
    frames carry their own HMAC proofs, so no tag."""
    return bytes([DGRAM_HANDSHAKE]) + frame


def encode_nack(ranges: list[tuple[int, int]]) -> bytes:
    """NACK frame body: ranges (first slot, count) the SubBroker is missing."""
    if not 1 <= len(ranges) <= MAX_NACK_RANGES:
        raise ValueError(f"a NACK holds 1..{MAX_NACK_RANGES} ranges")
    body = varint(len(ranges))
    for first, n in ranges:
        body += varint(first) + varint(n)
    return varint(len(body) + 1) + bytes([NACK]) + body


def decode_nack(body: bytes) -> list[tuple[int, int]]:
    r = Reader(body)
    n = r.varint()
    if not 1 <= n <= MAX_NACK_RANGES:
        raise r.fail(f"a NACK holds 1..{MAX_NACK_RANGES} ranges")
    out = []
    for _ in range(n):
        first, count = r.varint(), r.varint()
        if not 1 <= count <= MAX_NACK_RANGE_SLOTS:
            raise r.fail(f"NACK range of 0 or more than {MAX_NACK_RANGE_SLOTS} slots")
        out.append((first, count))
    r.end()
    return out


class ReplayWindow:
    """Sequence numbers seen (RFC 4303's sliding window): a number older than
    the window or already seen is refused. ``size`` bounds the memory."""

    def __init__(self, size: int = 1024) -> None:
        self.size = size
        self.top = -1
        self.seen: set[int] = set()

    def seen_or_old(self, seq: int) -> bool:
        """True when ``accept(seq)`` would refuse it (nothing remembered)."""
        return seq <= self.top - self.size or seq in self.seen

    def accept(self, seq: int) -> bool:
        """True, and remember it, if ``seq`` is new and inside the window."""
        if seq <= self.top - self.size or seq in self.seen:
            return False
        self.seen.add(seq)
        if seq > self.top:
            self.top = seq
            floor = self.top - self.size
            if len(self.seen) > self.size:
                self.seen = {s for s in self.seen if s > floor}
        return True
