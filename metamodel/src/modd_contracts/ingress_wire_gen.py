"""Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.

Wire enumerations, counts and limits (modd_contracts/wire.json).
"""

from __future__ import annotations

from enum import IntEnum
from typing import Final

# -- ingress: The PubBroker's ingress protocol (docs/ingress.md).
#: Protocol version; 2 adds the broker's answers (CATALOGUE, ACK, REJECT).
VERSION: Final = 2
#: Oldest version a broker accepts (a version-1 publisher gets no answers).
MIN_VERSION: Final = 1
#: Largest frame, in bytes after the length prefix.
MAX_FRAME: Final = 1048576
#: Largest local topic id of a publisher.
MAX_LOCAL_ID: Final = 65535
#: Longest topic, publisher or drone name and REJECT detail, in bytes.
MAX_NAME: Final = 255


class MsgType(IntEnum):
    """The type byte of a frame: publisher -> broker below 0x80, broker -> publisher (version
    2) above."""

    HELLO = 0x01
    REGISTER = 0x02
    SAMPLES = 0x03
    HEALTH = 0x04
    CATALOGUE = 0x81
    ACK = 0x82
    REJECT = 0x83


class RejectReason(IntEnum):
    """Why the broker refused a record: the reason code of REJECT, and the index of the
    PubBroker's rejected_* counters (labels: their log names)."""

    UNKNOWN_TOPIC = 0  # unknown topic
    WRONG_TYPE = 1  # wrong type
    NOT_FINITE = 2  # value not finite
    TIMESTAMP = 3  # timestamp out of bounds
    OVERFLOW = 4  # archive queue full
    MALFORMED = 5  # malformed
    QUOTA = 6  # over its fair share of the archive queue

    @property
    def label(self) -> str:
        """The member's name in logs and status documents (``"uptime_s"``)."""
        return self.name.lower()


__all__ = [
    "VERSION",
    "MIN_VERSION",
    "MAX_FRAME",
    "MAX_LOCAL_ID",
    "MAX_NAME",
    "MsgType",
    "RejectReason",
]
