"""The base station's serial port (subbroker/dgport.py) on a pseudo-terminal this
test opens: each datagram one frame (COBS, CRC-16/CCITT-FALSE, 0x00) on the
wire, frames read back with no source address, a damaged one counted. The
oracle for the CRC is the standard library's (binascii.crc_hqx), for COBS a
decoder written from the paper's definition; the frames from the radio are
encoded here from the spec, not by the project's encoder."""

from __future__ import annotations

import binascii
import os
import pty
import select
import time

from modd.subbroker.dgport import SerialPort

DATAGRAM = bytes([0x40, 0x00, 0x07, 0x00, 0x00, 0xFF, 0x11])


def _cobs_decode(data: bytes) -> bytes:
    out = bytearray()
    i = 0
    while i < len(data):
        code = data[i]
        out += data[i + 1 : i + code]
        i += code
        if code < 0xFF and i < len(data):
            out.append(0)
    return bytes(out)


def _frame(datagram: bytes) -> bytes:
    """The frame the PubBroker would write, from the spec (docs/protocol.md)."""
    crc = binascii.crc_hqx(datagram, 0xFFFF).to_bytes(2, "little")
    body = datagram + crc
    out = bytearray()
    for chunk in body.split(b"\x00"):
        while len(chunk) >= 0xFE:
            out += bytes([0xFF]) + chunk[:0xFE]
            chunk = chunk[0xFE:]
        out += bytes([len(chunk) + 1]) + chunk
    return bytes(out) + b"\x00"


def _read_all(fd: int, until: int) -> bytes:
    got = b""
    deadline = time.monotonic() + 5
    while len(got) < until and time.monotonic() < deadline:
        if select.select([fd], [], [], 0.1)[0]:
            got += os.read(fd, 4096)
    return got


def _recv(port: SerialPort, count: int) -> list[tuple[bytes, object]]:
    got: list[tuple[bytes, object]] = []
    deadline = time.monotonic() + 5
    while len(got) < count and time.monotonic() < deadline:
        got += port.recv(0.1)
    return got


def test_a_datagram_is_one_frame_each_way_on_a_pseudo_terminal() -> None:
    radio, device = pty.openpty()
    port = SerialPort(os.ttyname(device), 57600, 252)
    try:
        port.send(DATAGRAM)
        wire = _read_all(radio, len(_frame(DATAGRAM)))
        assert wire == _frame(DATAGRAM) and port.wire_out == len(wire)
        body = _cobs_decode(wire[:-1])
        assert body[:-2] == DATAGRAM
        assert binascii.crc_hqx(body[:-2], 0xFFFF) == int.from_bytes(body[-2:], "little")
        # from the radio: a good frame, a damaged one, a good one
        damaged = bytearray(_frame(b"\x30\x01\x02\x03"))
        damaged[2] ^= 0x10
        os.write(radio, _frame(b"\x30\x05") + bytes(damaged) + _frame(DATAGRAM))
        assert _recv(port, 2) == [(b"\x30\x05", None), (DATAGRAM, None)]
        assert port.corrupt == 1 and port.peer is None
    finally:
        port.close()
        os.close(radio)
        os.close(device)
