"""Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.

Wire enumerations, counts and limits (modd_contracts/wire.json).
"""

from __future__ import annotations

from enum import IntEnum
from typing import Final

# -- link: The link protocol's frames (docs/protocol.md).
#: Protocol version of HELLO and CHALLENGE.
VERSION: Final = 1
#: Largest frame, in bytes after the length prefix.
MAX_FRAME: Final = 1048576
#: Largest accepted delay a CONFIG may carry (one hour, as the PubBroker's link.delay_ms).
MAX_ACCEPTED_DELAY_MS: Final = 3600000
#: Largest PING or PONG payload, in bytes.
MAX_PING: Final = 64
#: Most instruments in one STATUS or HEALTH (docs/protocol.md, STATUS).
MAX_HEALTH_SENSORS: Final = 64
#: Most counters of one instrument's health.
MAX_HEALTH_FIELDS: Final = 32
#: Longest instrument name in a health report, in bytes.
MAX_HEALTH_NAME: Final = 64
#: Largest health field or STATUS counter forwarded: 2^53 - 1, exact in a double (a larger one
#: is clamped by the PubBroker, left out by the SubBroker).
MAX_HEALTH_COUNT: Final = 9007199254740991
#: Latest last_value_ms of an instrument's health: 2100-01-01T00:00Z in Unix ms (a later one
#: reads as 0, none).
MAX_LAST_VALUE_MS: Final = 4102444800000
#: Longest STATUS period a CONFIG may ask for, in seconds: one day (0: no STATUS).
MAX_STATUS_PERIOD_S: Final = 86400
#: The STATUS period the SubBroker asks for in CONFIG unless configured
#: (link.pubbroker_status_period_s), and the planner counts.
DEFAULT_STATUS_PERIOD_S: Final = 60
#: Most topics, or streams, of one CONFIG.
MAX_LIST: Final = 65535
#: Longest topic name, in bytes.
MAX_NAME: Final = 255
#: Largest buffer size of a CONFIG topic (the smallest is 1).
MAX_BUFFER_SIZE: Final = 1000000
#: Longest stream period of a CONFIG or a backfill request, in microseconds: 366 days (the
#: smallest is 1).
MAX_PERIOD_US: Final = 31622400000000
#: Largest on-board model (ONBOARD) or answer (ONBOARD_ACK), in bytes once decompressed.
MAX_ONBOARD_BYTES: Final = 262144
#: Largest compressed on-board model an ONBOARD frame carries: 16 control fragments of a 240-B
#: packet.
MAX_ONBOARD_WIRE: Final = 3584
#: How long the PubBroker waits for the on-board processes' answers before ONBOARD_ACK.
ONBOARD_WAIT_MS: Final = 2000
#: Shortest pre-shared key, in bytes: shorter keys are refused.
MIN_KEY_BYTES: Final = 16


class StatusField(IntEnum):
    """The PubBroker's counters in the order STATUS carries them (docs/protocol.md, STATUS);
    fields are only ever appended. The labels (lower case) name them in logs, the run record
    and the SubBroker's status."""

    UPTIME_S = 0
    SAMPLES_IN = 1
    SAMPLES_ARCHIVED = 2
    REJECTED_UNKNOWN_TOPIC = 3
    REJECTED_WRONG_TYPE = 4
    REJECTED_NOT_FINITE = 5
    REJECTED_TIMESTAMP = 6
    REJECTED_OVERFLOW = 7
    REJECTED_MALFORMED = 8
    ARCHIVE_FAILED = 9
    INGRESS_MALFORMED_FRAMES = 10
    PUBLISHERS_CONNECTED = 11
    FRAMES_SENT = 12
    FRAMES_DROPPED = 13
    LINK_BYTES_SENT = 14
    DISK_FREE_MB = 15
    BUFFER_FILL_PCT = 16
    ARCHIVE_FILES = 17
    AUTH_FAILURES = 18
    CONFIG_ID = 19
    REJECTED_QUOTA = 20
    ARCHIVE_STATE = 21
    ARCHIVE_RATE_BPS = 22
    SAMPLES_PENDING = 23
    LINK_DATAGRAMS_SENT = 24
    LINK_DATAGRAMS_RESENT = 25
    LINK_NACKS = 26
    LINK_SLOTS_DROPPED = 27
    LINK_FORGED = 28
    LINK_REPLAYED = 29
    INSTRUMENTS = 30
    INSTRUMENTS_OPEN = 31
    INSTRUMENTS_SILENT = 32
    INSTRUMENTS_CLOSED = 33
    INSTRUMENTS_UNLISTED = 34
    HEALTH_CORRECTED = 35
    STATUS_COALESCED = 36

    @property
    def label(self) -> str:
        """The member's name in logs and status documents (``"uptime_s"``)."""
        return self.name.lower()


