"""A MoDD archive (MCAP) read front to back, one chunk at a time, as batches
of one topic's samples: bounded memory whatever the file's length.

Its own record scanner rather than the official reader's, for two reasons:
speed (a chunk's messages are sliced out of the decompressed bytes in one
loop, their values decoded by NumPy in one call) and location (an error names
the file and the byte offset of the record that is wrong). The tests read the
same files with the official ``mcap`` reader as the oracle.

A file cut short (a crash, or a file still being written) is read up to its
last complete record and reported as ``cut``; a record that is not what the
MCAP specification says (bad CRC, impossible length, undecodable message) is
an :class:`ArchiveError`.

>>> for batch in read_file(Path("usv-20260101T000000Z-0000.mcap")):  # doctest: +SKIP
...     print(batch.topic, len(batch.time_ns))
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

import numpy as np
from modd_contracts.archive_record import PREFIX, channel_type

from .record import RecordError, decode_texts, decode_values

MAGIC = b"\x89MCAP0\r\n"
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_DATA_END = (
    0x01,
    0x02,
    0x03,
    0x04,
    0x05,
    0x06,
    0x0F,
)
_REC = struct.Struct("<BQ")
_MSG = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time
_MSG_HEAD = 2 + 4 + 8 + 8
#: No record of a MoDD archive is near this; a longer length is a corrupt file.
MAX_RECORD = 1 << 31


class ArchiveError(Exception):
    """A corrupt archive, located: file and byte offset."""

    def __init__(self, path: Path, offset: int, why: str) -> None:
        super().__init__(f"{path}: offset {offset}: {why}")
        self.path, self.offset, self.why = path, offset, why


@dataclass
class Batch:
    """Samples of one topic, in file order (time order for one topic)."""

    topic: str
    value_type: str
    time_ns: np.ndarray  # int64, ns since the Unix epoch (the MCAP log time)
    value: np.ndarray  # record.dtype_of(value_type)
    #: int64, the MCAP publish time: the publisher's stamp (the instrument's clock for
    #: a sensor declaring ``clock = instrument``); None where the reader has none.
    publish_ns: np.ndarray | None = None
    #: bool, per sample: a base-station record's window delivered by backfill (the
    #: delivered value's ``backfilled``), not live; None for the archive's samples.
    historical: np.ndarray | None = None


@dataclass
class FileState:
    """What a read learnt about a file: its channels, and whether it was cut."""

    path: Path
    topics: dict[int, tuple[str, str | None]] = field(default_factory=dict)  # id -> (topic, type)
    schemas: dict[int, str] = field(default_factory=dict)
    cut_at: int | None = None  # offset of the incomplete record, when the file was cut
    closed: bool = False  # ended with a footer
    size: int = 0


def _string(buf: bytes, at: int) -> tuple[str, int]:
    (n,) = struct.unpack_from("<I", buf, at)
    return buf[at + 4 : at + 4 + n].decode("utf-8"), at + 4 + n


def _schema(state: FileState, buf: bytes) -> None:
    (sid,) = struct.unpack_from("<H", buf, 0)
    state.schemas[sid], _ = _string(buf, 2)


def _channel(state: FileState, buf: bytes) -> None:
    cid, sid = struct.unpack_from("<HH", buf, 0)
    topic, at = _string(buf, 4)
    _encoding, at = _string(buf, at)
    (size,) = struct.unpack_from("<I", buf, at)
    meta: dict[str, str] = {}
    at, end = at + 4, at + 4 + size
    while at < end:
        key, at = _string(buf, at)
        meta[key], at = _string(buf, at)
    state.topics[cid] = (topic, channel_type(state.schemas.get(sid, ""), meta))


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        import lz4.frame

        out: bytes = lz4.frame.decompress(data)
        return out
    raise ValueError(f"unknown chunk compression {compression!r}")


def _chunk(state: FileState, buf: bytes, offset: int) -> bytes:
    _start, _end, size, crc = struct.unpack_from("<QQQI", buf, 0)
    compression, at = _string(buf, 28)
    (n,) = struct.unpack_from("<Q", buf, at)
    try:
        data = _decompress(compression, buf[at + 8 : at + 8 + n], size)
    except Exception as exc:  # noqa: BLE001 - zstd/lz4 raise their own types
        raise ArchiveError(state.path, offset, f"chunk does not decompress ({exc})") from None
    if len(data) != size or (crc and zlib.crc32(data) != crc):
        raise ArchiveError(
            state.path,
            offset,
            "chunk CRC mismatch (corrupt chunk); `modd archive recover` keeps every valid chunk",
        )
    return data


Pending = dict[int, tuple[list[int], list[int], list[bytes]]]
#: A chunk of the PubBroker's is messages only, each ``{"value":TEXT}``: NumPy finds
#: every value's prefix in one pass over the bytes, each record's header sits just before
#: its prefix, and the value texts are cut out as rows of one byte array. Used only when
#: the records so found tile the chunk exactly, with the opcodes, lengths and closing
#: braces they declare (a prefix's bytes met by chance elsewhere breaks the tiling); else
#: the record loop reads the chunk.
_PREFIX = np.frombuffer(PREFIX, dtype=np.uint8)
_HEAD = np.dtype([("len", "<u8"), ("ch", "<u2"), ("seq", "<u4"), ("log", "<u8"), ("pub", "<u8")])
_BEFORE = 9 + _MSG_HEAD  # bytes of a message record before its data


@dataclass
class Located:
    """A messages-only chunk's records: channel, times, and where each value text lies."""

    channels: np.ndarray  # uint16 channel id per message
    times: np.ndarray  # int64 log times
    pubs: np.ndarray  # int64 publish times
    text_at: np.ndarray  # offset of each value text in ``raw``
    text_len: np.ndarray  # its length
    raw: np.ndarray  # the chunk's bytes (uint8), zero-padded past the end

    def texts(self, rows: np.ndarray) -> np.ndarray:
        """The value texts of messages ``rows`` (a bytes array, NUL-padded)."""
        at, lens = self.text_at[rows], self.text_len[rows]
        width = max(int(lens.max()), 1) if len(rows) else 1
        grid = _windows(self.raw, width)[at]
        grid *= np.arange(width) < lens[:, None]
        out: np.ndarray = grid.view(f"S{width}").ravel()
        return out


