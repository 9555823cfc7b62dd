"""Serial framing of the MoDD link's datagrams (docs/protocol.md, "Serial
framing"): COBS over the datagram followed by its CRC-16/CCITT-FALSE
(little-endian), then one 0x00 delimiter. At most the radio's packet size
on the wire. A frame whose CRC fails is counted as corrupt and dropped.

>>> frame = encode_frame(b"\\x00\\x01")
>>> frame.hex()
'0104012e0d00'
>>> Deframer(252).feed(frame)
[b'\\x00\\x01']
"""

from __future__ import annotations


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection).

    >>> hex(crc16(b"123456789"))
    '0x29b1'
    """
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def cobs_encode(data: bytes) -> bytes:
    out = bytearray([0])
    code_at = 0
    for b in data:
        if b == 0:
            out[code_at] = len(out) - code_at
            code_at = len(out)
            out.append(0)
            continue
        out.append(b)
        if len(out) - code_at == 0xFF:
            out[code_at] = 0xFF
            code_at = len(out)
            out.append(0)
    out[code_at] = len(out) - code_at
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Raises ValueError on a malformed COBS block."""
    out = bytearray()
    i = 0
    while i < len(data):
        code = data[i]
        if code == 0 or i + code > len(data) + (0 if code == 1 else 0):
            raise ValueError(f"bad COBS code at byte {i}")
        block = data[i + 1 : i + code]
        if len(block) != code - 1 or 0 in block:
            raise ValueError(f"bad COBS block at byte {i}")
        out += block
        i += code
        if code != 0xFF and i < len(data):
            out.append(0)
    return bytes(out)


def encode_frame(datagram: bytes) -> bytes:
    crc = crc16(datagram)
    return cobs_encode(datagram + bytes([crc & 0xFF, crc >> 8])) + b"\x00"


class Deframer:
    """Splits a serial byte stream into datagrams; bounded by ``max_frame``
    (bytes between delimiters, the radio's packet size). Counts what it drops."""

    def __init__(self, max_frame: int) -> None:
        self.max_frame = max_frame
        self.buf = bytearray()
        self.corrupt = 0
        self.oversized = 0
        self._skipping = False

    def feed(self, data: bytes) -> list[bytes]:
        out: list[bytes] = []
        for b in data:
            if b != 0:
                if self._skipping:
                    continue
                self.buf.append(b)
                if len(self.buf) > self.max_frame:
                    self.oversized += 1
                    self.buf.clear()
                    self._skipping = True
                continue
            if self._skipping:
                self._skipping = False
                continue
            if self.buf:
                frame = self._decode(bytes(self.buf))
                if frame is not None:
                    out.append(frame)
                self.buf.clear()
        return out

    def _decode(self, raw: bytes) -> bytes | None:
        try:
            body = cobs_decode(raw)
        except ValueError:
            self.corrupt += 1
            return None
        if len(body) < 3 or crc16(body[:-2]) != body[-2] | body[-1] << 8:
            self.corrupt += 1
            return None
        return body[:-2]