class MsgType(IntEnum):
    """The type byte of a frame."""

    HELLO = 0x01
    CHALLENGE = 0x02
    AUTH = 0x03
    AUTH_OK = 0x04
    PING = 0x05
    PONG = 0x06
    CONFIG = 0x07
    CONFIG_ACK = 0x08
    ONBOARD = 0x0B  # config id, the on-board model (zstd): for modd-sensors and modd-mavlink
    ONBOARD_ACK = 0x0C  # config id, status, what each on-board process did (zstd JSON)
    DATA = 0x10  # seq8, values (all streams present)
    DATA_BITMAP = 0x11  # seq8, presence bitmap, values
    DATA_SYNC = 0x12  # config id, full slot number, values
    DATA_SYNC_BITMAP = 0x13  # config id, full slot number, presence bitmap, values
    STATUS = 0x20
    ERROR = 0x7F


class ValueType(IntEnum):
    """A topic's value type: the metamodel's ValueType enum, coded in its order."""

    FLOAT32 = 0
    FLOAT64 = 1
    INT = 2
    BOOL = 3

    @classmethod
    def parse(cls, label: str) -> ValueType:
        """The member of a metamodel label (``"float32"``); KeyError if none."""
        return cls({"float32": 0, "float64": 1, "int": 2, "bool": 3}[label])

    @property
    def label(self) -> str:
        """The metamodel label of the member."""
        return ("float32", "float64", "int", "bool")[self]


# -- error codes: The code of an ERROR frame, and of the C++ runtime's one error type.


class ErrorCode(IntEnum):
    """Why a frame or a session was refused."""

    BAD_FRAME = 1  # malformed bytes (truncated, overlong varint, bad type code)
    VERSION = 2  # unsupported protocol version
    AUTH_FAILED = 3  # HMAC proof did not verify
    NOT_AUTHENTICATED = 4  # message other than the handshake before authentication
    BAD_CONFIG = 5  # CONFIG (or config file) inconsistent
    BUSY = 6  # a CONFIG is already waiting for its switch date
    TIMEOUT = 8  # handshake or peer timeout
    INTERNAL = 9  # system call failure and the like
    IO = 10  # file or socket error


# -- varints: The LEB128 varints of both protocols: unsigned 64-bit values.
#: Longest varint, in bytes (7 bits each; the tenth holds bit 63 alone).
MAX_VARINT_BYTES: Final = 10


# -- backfill: Backfill frames of the link (docs/protocol.md, "Backfill").
#: Most windows of one request.
MAX_WINDOWS: Final = 4294967295
#: Most windows of one BACKFILL_DATA frame.
MAX_BATCH: Final = 65535


class BackfillType(IntEnum):
    """The type byte of a backfill frame."""

    REQUEST = 0x50
    DATA = 0x51
    PROGRESS = 0x52
    END = 0x53
    CANCEL = 0x54


class EndStatus(IntEnum):
    """How a backfill ended (BACKFILL_END)."""

    DONE = 0  # every window from the resume point to the end was sent
    CANCELLED = 1  # a BACKFILL_CANCEL (or a newer request with the same id) stopped it
    UNKNOWN_TOPIC = 2  # the broker has no such topic in its archive
    BAD_REQUEST = 3  # type differs from the archive's, or the range is out of bounds
    BUSY = 4  # too many backfills at once: ask again later
    IO = 5  # the archive could not be read


# -- events: Event subscriptions, ON_CHANGE and THRESHOLD (docs/planning.md, "Event
# -- subscriptions"): their codes and bounds; the definition is modd_contracts.events, its
# -- vectors contracts/vectors/events.json.
#: Most events one window of an event subscription carries (its declared or derived 'at most
#: N'): the link's list bound.
MAX_EVENTS: Final = 65535


class EventKind(IntEnum):
    """What makes an event."""

    ON_CHANGE = 0  # the sample differs from the last reported one by more than the deadband
    THRESHOLD = 1  # the sample crosses the level by more than the hysteresis


