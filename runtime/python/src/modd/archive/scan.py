"""Every record of an MCAP file that can be trusted, whether it was closed
properly, cut by a crash (``kill -9``: no summary, no footer, maybe a torn
last chunk) or damaged by bad bytes anywhere.

A damaged record does not stop the scan: it is skipped, the scan resyncs on
the next record that checks whole (:mod:`.chunks`), and the skipped region is
reported (offset, length, why). This is the same walk as the PubBroker's
start-up recovery (runtime/cpp/src/archive/chunk_scan.cpp).

>>> scan = scan_file("usv-20260101T000000Z-0000.mcap")    # doctest: +SKIP
>>> scan.complete, len(scan.messages), len(scan.skipped)   # doctest: +SKIP
(False, 5120, 0)
"""

from __future__ import annotations

import mmap
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from mcap.opcode import Opcode
from mcap.records import Channel, Message, Schema

from .chunks import (
    Damaged,
    check_chunk,
    chunk_header_fits,
    definition_at,
    index_fits,
    read_message,
    u32,
    u64,
)

MAGIC = b"\x89MCAP0\r\n"


class TooLarge(ValueError):
    """More messages than a scan may hold in memory."""


@dataclass(frozen=True)
class Skipped:
    """A damaged region of the file, skipped."""

    offset: int
    length: int
    why: str


@dataclass
class Scan:
    """What a file holds that can be trusted.

    ``complete`` is True when its data section ends with a Data End record
    whose CRC holds and the file ends with the magic (it was closed);
    ``skipped`` lists the damaged regions; ``error`` sums them up (None when
    the whole file was read)."""

    path: Path
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    messages: list[Message] = field(default_factory=list)
    chunks: int = 0
    skipped: list[Skipped] = field(default_factory=list)
    complete: bool = False
    magic: bool = True

    @property
    def skipped_bytes(self) -> int:
        return sum(s.length for s in self.skipped)

    @property
    def error(self) -> str | None:
        if not self.skipped:
            return None
        first = self.skipped[0]
        return (
            f"{self.path}: {len(self.skipped)} damaged or torn region(s) skipped "
            f"({self.skipped_bytes} bytes), the first at offset {first.offset}: {first.why}"
        )


def scan_file(path: str | Path, max_messages: int = 50_000_000) -> Scan:
    """Reads ``path`` record by record (CRCs checked), skipping damage;
    raises ``ValueError`` when it holds no MCAP record at all (no magic, no
    trusted record). ``max_messages`` bounds memory."""
    p = Path(path)
    with open(p, "rb") as f:
        size = f.seek(0, 2)
        if size == 0:
            raise ValueError(f"{p}: an empty file, not an MCAP file")
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as m:
            walk = _Walk(m, Scan(p), max_messages)
            try:
                walk.run()
            finally:
                walk.buf.release()
    out = walk.scan
    if not out.magic and not out.channels and not out.chunks:
        raise ValueError(f"{p}: not an MCAP file (no MCAP magic at offset 0, no record found)")
    return out


class _Walk:
    def __init__(self, m: mmap.mmap, scan: Scan, max_messages: int) -> None:
        self.m, self.buf = m, memoryview(m)
        self.scan, self.max_messages = scan, max_messages
        self.pos = 8

    def run(self) -> None:
        buf, size = self.buf, len(self.buf)
        self.scan.magic = bytes(buf[:8]) == MAGIC
        while self.pos < size:
            at = self.pos
            if size - at < 9:
                self.scan.skipped.append(Skipped(at, size - at, "a record cut short"))
                break
            op, length = buf[at], u64(buf, at + 1)
            if length > size - at - 9:
                self._skip(at, "a record longer than the rest of the file")
            elif op == Opcode.CHUNK:
                self._chunk(at)
            elif op in (Opcode.SCHEMA, Opcode.CHANNEL):
                self._definition(at)
            elif (op == Opcode.HEADER and at == 8) or (
                op == Opcode.MESSAGE_INDEX and index_fits(buf, at)
            ):
                self.pos = at + 9 + length  # indexes are written again by the recovery
            elif op == Opcode.MESSAGE:
                self._message(at, length)
            elif op == Opcode.DATA_END and length >= 4 and self._data_end_holds(at):
                self.scan.complete = bytes(buf[size - 8 :]) == MAGIC
                break  # the summary follows: written again
            else:
                self._skip(at, "an unexpected record")

    def _skip(self, at: int, why: str) -> None:
        to = self._resync(at + 1)
        self.scan.skipped.append(Skipped(at, to - at, why))
        self.pos = to

    def _chunk(self, at: int) -> None:
        try:
            content = check_chunk(self.buf, at, set(self.scan.schemas), set(self.scan.channels))
        except Damaged as exc:
            self._skip(at, f"a chunk whose data does not check ({exc})")
            return
        for s in content.schemas:
            self.scan.schemas.setdefault(s.id, s)
        for c in content.channels:
            self.scan.channels.setdefault(c.id, c)
        self._keep(content.messages)
        self.scan.chunks += 1
        self.pos = at + 9 + u64(self.buf, at + 1)

    def _definition(self, at: int) -> None:
        rec = definition_at(self.buf, at, set(self.scan.schemas))
        if rec is None:
            self._skip(at, "a schema or channel record that does not parse")
            return
        if isinstance(rec, Schema):
            self.scan.schemas.setdefault(rec.id, rec)
        else:
            self.scan.channels.setdefault(rec.id, rec)
        self.pos = at + 9 + u64(self.buf, at + 1)

    def _message(self, at: int, length: int) -> None:
        """A message outside chunks (an unchunked file): kept if it parses."""
        try:
            m = read_message(bytes(self.buf[at + 9 : at + 9 + length]))
        except Damaged:
            m = None
        if m is None or m.channel_id not in self.scan.channels:
            self._skip(at, "a message record that does not parse")
            return
        self._keep([m])
        self.pos = at + 9 + length

    def _keep(self, messages: list[Message]) -> None:
        if len(self.scan.messages) + len(messages) > self.max_messages:
            raise TooLarge(f"{self.scan.path}: more than {self.max_messages} messages")
        self.scan.messages.extend(messages)

    def _data_end_holds(self, at: int) -> bool:
        """A Data End whose CRC holds, or is 0 (not computed: the ``mcap`` writer's)."""
        crc = u32(self.buf, at + 9)
        return crc == 0 or crc == zlib.crc32(self.buf[:at])

    def _resync(self, start: int) -> int:
        """The next offset from ``start`` where a record checks whole, else the end."""
        buf, size = self.buf, len(self.buf)
        schemas, channels = set(self.scan.schemas), set(self.scan.channels)
        # mmap.find jumps from candidate to candidate (the next byte of each opcode that
        # can start a trusted record): a resync over megabytes stays fast
        ops = (bytes([Opcode.CHUNK]), bytes([Opcode.SCHEMA]), bytes([Opcode.CHANNEL]))
        nxt = {op: self.m.find(op, start) for op in ops}
        while True:
            live = [i for i in nxt.values() if 0 <= i <= size - 9]
            if not live:
                return size
            p = min(live)
            if self._trusted_at(p, schemas, channels):
                return p
            op = bytes([buf[p]])
            nxt[op] = self.m.find(op, p + 1)

    def _trusted_at(self, p: int, schemas: set[int], channels: set[int]) -> bool:
        if self.buf[p] != Opcode.CHUNK:
            return definition_at(self.buf, p, schemas) is not None
        if not chunk_header_fits(self.buf, p):
            return False
        try:
            check_chunk(self.buf, p, schemas, channels)
        except Damaged:
            return False
        return True