def _windows(raw: np.ndarray, width: int) -> np.ndarray:
    """Every ``width`` consecutive bytes of ``raw`` (uint8, contiguous) as the rows of a
    view (NumPy's ``sliding_window_view``, without its checks: ~50 us a call, and a
    chunk has a call per channel)."""
    rows = max(len(raw) - width + 1, 0)
    return np.ndarray((rows, width), np.uint8, buffer=raw, strides=(1, 1))


def _prefixes(raw: np.ndarray) -> np.ndarray:
    """Offsets in ``raw`` where the archive record's prefix stands after a header."""
    n = len(raw) - len(_PREFIX)
    at = np.flatnonzero(raw[_BEFORE:n] == _PREFIX[0]) + _BEFORE
    ok = np.ones(len(at), dtype=bool)
    for i in range(1, len(_PREFIX)):
        ok &= raw[at + i] == _PREFIX[i]
    return at[ok]


def _fast(buf: bytes) -> Located | None:
    """The messages of a messages-only chunk of archive records, or None."""
    raw = np.frombuffer(buf, dtype=np.uint8)
    at = _prefixes(raw) if len(raw) > _BEFORE + len(_PREFIX) else raw[:0].astype(np.int64)
    if len(at) == 0:
        return None
    starts = at - _BEFORE
    if starts[0] != 0:
        return None
    head = _windows(raw, _HEAD.itemsize)[starts + 1].view(_HEAD).ravel()
    ends = starts + 9 + head["len"].astype(np.int64)
    if ends[-1] != len(raw) or not np.array_equal(ends[:-1], starts[1:]):
        return None  # other records too (schemas, channels): the record loop reads it
    if not ((raw[starts] == OP_MESSAGE).all() and (raw[ends - 1] == ord("}")).all()):
        return None
    text_at = at + len(_PREFIX)
    text_len = ends - 1 - text_at
    pad = np.zeros(len(raw) + int(text_len.max()) + 1, dtype=np.uint8)
    pad[: len(raw)] = raw
    times, pubs = head["log"].astype(np.int64), head["pub"].astype(np.int64)
    return Located(head["ch"], times, pubs, text_at, text_len, pad)


def _located_batches(
    state: FileState, loc: Located, offset: int, only: set[str] | None
) -> Iterator[Batch]:
    order = np.argsort(loc.channels, kind="stable")
    sorted_ch = loc.channels[order]
    cuts = np.flatnonzero(np.diff(sorted_ch)) + 1
    for rows in np.split(order, cuts):
        wanted = _wanted(state, int(loc.channels[rows[0]]), offset, only)
        if wanted is None:
            continue
        topic, vtype = wanted
        try:
            values = decode_texts(vtype, loc.texts(rows))
        except RecordError as exc:
            raise ArchiveError(state.path, offset, f"topic {topic}: {exc}") from None
        yield Batch(topic, vtype, loc.times[rows], values, loc.pubs[rows])


