"""An independent minimal reader (and writer) of the MCAP spec for the archive
recovery tests: it shares no code with ``modd.archive`` or the PubBroker.
The oracle of a damaged file counts, chunk by chunk over the chunk boundaries
of the same file before it was damaged, the messages of every chunk whose data
still checks (record length, zstd/lz4/none to the declared size, CRC-32).
A zstd frame counts when python-zstandard's libzstd or the system's gets the
data back: they differ in what they read past (1.5.7 refuses reserved bits
that 1.5.4 ignores), and the CRC then says whether the data is whole.

>>> data = crashed_mcap(60, per_chunk=20)
>>> count_valid(data, records(data))
60
"""

from __future__ import annotations

import ctypes
import ctypes.util
import struct
import zlib

import lz4.frame
import zstandard

MAGIC = b"\x89MCAP0\r\n"
CHUNK, MESSAGE_INDEX, MESSAGE = 0x06, 0x07, 0x05
Record = tuple[int, int, int]  # opcode, offset, whole size


def _system_zstd(comp: bytes, usize: int) -> bytes | None:
    name = ctypes.util.find_library("zstd")
    if name is None:
        return None
    lib = ctypes.CDLL(name)
    lib.ZSTD_decompress.restype = ctypes.c_size_t
    lib.ZSTD_isError.restype = ctypes.c_uint
    out = ctypes.create_string_buffer(max(usize, 1))
    n = lib.ZSTD_decompress(out, ctypes.c_size_t(usize), comp, ctypes.c_size_t(len(comp)))
    return None if lib.ZSTD_isError(ctypes.c_size_t(n)) else out.raw[:n]


def records(data: bytes) -> list[Record]:
    """The top-level records of an undamaged file, front to back (to a torn tail)."""
    out, at = [], 8
    while len(data) - at >= 9:
        (length,) = struct.unpack_from("<Q", data, at + 1)
        if length > len(data) - at - 9:
            break
        out.append((data[at], at, 9 + length))
        at += 9 + length
    return out


def chunk_messages(data: bytes, at: int, size: int) -> list[tuple[int, int]] | None:
    """(channel, log_time) of the messages of the Chunk record at ``at`` if it checks."""
    if at + size > len(data) or data[at] != CHUNK:
        return None
    if struct.unpack_from("<Q", data, at + 1)[0] != size - 9:
        return None
    usize, crc, name_len = struct.unpack_from("<QII", data, at + 9 + 16)
    if name_len > 4 or usize > 1 << 26:
        return None
    name = data[at + 41 : at + 41 + name_len]
    (clen,) = struct.unpack_from("<Q", data, at + 41 + name_len)
    if 9 + 40 + name_len + clen != size:
        return None
    comp = data[at + 49 + name_len : at + size]
    try:
        if name == b"zstd":
            try:
                plain = zstandard.ZstdDecompressor().decompress(comp, max_output_size=usize)
            except zstandard.ZstdError:
                if (read_past := _system_zstd(comp, usize)) is None:
                    raise
                plain = read_past
        elif name == b"lz4":
            plain = lz4.frame.decompress(comp)
        else:
            plain = comp if name == b"" else b"\0"
    except (zstandard.ZstdError, RuntimeError, MemoryError):
        return None
    if len(plain) != usize or zlib.crc32(plain) != crc:
        return None
    out, p = [], 0
    while p + 9 <= len(plain):
        op, length = struct.unpack_from("<BQ", plain, p)
        if op == MESSAGE:
            ch, _seq, t = struct.unpack_from("<HIQ", plain, p + 9)
            out.append((ch, t))
        p += 9 + length
    return out


def count_valid(damaged: bytes, layout: list[Record]) -> int:
    """Messages in the chunks (at ``layout``'s boundaries) whose data checks."""
    n = 0
    for op, at, size in layout:
        if op == CHUNK and (m := chunk_messages(damaged, at, size)) is not None:
            n += len(m)
    return n


def _record(op: int, body: bytes) -> bytes:
    return struct.pack("<BQ", op, len(body)) + body


def _string(s: str) -> bytes:
    b = s.encode()
    return struct.pack("<I", len(b)) + b


