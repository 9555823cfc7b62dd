"""Where the base station's datagrams come and go (docs/protocol.md,
"Datagram transports"): a UDP socket connected to the PubBroker's endpoint,
or a character device (a telemetry radio, a UART, a pseudo-terminal) in raw
mode, each datagram one serial frame (COBS + CRC-16, 0x00). Each datagram
read comes with its source address (None on a serial line): the session
binds to the PubBroker's (docs/security.md).

>>> port = UdpPort(("127.0.0.1", 7171))          # doctest: +SKIP
>>> port.send(raw); port.recv(0.1)               # doctest: +SKIP
[(b'...', ('127.0.0.1', 7171))]
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
import termios
import tty
from collections.abc import Hashable
from typing import Protocol

from modd.link.serialframe import Deframer, encode_frame

#: IPv4 (20) + UDP (8): what a datagram costs on the wire beyond its payload.
UDP_IP_HEADER_BYTES = 28

_BAUD = {
    9600: termios.B9600,
    19200: termios.B19200,
    38400: termios.B38400,
    57600: termios.B57600,
    115200: termios.B115200,
    230400: termios.B230400,
}


class DatagramPort(Protocol):
    """One end of a datagram link. ``wire_in``/``wire_out`` count the bytes on
    the wire (headers or framing included)."""

    wire_in: int
    wire_out: int

    @property
    def peer(self) -> Hashable | None:
        """The address the PubBroker's datagrams come from (None: a point-to-point line)."""
        ...

    @property
    def corrupt(self) -> int: ...

    def send(self, datagram: bytes) -> None: ...

    def announce(self) -> None:
        """Tell the radio where this station is without transmitting (a standby
        station that listens: docs/fleet.md, "Diversity reception")."""
        ...

    def recv(self, timeout_s: float) -> list[tuple[bytes, Hashable | None]]:
        """The datagrams that came within ``timeout_s``, each with its source."""
        ...

    def close(self) -> None: ...


class UdpPort:
    """A UDP socket that sends to the PubBroker's endpoint (loopback in tests) and
    reads from any address, so that a stranger's datagrams are seen and counted."""

    def __init__(self, endpoint: tuple[str, int]) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        addr = socket.getaddrinfo(endpoint[0], endpoint[1], socket.AF_INET, socket.SOCK_DGRAM)[0][4]
        self._peer = (str(addr[0]), int(addr[1]))  # as recvfrom reports it
        self.wire_in = self.wire_out = 0

    @property
    def peer(self) -> tuple[str, int]:
        return self._peer

    @property
    def corrupt(self) -> int:
        return 0  # the UDP checksum drops a damaged datagram before us

    def send(self, datagram: bytes) -> None:
        with contextlib.suppress(OSError):  # nobody there (yet): lost, as on a radio
            self.sock.sendto(datagram, self._peer)
            self.wire_out += len(datagram) + UDP_IP_HEADER_BYTES

    def announce(self) -> None:
        """An empty datagram: a UDP bridge of a modem learns its client from it, and a
        radio has nothing to send (modd-radio does the same)."""
        with contextlib.suppress(OSError):
            self.sock.sendto(b"", self._peer)

    def recv(self, timeout_s: float) -> list[tuple[bytes, Hashable | None]]:
        out: list[tuple[bytes, Hashable | None]] = []
        ready, _, _ = select.select([self.sock], [], [], timeout_s)
        while ready and len(out) < 64:
            try:
                data, source = self.sock.recvfrom(65535)
            except (BlockingIOError, ConnectionRefusedError):
                break  # an ICMP error of an earlier send: the far end is not up
            self.wire_in += len(data) + UDP_IP_HEADER_BYTES
            out.append((data, source[:2]))
            ready, _, _ = select.select([self.sock], [], [], 0)
        return out

    def close(self) -> None:
        self.sock.close()


class SerialPort:
    """A character device in raw mode at ``baud``; frames of at most
    ``max_frame`` bytes (the radio's packet)."""

    def __init__(self, device: str, baud: int, max_frame: int) -> None:
        self.fd = os.open(device, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            tty.setraw(self.fd)
            attrs = termios.tcgetattr(self.fd)
            speed = _BAUD.get(baud)
            if speed is not None:
                attrs[4] = attrs[5] = speed
                termios.tcsetattr(self.fd, termios.TCSANOW, attrs)
        except termios.error:
            pass  # not a terminal (a FIFO in a test): raw bytes anyway
        self.deframer = Deframer(max_frame)
        self.wire_in = self.wire_out = 0

    @property
    def peer(self) -> None:
        return None  # one radio at the other end of the line

    @property
    def corrupt(self) -> int:
        return self.deframer.corrupt + self.deframer.oversized

    def send(self, datagram: bytes) -> None:
        frame = encode_frame(datagram)
        view = memoryview(frame)
        while view:
            try:
                n = os.write(self.fd, view)
            except BlockingIOError:
                select.select([], [self.fd], [], 0.5)
                continue
            self.wire_out += n
            view = view[n:]

    def announce(self) -> None:
        pass  # a modem on a serial line gives what it hears to the line: nothing to say

    def recv(self, timeout_s: float) -> list[tuple[bytes, Hashable | None]]:
        ready, _, _ = select.select([self.fd], [], [], timeout_s)
        if not ready:
            return []
        try:
            data = os.read(self.fd, 65536)
        except BlockingIOError:
            return []
        except OSError as exc:  # EIO: the other end of a pseudo-terminal went away
            raise ConnectionError(f"serial device: {exc.strerror}") from exc
        self.wire_in += len(data)
        return [(d, None) for d in self.deframer.feed(data)]

    def close(self) -> None:
        with contextlib.suppress(OSError):
            os.close(self.fd)
