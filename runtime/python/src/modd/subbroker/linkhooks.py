"""What a link session reports and to whom (``session.py``): the SubBroker's
hooks, the clocks it reads, its counters and its two failures.

>>> LinkStats().state
'connecting'
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Protocol

from modd.link.frames import AuthOk, Config, ConfigAck, Status
from modd.link.receiver import Window

from .backpressure import Backpressure


class LinkDown(ConnectionError):
    """The link is not up (or dropped while waiting)."""


class ConfigRejected(RuntimeError):
    """The PubBroker refused a CONFIG; ``status`` is its CONFIG_ACK status or ERROR code."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


@dataclass(frozen=True)
class Adopted:
    """The config the PubBroker runs, taken as acknowledged without sending it (another
    station sent it: handover.py)."""

    config: Config
    ack: ConfigAck
    slot: int = 0  # the last slot that station had: where the slot numbers are read


class LinkHandler(Protocol):
    """What the SubBroker does with link events (called on the link thread)."""

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | Adopted | None:
        """The CONFIG to send now, the running one adopted, or None to resume the one
        ``ok`` reports (this SubBroker's own)."""
        ...

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None: ...

    def on_windows(self, windows: list[Window]) -> None: ...

    def on_status(self, status: Status) -> None: ...


class Clock(Protocol):
    """The two clocks a session reads: monotonic seconds (timers) and wall
    nanoseconds (a window's lateness, ``last_data_ns``)."""

    def monotonic(self) -> float: ...

    def time_ns(self) -> int: ...


class SystemClock:
    def monotonic(self) -> float:
        return time.monotonic()

    def time_ns(self) -> int:
        return time.time_ns()


@dataclass
class LinkStats:
    """Counters of the link as the SubBroker sees it (frame bytes, not IP)."""

    state: str = "connecting"
    bytes_in: int = 0
    bytes_out: int = 0
    frames_in: int = 0
    data_frames: int = 0
    bad_frames: int = 0
    connects: int = 0
    rtt_s: float | None = None
    last_data_ns: int | None = None
    last_error: str | None = None
    pubbroker: dict[str, int] = field(default_factory=dict)
    sensors: dict[str, dict[str, int]] = field(default_factory=dict)  # instruments' health
    backpressure: Backpressure = field(default_factory=Backpressure)
