"""The checks that decide whether an MCAP record can be trusted in a damaged
file: a Chunk whose header agrees with its record length, whose data
decompresses to exactly its declared size (never more: a zstd bomb or a
crafted size stops at the bound) and matches its CRC, and whose records parse;
a Schema or Channel record that parses using every byte. :mod:`.scan` walks a
file with them and resyncs past what fails.

>>> chunk_header_fits(b"\\x06" + (40).to_bytes(8, "little") + bytes(40), 0)
True
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import io
import struct
import zlib
from dataclasses import dataclass, field

import lz4.frame
import zstandard
from mcap.data_stream import ReadDataStream
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.records import Channel, Message, Schema

#: A decompressed chunk larger than this is refused as a torn or crafted header
#: (the PubBroker closes a chunk at 64 MiB at most; its recovery uses the same bound).
MAX_CHUNK_BYTES = 1 << 28
#: A Schema or Channel record larger than this is not trusted by a resync.
MAX_DEFINITION_BYTES = 1 << 20

#: What parsing a damaged record can raise; any of them means "not trusted".
PARSE_ERRORS = (
    McapError,
    EOFError,
    struct.error,
    ValueError,
    UnicodeDecodeError,
    IndexError,
    KeyError,
    OverflowError,
    zstandard.ZstdError,
    RuntimeError,
)

_U64 = struct.Struct("<Q")
_U32 = struct.Struct("<I")


class Damaged(ValueError):
    """A record that cannot be trusted, and why."""


@dataclass
class ChunkContent:
    """The records of a chunk whose data checks."""

    schemas: list[Schema] = field(default_factory=list)
    channels: list[Channel] = field(default_factory=list)
    messages: list[Message] = field(default_factory=list)


def u64(buf: bytes | memoryview, at: int) -> int:
    return int(_U64.unpack_from(buf, at)[0])


def u32(buf: bytes | memoryview, at: int) -> int:
    return int(_U32.unpack_from(buf, at)[0])


def index_fits(buf: bytes | memoryview, at: int) -> bool:
    """Whether a Message Index record at ``at`` is well formed (its entries
    fill it exactly), so that stepping over it lands on the next record."""
    if len(buf) - at < 9 + 6:
        return False
    length = u64(buf, at + 1)
    return 6 <= length <= len(buf) - at - 9 and u32(buf, at + 11) == length - 6


def read_message(body: bytes) -> Message:
    """A Message record's body; raises :class:`Damaged`."""
    if len(body) < 22:
        raise Damaged("a message record shorter than its fields")
    try:
        m: Message = Message.read(ReadDataStream(io.BytesIO(body)), len(body))
    except PARSE_ERRORS as exc:
        raise Damaged(f"{type(exc).__name__}: {exc}") from exc
    return m


def chunk_header_fits(buf: bytes | memoryview, at: int) -> bool:
    """Whether a Chunk record at ``at`` has a header that agrees with its record
    length and the file (cheap: a resync tries it on every candidate byte)."""
    size = len(buf)
    if size - at < 9 + 40 or buf[at] != Opcode.CHUNK:
        return False
    length = u64(buf, at + 1)
    if length > size - at - 9 or length < 40:
        return False
    name = u32(buf, at + 9 + 28)
    if name > 4 or 40 + name > length:
        return False
    clen = u64(buf, at + 9 + 32 + name)
    return u64(buf, at + 9 + 16) <= MAX_CHUNK_BYTES and clen == length - 40 - name


@functools.cache
def _libzstd() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("zstd")  # libzstd1: required on Debian (dpkg uses it)
    if name is None:
        return None
    lib = ctypes.CDLL(name)
    lib.ZSTD_decompress.restype = ctypes.c_size_t
    size_t, buf = ctypes.c_size_t, ctypes.c_char_p
    lib.ZSTD_decompress.argtypes = [buf, size_t, buf, size_t]
    lib.ZSTD_isError.restype = ctypes.c_uint
    lib.ZSTD_isError.argtypes = [ctypes.c_size_t]
    return lib


def system_zstd(data: bytes, size: int) -> bytes | None:
    """``data`` decompressed by the system's libzstd into at most ``size``
    bytes, or None. Decoders differ in what they read past: python-zstandard's
    libzstd (1.5.7) refuses reserved bits that 1.5.4, the PubBroker's, ignores,
    so a chunk the PubBroker keeps (its CRC checks) is not dropped here."""
    lib = _libzstd()
    if lib is None:
        return None
    out = ctypes.create_string_buffer(max(size, 1))
    n = lib.ZSTD_decompress(out, size, data, len(data))
    return None if lib.ZSTD_isError(n) else out.raw[:n]


