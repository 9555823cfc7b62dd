"""Bytes from the autopilot → classified MAVLink frames. Never raises, whatever
the bytes: a frame with a wrong CRC, a bad length or junk between frames comes
out as ``bad``, a well-formed frame of a message id the dialect does not know
as ``unknown``, the rest as decoded messages.

Over UDP a datagram holds whole frames, so the bytes left over at the end of a
datagram (a truncated frame) are dropped and counted as bad rather than glued
to the next datagram, which would lose that datagram's good frames too.

Example::

    decoder = Decoder()
    for frame in decoder.feed(sock.recv(4096), datagram=True):
        if frame.kind is Kind.MESSAGE:
            print(frame.message.get_type())
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any

from .dialect import MAV, parser


class Kind(Enum):
    MESSAGE = "message"
    UNKNOWN = "unknown"
    BAD = "bad"


@dataclass(frozen=True)
class Frame:
    kind: Kind
    message: Any = None  # the pymavlink message (MESSAGE and UNKNOWN)
    reason: str = ""  # why a BAD frame is bad


class Decoder:
    def __init__(self, signing_key: bytes | None = None) -> None:
        self._mav = parser()
        if signing_key is not None:  # only signed MAVLink 2 (guard.require_signing)
            from .guard import require_signing

            require_signing(self._mav, signing_key)

    def _reset(self) -> None:
        self._mav.buf = bytearray()
        self._mav.buf_index = 0
        self._mav.expected_length = MAV.HEADER_LEN_V1 + 2

    def feed(self, data: bytes, datagram: bool = False) -> list[Frame]:
        """The frames completed by ``data``; with ``datagram``, ``data`` is one whole
        UDP datagram and a truncated frame at its end is reported as bad."""
        try:
            messages = self._mav.parse_buffer(data) or []
        except Exception as exc:  # robust parsing should not raise; never let it through
            self._reset()
            return [Frame(Kind.BAD, reason=f"parser error: {exc}")]
        frames = [self._classify(m) for m in messages]
        if datagram and self._mav.buf_len() > 0:
            frames.append(
                Frame(
                    Kind.BAD,
                    reason=f"truncated frame ({self._mav.buf_len()} bytes "
                    "at the end of a datagram)",
                )
            )
            self._reset()
        return frames

    @staticmethod
    def _classify(m: Any) -> Frame:
        kind = m.get_type()
        if kind == "BAD_DATA":
            return Frame(Kind.BAD, reason=str(getattr(m, "reason", "bad data")))
        if kind.startswith("UNKNOWN_"):
            return Frame(Kind.UNKNOWN, message=m)
        return Frame(Kind.MESSAGE, message=m)
