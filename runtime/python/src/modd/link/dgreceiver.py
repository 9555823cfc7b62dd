"""The base station's side of a datagram link (udp, serial): verifies each
datagram's tag before anything else, refuses replays, decodes the slots it
carries with the schedule, tracks gaps for NACKs and keeps the counters the
SubBroker's status reports (docs/protocol.md, "Datagram transports").

The sender's side is :class:`DatagramSender` (the PubBroker's packing and
resend ring, in Python for tests, benchmarks and the reference)."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from . import codec
from .datagram import (
    BASE_TO_DRONE,
    DGRAM_FRAGMENT,
    DRONE_TO_BASE,
    DataDatagram,
    Forged,
    Fragment,
    ReplayWindow,
    VerifiedData,
    decode_nack,
    encode_control,
    encode_data,
    encode_nack,
    verify_control,
    verify_data,
    verify_fragment,
    verify_slot_body,
)
from .frames import ErrorCode, ProtocolError, Value, ValueKind
from .resend import GapTracker, ResendRing
from .schedule import SlotIterator


@dataclass
class LinkStats:
    """Counters of one datagram link (the SubBroker's status, per direction)."""

    datagrams: int = 0
    bytes_in: int = 0
    bytes_out: int = 0
    forged: int = 0
    replayed: int = 0
    malformed: int = 0
    slots: int = 0
    nacks: int = 0
    _recent: deque[tuple[float, int, int]] = field(default_factory=deque)

    def count(self, now: float, inbound: int = 0, outbound: int = 0) -> None:
        self.bytes_in += inbound
        self.bytes_out += outbound
        self._recent.append((now, inbound, outbound))
        while self._recent and self._recent[0][0] < now - 10.0:
            self._recent.popleft()

    def rates(self) -> tuple[float, float]:
        """Measured bytes/s (in, out) over the last 10 s."""
        if len(self._recent) < 2:
            return 0.0, 0.0
        span = max(self._recent[-1][0] - self._recent[0][0], 1.0)
        return (
            sum(i for _, i, _ in self._recent) / span,
            sum(o for _, _, o in self._recent) / span,
        )


class Reassembly:
    """The fragments (0x32) of the slots being put together; bounded: at most
    ``max_slots`` slots at once (the oldest partial slot is given up, and its
    slot is asked for again like any lost one), each at most 16 pieces.

    >>> r = Reassembly()
    >>> r.add(Fragment(1, 7, 1, 2, b"cd")) is None
    True
    >>> r.add(Fragment(1, 7, 0, 2, b"ab"))
    b'abcd'
    """

    def __init__(self, max_slots: int = 8) -> None:
        self.max_slots = max_slots
        self.partial: dict[int, tuple[int, int, dict[int, bytes]]] = {}
        self.given_up = 0

    def add(self, f: Fragment) -> bytes | None:
        """The slot's body once its last missing piece arrives, else None.
        Raises ProtocolError when the fragment contradicts the others of its slot."""
        config_id, count, pieces = self.partial.get(f.slot, (f.config_id, f.count, {}))
        if (config_id, count) != (f.config_id, f.count):
            del self.partial[f.slot]
            raise ProtocolError(
                ErrorCode.BAD_FRAME, f"fragment of slot {f.slot} disagrees with the others", 4
            )
        pieces[f.index] = f.piece  # a duplicate piece replaces its twin
        if len(pieces) == count:
            self.partial.pop(f.slot, None)
            return b"".join(pieces[i] for i in range(count))
        self.partial[f.slot] = (config_id, count, pieces)
        while len(self.partial) > self.max_slots:
            del self.partial[min(self.partial)]
            self.given_up += 1
        return None


class DatagramReceiver:
    """Decodes DATA datagrams of one config into ``(slot, values)`` where
    values lists the slot's streams in order (absent ones not present)."""

    def __init__(
        self,
        key: bytes,
        config_id: int,
        periods_us: Sequence[int],
        kinds: Sequence[ValueKind],
        window: int = 1024,
    ) -> None:
        self.key = key
        self.config_id = config_id
        self.periods_us = list(periods_us)
        self.kinds = list(kinds)
        self.replay = ReplayWindow(window)
        self.gaps = GapTracker()
        self.stats = LinkStats()
        self.reassembly = Reassembly()
        self.counter = 0
        #: The slot expected before the first datagram: 0 for a config that starts now,
        #: another station's last for a config joined while it runs (slot numbers
        #: travel as their low 16 bits: extend16 reads them near this one).
        self.expected = 0

    def _expected_slot(self) -> int:
        return self.gaps.next if self.gaps.next >= 0 else self.expected

    def on_datagram(self, raw: bytes, now: float) -> list[tuple[int, list[Value]]]:
        """The slots of a datagram that verifies and is new, decoded; [] otherwise
        (counted as forged, replayed or malformed)."""
        self.stats.count(now, inbound=len(raw))
        self.stats.datagrams += 1
        try:
            if raw[:1] == bytes([DGRAM_FRAGMENT]):
                return self._on_fragment(raw, now)
            v = verify_data(raw, self.key, DRONE_TO_BASE, self._expected_slot())
        except Forged:
            self.stats.forged += 1
            return []
        except ProtocolError:
            self.stats.malformed += 1
            return []
        return self._accept(v, now)

    def _on_fragment(self, raw: bytes, now: float) -> list[tuple[int, list[Value]]]:
        """A fragment: verified, kept until its slot is whole; a piece of a slot
        already delivered is a replay. Raises Forged, ProtocolError."""
        f = verify_fragment(raw, self.key, DRONE_TO_BASE, self._expected_slot())
        if f.config_id != self.config_id or self.replay.seen_or_old(f.slot):
            self.stats.replayed += 1
            return []
        body = self.reassembly.add(f)
        if body is None:
            return []
        return self._accept(verify_slot_body(f.config_id, f.slot, body), now)

    def _accept(self, v: VerifiedData, now: float) -> list[tuple[int, list[Value]]]:
        if v.config_id != self.config_id or not self.replay.accept(v.slot):
            self.stats.replayed += 1
            return []
        try:
            out = self._decode(v.slot, v.slot_count, v.presence, v.values)
        except ProtocolError:
            self.stats.malformed += 1
            return []
        self.gaps.received(v.slot, len(out), now)
        self.stats.slots += len(out)
        return out

    def _decode(
        self, first: int, count: int | None, presence: bytes | None, values: bytes
    ) -> list[tuple[int, list[Value]]]:
        r = codec.Reader(values)
        it = SlotIterator(self.periods_us)
        it.skip_to(first)
        out: list[tuple[int, list[Value]]] = []
        bit = 0
        slot = first
        chain: dict[int, int] = {}  # quantised values: a datagram decodes on its own
        while (count is None and r.remaining()) or (count is not None and len(out) < count):
            streams = next(it).streams
            vals: list[Value] = []
            for s in streams:
                present = presence is None or bool(presence[bit // 8] >> (bit % 8) & 1)
                bit += 1
                vals.append(codec._get_value(r, self.kinds[s], chain, s) if present else Value())
            out.append((slot, vals))
            slot += 1
        r.end()
        return out

    def nack(self, now: float, every: float) -> bytes | None:
        """A control datagram asking for the missing slots, when one is due."""
        ranges = self.gaps.due(now, every)
        if not ranges:
            return None
        self.counter += 1
        self.stats.nacks += 1
        raw = encode_control(self.counter, encode_nack(ranges), self.key, BASE_TO_DRONE)
        self.stats.count(now, outbound=len(raw))
        return raw


class DatagramSender:
    """Packs encoded slots into DATA datagrams (up to ``delay_s`` and
    ``room`` value bytes), keeps them in a resend ring, answers NACKs."""

    def __init__(self, key: bytes, config_id: int, delay_s: float, room: int) -> None:
        self.key = key
        self.config_id = config_id
        self.delay_s = delay_s
        self.room = room
        self.ring = ResendRing()
        self.group: list[tuple[int, float, bytes]] = []
        self.chain: dict[int, int] = {}  # the open datagram's last steps by stream
        self.window = ReplayWindow(64)

    def add_slot(self, slot: int, date: float, values: bytes) -> list[bytes]:
        """Queue one all-present slot; returns the datagrams to send now."""
        out: list[bytes] = []
        if self.group and (
            date - self.group[0][1] > self.delay_s
            or sum(len(v) for *_, v in self.group) + len(values) > self.room
        ):
            out.append(self.flush())
        self.group.append((slot, date, values))
        return out

    def add_values(
        self, slot: int, date: float, encode: Callable[[dict[int, int]], bytes]
    ) -> list[bytes]:
        """Queue one all-present slot whose values ``encode`` writes against the
        datagram's chain of quantised values (a slot that starts a datagram is
        written against an empty chain: every datagram decodes on its own)."""
        out: list[bytes] = []
        if self.group and date - self.group[0][1] > self.delay_s:
            out.append(self.flush())
        chain = dict(self.chain)
        values = encode(chain)
        if self.group and sum(len(v) for *_, v in self.group) + len(values) > self.room:
            out.append(self.flush())
            chain = {}
            values = encode(chain)
        self.chain = chain
        self.group.append((slot, date, values))
        return out

    def due(self, now: float) -> list[bytes]:
        """The pending datagram, once its first slot has waited the accepted delay."""
        if self.group and now - self.group[0][1] >= self.delay_s:
            return [self.flush()]
        return []

    def flush(self) -> bytes:
        first = self.group[0][0]
        raw = encode_data(
            DataDatagram(self.config_id, first, [v for *_, v in self.group]),
            self.key,
            DRONE_TO_BASE,
        )
        self.ring.add(first, len(self.group), raw)
        self.group.clear()
        self.chain = {}
        return raw

    def on_control(self, raw: bytes) -> list[bytes]:
        """Datagrams to resend for a NACK (nothing for a forged or replayed one)."""
        try:
            counter, frame = verify_control(raw, self.key, BASE_TO_DRONE)
        except (Forged, ProtocolError):
            return []
        if not self.window.accept(counter):
            return []
        f = codec.split_frame(frame)
        if f is None or f.type != 0x09:
            return []
        return self.ring.lookup(decode_nack(f.body))