def crashed_mcap(messages: int, per_chunk: int = 40, channels: int = 3) -> bytes:
    """A file as a crash leaves it: magic, header, one schema, ``channels``
    channels, zstd chunks each followed by its Message Index records, no
    summary, and a torn last chunk."""
    out = bytearray(MAGIC + _record(0x01, _string("") + _string("oracle")))
    out += _record(
        0x03,
        struct.pack("<H", 1)
        + _string("modd.float32")
        + _string("jsonschema")
        + struct.pack("<I", 2)
        + b"{}",
    )
    for ch in range(channels):
        out += _record(
            0x04,
            struct.pack("<HH", ch, 1)
            + _string(f"usv.c{ch}")
            + _string("json")
            + struct.pack("<I", 0),
        )
    for first in range(0, messages, per_chunk):
        plain, index = bytearray(), dict[int, list[tuple[int, int]]]()
        for i in range(first, min(messages, first + per_chunk)):
            ch, t = i % channels, 1_000_000 + i
            index.setdefault(ch, []).append((t, len(plain)))
            data = b'{"value":%d.%d}' % (i * 37 % 1001, i % 7)
            plain += _record(MESSAGE, struct.pack("<HIQQ", ch, i, t, t - 1) + data)
        comp = zstandard.ZstdCompressor(level=1).compress(bytes(plain))
        out += _record(
            CHUNK,
            struct.pack(
                "<QQQI",
                1_000_000 + first,
                1_000_000 + first + per_chunk,
                len(plain),
                zlib.crc32(plain),
            )
            + _string("zstd")
            + struct.pack("<Q", len(comp))
            + comp,
        )
        for ch, entries in sorted(index.items()):
            body = b"".join(struct.pack("<QQ", t, o) for t, o in entries)
            out += _record(MESSAGE_INDEX, struct.pack("<HI", ch, len(body)) + body)
    return bytes(out[:-5])  # torn: the last Message Index cut short


def flips(data: bytes, layout: list[Record]) -> list[tuple[int, int]]:
    """25 (offset, xor mask): 19 single-bit flips spread over the chunks and
    indexes, and 6 whole-byte flips on the fields that frame a chunk or an
    index (opcode, record length, CRC, uncompressed size, index length and
    channel)."""
    chunks = [at for op, at, _ in layout if op == CHUNK]
    indexes = [at for op, at, _ in layout if op == MESSAGE_INDEX]
    first = chunks[0]

    def in_data(p: int) -> int:  # a channel record between chunks: the next chunk instead
        rec = next((r for r in layout if r[1] <= p < r[1] + r[2]), None)
        if rec is None or rec[0] in (CHUNK, MESSAGE_INDEX):
            return p
        return next(at for at in chunks if at > p) + 20

    out = [
        (in_data(first + 1 + k * (len(data) - first - 2) // 18), 1 << (k % 8)) for k in range(19)
    ]
    after = [next(i for i in indexes if i > chunks[c]) for c in (11, 13)]
    out += [
        (chunks[3], 0xFF),
        (chunks[5] + 3, 0xFF),
        (chunks[7] + 9 + 24, 0xFF),
        (chunks[9] + 9 + 19, 0xFF),
        (after[0] + 2, 0xFF),
        (after[1] + 9, 0xFF),
    ]
    return out


def read_past_flip(data: bytes, layout: list[Record], chunks: int = 8) -> tuple[int, int] | None:
    """A single-bit flip in the zstd data of one of the first ``chunks`` chunks
    that python-zstandard refuses while the system's libzstd reads past it to
    the chunk's own data (a reserved bit, say); None if there is none."""
    for _op, at, size in [r for r in layout if r[0] == CHUNK][:chunks]:
        (name_len,) = struct.unpack_from("<I", data, at + 9 + 28)
        (usize,) = struct.unpack_from("<Q", data, at + 9 + 16)
        start = at + 49 + name_len
        comp = data[start : at + size]
        if data[at + 41 : at + 41 + name_len] != b"zstd" or not comp:
            continue
        plain = zstandard.ZstdDecompressor().decompress(comp, max_output_size=usize)
        for p in range(len(comp)):
            for bit in range(8):
                b = bytearray(comp)
                b[p] ^= 1 << bit
                try:
                    zstandard.ZstdDecompressor().decompress(bytes(b), max_output_size=usize)
                    continue
                except (zstandard.ZstdError, MemoryError):
                    pass
                if _system_zstd(bytes(b), usize) == plain:
                    return start + p, 1 << bit
    return None


def flipped(data: bytes, at: int, mask: int) -> bytes:
    b = bytearray(data)
    b[at] ^= mask
    return bytes(b)
