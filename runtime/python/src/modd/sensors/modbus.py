"""Modbus RTU, the part a reader of registers needs (sans I/O): read requests
(function 3, holding registers; 4, input registers), the CRC-16, the reply's
checks (unit, function, byte count, CRC) and exception replies, and register
words → numbers (int16, uint16, int32, uint32, float32; big or little word
order, bytes big-endian within a word as Modbus sends them).

Example::

    >>> read_request(1, HOLDING, 0, 2).hex()
    '010300000002c40b'
    >>> decode_words([0x41C8, 0x0000], "float32", "big")
    25.0
"""

from __future__ import annotations

import struct

HOLDING, INPUT = 3, 4
TABLE_FUNCTION = {"holding": HOLDING, "input": INPUT}
WORDS = {"int16": 1, "uint16": 1, "int32": 2, "uint32": 2, "float32": 2}
EXCEPTIONS = {
    1: "illegal function",
    2: "illegal data address",
    3: "illegal data value",
    4: "server device failure",
    5: "acknowledge",
    6: "server device busy",
    8: "memory parity error",
    10: "gateway path unavailable",
    11: "gateway target failed to respond",
}
MAX_REGISTERS = 125
_FORMAT = {
    "int16": ">h",
    "uint16": ">H",
    "int32": ">i",
    "uint32": ">I",
    "float32": ">f",
}  # per read, the protocol's limit


class BadReply(ValueError):
    """A reply that cannot be trusted (CRC, length, unit, function); the message says why."""


class ExceptionReply(ValueError):
    """The device answered with a Modbus exception."""

    def __init__(self, code: int) -> None:
        super().__init__(f"exception {code} ({EXCEPTIONS.get(code, 'unknown')})")
        self.code = code


def crc16(data: bytes) -> int:
    """Modbus CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF)."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def _with_crc(pdu: bytes) -> bytes:
    return pdu + struct.pack("<H", crc16(pdu))


def read_request(unit: int, function: int, address: int, count: int) -> bytes:
    """The RTU frame asking ``unit`` for ``count`` registers from ``address``."""
    return _with_crc(struct.pack(">BBHH", unit, function, address, count))


def reply_length(data: bytes, function: int) -> int | None:
    """How many bytes the reply starting ``data`` has, once known (None: read more)."""
    if len(data) < 3:
        return None
    if data[1] == function | 0x80:
        return 5
    return 5 + data[2]


def parse_reply(frame: bytes, unit: int, function: int, count: int) -> list[int]:
    """The register words of a complete reply; BadReply or ExceptionReply otherwise."""
    if len(frame) < 5:
        raise BadReply(f"reply of {len(frame)} bytes")
    if crc16(frame[:-2]) != struct.unpack("<H", frame[-2:])[0]:
        raise BadReply("bad CRC")
    if frame[0] != unit:
        raise BadReply(f"reply from unit {frame[0]}, asked {unit}")
    if frame[1] == function | 0x80:
        raise ExceptionReply(frame[2])
    if frame[1] != function:
        raise BadReply(f"reply to function {frame[1]}, asked {function}")
    if frame[2] != 2 * count or len(frame) != 5 + 2 * count:
        raise BadReply(f"{frame[2]} data bytes, asked {2 * count}")
    return list(struct.unpack(f">{count}H", frame[3:-2]))


def decode_words(words: list[int], kind: str, order: str) -> float | int:
    """The number held by a variable's words (``order`` little: low word first)."""
    if kind in ("int16", "uint16"):
        raw = struct.pack(">H", words[0])
    else:
        hi, lo = (words[1], words[0]) if order == "little" else (words[0], words[1])
        raw = struct.pack(">HH", hi, lo)
    value: float | int = struct.unpack(_FORMAT[kind], raw)[0]
    return value