def decompress(compression: str, data: bytes, size: int) -> bytes:
    """``data`` decompressed to exactly ``size`` bytes; raises :class:`Damaged`
    otherwise. Never produces more than ``size + 1`` bytes."""
    if size > MAX_CHUNK_BYTES:
        raise Damaged(f"declared size {size} over the {MAX_CHUNK_BYTES}-byte bound")
    if compression == "":
        out = data
    elif compression == "zstd":
        declared = zstandard.frame_content_size(data)  # -1: not in the frame's header
        if declared not in (-1, size):
            raise Damaged(f"the zstd frame holds {declared} bytes, the chunk declares {size}")
        try:
            with zstandard.ZstdDecompressor().stream_reader(io.BytesIO(data)) as r:
                out = r.read(size + 1)
        except zstandard.ZstdError:
            read_past = system_zstd(data, size)
            if read_past is None:
                raise
            out = read_past
    elif compression == "lz4":
        if size > len(data) * 256 + 64:  # LZ4's ratio is below 255:1: nothing allocated
            raise Damaged(f"{len(data)} lz4 bytes cannot hold {size}")
        out = lz4.frame.LZ4FrameDecompressor().decompress(data, max_length=size + 1)
    else:
        raise Damaged(f"unknown compression {compression!r}")
    if len(out) != size:
        raise Damaged(f"decompressed to {len(out)} bytes, declared {size}")
    return out


def check_chunk(
    buf: bytes | memoryview, at: int, schemas: set[int], channels: set[int]
) -> ChunkContent:
    """The records of the Chunk record at ``at`` if its data checks (its
    messages' channels defined before or inside it); raises :class:`Damaged`."""
    if not chunk_header_fits(buf, at):
        raise Damaged("a chunk header that does not fit its record")
    length = u64(buf, at + 1)
    body = ReadDataStream(io.BytesIO(bytes(buf[at + 9 : at + 9 + length])))
    try:
        body.read8(), body.read8()  # message start and end times
        size, crc = body.read8(), body.read4()
        compression = body.read_prefixed_string()
        data = body.read(body.read8())
        plain = decompress(compression, data, size)
        if crc != 0 and zlib.crc32(plain) != crc:
            raise Damaged("CRC mismatch")
        return _records(plain, set(schemas), set(channels))
    except Damaged:
        raise
    except PARSE_ERRORS as exc:
        raise Damaged(f"{type(exc).__name__}: {exc}") from exc


def _records(plain: bytes, schemas: set[int], channels: set[int]) -> ChunkContent:
    out = ChunkContent()
    stream = ReadDataStream(io.BytesIO(plain))
    while stream.count < len(plain):
        opcode, length = stream.read1(), stream.read8()
        if length > len(plain) - stream.count:
            raise Damaged("a record inside the chunk runs past its end")
        body = ReadDataStream(io.BytesIO(stream.read(length)))
        if opcode == Opcode.MESSAGE:
            if length < 22:
                raise Damaged("a message record shorter than its fields")
            m = Message.read(body, length)
            if m.channel_id not in channels:
                raise Damaged(f"a message on channel {m.channel_id}, never defined")
            out.messages.append(m)
        elif opcode == Opcode.SCHEMA:
            s = Schema.read(body)
            schemas.add(s.id)
            out.schemas.append(s)
        elif opcode == Opcode.CHANNEL:
            c = Channel.read(body)
            channels.add(c.id)
            out.channels.append(c)
    return out


def definition_at(buf: bytes | memoryview, at: int, schemas: set[int]) -> Schema | Channel | None:
    """The Schema or Channel record at ``at`` if it parses using every byte, its
    schema is known, and the record after it is one that can follow it."""
    size = len(buf)
    if size - at < 9 or buf[at] not in (Opcode.SCHEMA, Opcode.CHANNEL):
        return None
    length = u64(buf, at + 1)
    if length > min(size - at - 9, MAX_DEFINITION_BYTES):
        return None
    nxt = at + 9 + length
    follows = (Opcode.SCHEMA, Opcode.CHANNEL, Opcode.CHUNK, Opcode.MESSAGE_INDEX, Opcode.DATA_END)
    if nxt != size and buf[nxt] not in follows:
        return None
    body = ReadDataStream(io.BytesIO(bytes(buf[at + 9 : nxt])))
    try:
        rec: Schema | Channel
        if buf[at] == Opcode.SCHEMA:
            schema: Schema = Schema.read(body)
            rec, ok = schema, schema.id != 0
        else:
            channel: Channel = Channel.read(body)
            rec, ok = channel, channel.schema_id == 0 or channel.schema_id in schemas
    except PARSE_ERRORS:
        return None
    return rec if ok and body.count == length else None
