"""How bytes reach the autopilot: a pymavlink connection (``mavutil``) used for
transport only — the bridge decodes frames itself (see ``decode.py``).

URLs are pymavlink's: ``udpin:HOST:PORT`` (listen; replies go to whoever sent),
``udpout:HOST:PORT``, ``tcp:HOST:PORT``, or a serial device with an optional
baud rate, ``/dev/ttyUSB0,57600`` (through ``pyserial``).

Example::

    link = open_transport("udpin:127.0.0.1:14550", source_system=255)
    if link.wait(0.1):
        data = link.recv()
"""

from __future__ import annotations

import select
import time
from typing import Any, Protocol

DATAGRAM_PREFIXES = ("udp:", "udpin:", "udpout:", "udpbcast:", "mcast:")


class Transport(Protocol):
    #: each recv() returns one whole datagram (UDP) rather than a piece of a stream
    datagram: bool

    def wait(self, timeout: float) -> bool: ...

    def recv(self) -> bytes: ...

    def write(self, data: bytes) -> None: ...

    def close(self) -> None: ...


def split_serial(url: str) -> tuple[str, int]:
    """``/dev/ttyUSB0,57600`` → (``/dev/ttyUSB0``, 57600); the baud rate defaults to 57600."""
    device, _, baud = url.partition(",")
    if baud and not baud.isdigit():
        raise ValueError(
            f"bad baud rate in {url!r}: expected DEVICE,BAUD such as /dev/ttyUSB0,57600"
        )
    return device, int(baud or 57600)


class MavutilTransport:
    def __init__(self, url: str, source_system: int = 255, source_component: int = 0) -> None:
        from pymavlink import mavutil  # type: ignore[import-untyped]

        self.url = url
        self.datagram = url.startswith(DATAGRAM_PREFIXES)
        device, baud = (url, 115200) if ":" in url else split_serial(url)
        try:
            self._conn: Any = mavutil.mavlink_connection(
                device, baud=baud, source_system=source_system, source_component=source_component
            )
        except ModuleNotFoundError as exc:
            raise RuntimeError(
                f"{url}: serial ports need the pyserial package (pip install pyserial): {exc}"
            ) from exc

    def wait(self, timeout: float) -> bool:
        fd = getattr(self._conn, "fd", None)
        if fd is None:
            time.sleep(min(timeout, 0.01))
            return True
        readable, _, _ = select.select([fd], [], [], timeout)
        return bool(readable)

    def recv(self) -> bytes:
        data = self._conn.recv(4096)
        return bytes(data) if data else b""

    def write(self, data: bytes) -> None:
        self._conn.write(data)

    def close(self) -> None:
        self._conn.close()


def open_transport(url: str, source_system: int = 255, source_component: int = 0) -> Transport:
    return MavutilTransport(url, source_system, source_component)