def _wanted(
    state: FileState, cid: int, offset: int, only: set[str] | None
) -> tuple[str, str] | None:
    """(topic, value type) of channel ``cid`` when its messages are to be decoded: None
    for another tool's channel or a topic not asked for; ArchiveError for an unknown id."""
    topic, vtype = state.topics.get(cid, (None, None))
    if topic is None:
        raise ArchiveError(state.path, offset, f"message on unknown channel {cid}")
    if vtype is None or (only is not None and topic not in only):
        return None
    return topic, vtype


def _records(state: FileState, buf: bytes, base: int, pending: Pending) -> None:
    """The schemas, channels and messages of a chunk's records (or of one
    top-level record), messages gathered per channel."""
    at, end = 0, len(buf)
    while at < end:
        if at + 9 > end:
            raise ArchiveError(state.path, base + at, "record header runs past its chunk")
        op, length = _REC.unpack_from(buf, at)
        body = at + 9
        if body + length > end:
            raise ArchiveError(state.path, base + at, "record runs past its chunk")
        if op == OP_MESSAGE:
            cid, _seq, t, pub = _MSG.unpack_from(buf, body)
            times, pubs, datas = pending.setdefault(cid, ([], [], []))
            times.append(t)
            pubs.append(pub)
            datas.append(buf[body + _MSG_HEAD : body + length])
        elif op == OP_SCHEMA:
            _schema(state, buf[body : body + length])
        elif op == OP_CHANNEL:
            _channel(state, buf[body : body + length])
        at = body + length


def _batches(
    state: FileState,
    pending: Pending,
    offset: int,
    only: set[str] | None,
) -> Iterator[Batch]:
    for cid, (times, pubs, datas) in pending.items():
        wanted = _wanted(state, cid, offset, only)
        if wanted is None:
            continue
        topic, vtype = wanted
        try:
            values = decode_values(vtype, datas)
        except RecordError as exc:
            raise ArchiveError(state.path, offset, f"topic {topic}: {exc}") from None
        as_ns = np.asarray(times, dtype=np.int64)
        yield Batch(topic, vtype, as_ns, values, np.asarray(pubs, dtype=np.int64))


def _read_record(f: BinaryIO, state: FileState, offset: int) -> tuple[int, bytes] | None:
    """(opcode, body) of the record at ``offset``; None when the file ends
    there without a footer, or with a record it does not hold whole (cut)."""
    head = f.read(9)
    if len(head) < 9:
        state.cut_at = offset
        return None
    op, length = _REC.unpack_from(head)
    if offset + 9 + length > state.size:
        state.cut_at = offset
        return None
    if length > MAX_RECORD:
        raise ArchiveError(state.path, offset, f"record length {length} is impossible")
    return op, f.read(length)


def read_file(
    path: Path,
    state: FileState | None = None,
    progress: Callable[[int], None] | None = None,
    only: set[str] | None = None,
) -> Iterator[Batch]:
    """Every sample of ``path`` as batches (one per topic per chunk).

    ``state`` (filled as the file is read) tells the caller about a cut;
    ``progress`` is called with the bytes read so far after each chunk; ``only``
    limits the batches to those topics (the others are not decoded)."""
    st = state if state is not None else FileState(path)
    st.size = path.stat().st_size
    with path.open("rb") as f:
        if f.read(8) != MAGIC:
            raise ArchiveError(path, 0, "not an MCAP file (no MCAP magic)")
        offset = 8
        while True:
            rec = _read_record(f, st, offset)
            if rec is None:
                return
            op, body = rec
            slow: Pending = {}
            fast = None
            if op == OP_CHUNK:
                data = _chunk(st, body, offset)
                fast = _fast(data)
                if fast is None:
                    _records(st, data, offset, slow)
            elif op in (OP_SCHEMA, OP_CHANNEL, OP_MESSAGE):
                _records(st, _REC.pack(op, len(body)) + body, offset, slow)
            elif op == OP_FOOTER:
                st.closed = True
                return
            if fast is not None:
                yield from _located_batches(st, fast, offset, only)
            else:
                yield from _batches(st, slow, offset, only)
            offset += 9 + len(body)
            if progress is not None:
                progress(offset)