class DeadbandMode(IntEnum):
    """How an ON_CHANGE deadband is read."""

    ABSOLUTE = 0  # in the topic's unit: |x - last| > deadband
    RELATIVE = 1  # a fraction of the last reported value: |x - last| > deadband * |last|


class Crossing(IntEnum):
    """Which crossings of a THRESHOLD are events (a bit set)."""

    UP = 1  # below to above: x > level + hysteresis
    DOWN = 2  # above to below: x < level - hysteresis
    BOTH = 3  # either


# -- datagrams: Datagram form of the link (docs/protocol.md, "Datagram transports").
#: DATA datagram of consecutive slots.
DGRAM_DATA: Final = 0x30
#: DATA datagram with a presence bitmap.
DGRAM_DATA_BITMAP: Final = 0x31
#: A piece of a slot too large for one datagram.
DGRAM_FRAGMENT: Final = 0x32
#: Control datagram: one tagged link frame.
DGRAM_CONTROL: Final = 0x40
#: Handshake datagram (untagged).
DGRAM_HANDSHAKE: Final = 0x41
#: A piece of a control frame too large for one datagram.
DGRAM_CONTROL_FRAGMENT: Final = 0x42
#: Control frame type: ranges of slots to resend.
NACK: Final = 0x09
#: Most ranges of one NACK (the fewest is 1).
MAX_NACK_RANGES: Final = 32
#: Most slots of one NACK range (the fewest is 1).
MAX_NACK_RANGE_SLOTS: Final = 65535
#: Most slots of one DATA datagram (its slot count is one byte).
MAX_DATAGRAM_SLOTS: Final = 255
#: Most fragments of one slot.
MAX_FRAGMENTS: Final = 16
#: Bytes before a fragment's piece: type, config id, slot16, fragment byte.
FRAGMENT_HEAD: Final = 5
#: Truncated HMAC tag of a DATA datagram, in bytes.
TAG_BYTES: Final = 4
#: Truncated HMAC tag of a control datagram, in bytes.
CONTROL_TAG_BYTES: Final = 8
#: Smallest packet a radio may carry (link.maxPacket), in bytes.
MIN_PACKET: Final = 32
#: Largest packet (link.maxPacket): the largest UDP payload, in bytes.
MAX_PACKET: Final = 65507
#: The packet of a udp link when the model gives none: Ethernet's MTU less the IP and UDP
#: headers.
DEFAULT_UDP_PACKET: Final = 1472
#: The packet of a serial link when the model gives none (a SiK radio's frame).
DEFAULT_SERIAL_PACKET: Final = 252


__all__ = [
    "VERSION",
    "MAX_FRAME",
    "MAX_ACCEPTED_DELAY_MS",
    "MAX_PING",
    "MAX_HEALTH_SENSORS",
    "MAX_HEALTH_FIELDS",
    "MAX_HEALTH_NAME",
    "MAX_HEALTH_COUNT",
    "MAX_LAST_VALUE_MS",
    "MAX_STATUS_PERIOD_S",
    "DEFAULT_STATUS_PERIOD_S",
    "MAX_LIST",
    "MAX_NAME",
    "MAX_BUFFER_SIZE",
    "MAX_PERIOD_US",
    "MAX_ONBOARD_BYTES",
    "MAX_ONBOARD_WIRE",
    "ONBOARD_WAIT_MS",
    "MIN_KEY_BYTES",
    "StatusField",
    "MsgType",
    "ValueType",
    "ErrorCode",
    "MAX_VARINT_BYTES",
    "MAX_WINDOWS",
    "MAX_BATCH",
    "BackfillType",
    "EndStatus",
    "MAX_EVENTS",
    "EventKind",
    "DeadbandMode",
    "Crossing",
    "DGRAM_DATA",
    "DGRAM_DATA_BITMAP",
    "DGRAM_FRAGMENT",
    "DGRAM_CONTROL",
    "DGRAM_HANDSHAKE",
    "DGRAM_CONTROL_FRAGMENT",
    "NACK",
    "MAX_NACK_RANGES",
    "MAX_NACK_RANGE_SLOTS",
    "MAX_DATAGRAM_SLOTS",
    "MAX_FRAGMENTS",
    "FRAGMENT_HEAD",
    "TAG_BYTES",
    "CONTROL_TAG_BYTES",
    "MIN_PACKET",
    "MAX_PACKET",
    "DEFAULT_UDP_PACKET",
    "DEFAULT_SERIAL_PACKET",
]
