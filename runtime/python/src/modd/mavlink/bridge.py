"""The bridge's loop: bytes from the autopilot → decoded frames → samples handed
to the model's publishers; in between, the autopilot's HEARTBEAT, the message
rates asked of it, the bridge's own HEARTBEAT (1 Hz) and a periodic status line.

Sample timestamps are the receive time (``time.time_ns()`` when the bytes were
read), the same for every frame of one read. The autopilot's own clocks are not
used: ``time_boot_ms`` is not wall-clock time, and ``SYSTEM_TIME`` needs a GPS
fix and is itself sent late; the receive time is what the bridge actually knows,
late by the link's latency (milliseconds on loopback or a serial radio).

Only messages from the autopilot (the system and component of the first
HEARTBEAT, or ``target_system``/``target_component``) are mapped, and only after
that HEARTBEAT; at most twice the rate asked of each message (guard.RateBound,
the excess counted as ``limited``); with ``signing_key``, only signed MAVLink 2
(docs/security.md).

Example::

    bridge = Bridge(plan_bridge(model), open_transport("udpin:127.0.0.1:14550"),
                    {p.name: Publisher(p.name, ingress) for p in plan.publishers})
    bridge.run(stop_event)   # returns when stop_event is set, publishers flushed
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from .autopilot import Autopilot
from .decode import Decoder, Frame, Kind
from .dialect import MAV, parser
from .guard import RateBound
from .mapping import BridgePlan, Number
from .status import Counters, status_line
from .transport import Transport

HEARTBEAT_PERIOD_S = 1.0
BAD_LOGS_PER_STATUS = 5  # bad frames are logged one by one up to this many per status period


class Sink(Protocol):
    """What the bridge needs of a publisher (``modd.publisher.Publisher`` is one)."""

    def declare(self, topic: str, vtype: str) -> None: ...

    def publish(self, topic: str, timestamp_ns: int, value: Number) -> bool: ...

    def flush(self, timeout: float = 5.0) -> bool: ...

    def close(self, timeout: float = 2.0) -> None: ...


@dataclass(frozen=True)
class BridgeSettings:
    source_system: int = 255
    source_component: int = MAV.MAV_COMP_ID_ONBOARD_COMPUTER
    target_system: int | None = None  # None: the first autopilot heard
    target_component: int | None = None  # None: the first autopilot's
    signing_key: bytes | None = None  # 32 bytes: accept only signed MAVLink 2
    heartbeat_timeout_s: float = 3.0
    status_period_s: float = 10.0


class Bridge:
    def __init__(
        self,
        plan: BridgePlan,
        transport: Transport,
        sinks: Mapping[str, Sink],
        settings: BridgeSettings | None = None,
        log: Callable[[str], None] = print,
    ) -> None:
        self.plan = plan
        self.transport = transport
        self.sinks = dict(sinks)
        self.settings = settings or BridgeSettings()
        self.log = log
        self.counters = Counters()
        self.decoder = Decoder(self.settings.signing_key)
        self.autopilot = Autopilot(
            plan.intervals_us,
            log,
            self.settings.heartbeat_timeout_s,
            self.settings.target_system,
            target_component=self.settings.target_component,
        )
        self.rate = RateBound(plan.intervals_us)
        self._packer = parser(self.settings.source_system, self.settings.source_component)
        self._unknown_ids: set[str] = set()
        self._next_heartbeat = 0.0
        self._next_status: float | None = None
        self._bad_logged = 0  # bad frames logged since the last status line
        #: work for the bridge's own thread (a deployed model's replan), run between reads
        self.pending: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        for pub in plan.publishers:
            for m in pub.mappings:
                self.sinks[pub.name].declare(m.topic, m.type)

    # -- the decode path: never raises on any bytes ------------------------------------------

    def handle(self, data: bytes, now: float | None = None, now_ns: int | None = None) -> None:
        """Everything that follows from one read of ``data`` received at ``now_ns``."""
        now = time.monotonic() if now is None else now
        now_ns = time.time_ns() if now_ns is None else now_ns
        for frame in self.decoder.feed(data, datagram=self.transport.datagram):
            self._on_frame(frame, now, now_ns)

    def _on_frame(self, frame: Frame, now: float, now_ns: int) -> None:
        c = self.counters
        if frame.kind is Kind.BAD:
            c.bad += 1
            c.last_bad = frame.reason[:120]
            self._bad_logged += 1
            if self._bad_logged <= BAD_LOGS_PER_STATUS:
                more = (
                    " (no more until the next status line)"
                    if self._bad_logged == BAD_LOGS_PER_STATUS
                    else ""
                )
                self.log(f"bad MAVLink data: {c.last_bad} ({c.bad} bad in all){more}")
            return
        if frame.kind is Kind.UNKNOWN:
            c.unknown += 1
            kind = frame.message.get_type()
            if kind not in self._unknown_ids:
                self._unknown_ids.add(kind)
                self.log(f"ignoring unknown MAVLink message id {kind[8:]} (counted as unknown)")
            return
        msg = frame.message
        self.autopilot.on_message(msg, now)
        targets = self.plan.by_message.get(msg.get_type())
        if not targets or not self.autopilot.is_mine(msg):
            c.ignored += 1
            return
        if not self.rate.allow(msg.get_type(), now):
            c.limited += 1
            return
        c.mapped += 1
        for publisher, m in targets:
            value = m.convert(getattr(msg, m.field, None))
            if value is None:
                c.unconvertible += 1
            elif self.sinks[publisher].publish(m.topic, now_ns, value):
                c.samples += 1
            else:
                c.dropped += 1

    # -- housekeeping ------------------------------------------------------------------------

    def _send(self, msg: Any) -> None:
        self.transport.write(bytes(msg.pack(self._packer)))
        self._packer.seq = (self._packer.seq + 1) % 256

    def tick(self, now: float) -> None:
        """Sends what is due (own HEARTBEAT, rate requests) and the status line."""
        if now >= self._next_heartbeat:
            self._next_heartbeat = now + HEARTBEAT_PERIOD_S
            self._send(
                MAV.MAVLink_heartbeat_message(
                    MAV.MAV_TYPE_ONBOARD_CONTROLLER,
                    MAV.MAV_AUTOPILOT_INVALID,
                    0,
                    0,
                    MAV.MAV_STATE_ACTIVE,
                    3,
                )
            )
        for msg in self.autopilot.poll(now):
            self._send(msg)
        if self._next_status is None:
            self._next_status = now + self.settings.status_period_s
        elif now >= self._next_status:
            self._next_status = now + self.settings.status_period_s
            self.log(self.status())
            self._bad_logged = 0

    def status(self, now: float | None = None) -> str:
        ap = self.autopilot
        age = ap.heartbeat_age(time.monotonic() if now is None else now)
        return status_line(self.counters, age, ap.lost, ap.system)

    def run(self, stop: threading.Event, tick_s: float = 0.1) -> None:
        """Reads and maps until ``stop`` is set, then flushes and closes the publishers."""
        rates = ", ".join(
            f"{m} every {i / 1e6:g} s" for m, i in sorted(self.plan.intervals_us.items())
        )
        self.log(f"will ask for {rates or 'no messages'}")
        try:
            next_tick = 0.0
            while not stop.is_set():
                while not self.pending.empty():
                    self.pending.get()()
                now = time.monotonic()
                if now >= next_tick:
                    self.tick(now)
                    next_tick = now + tick_s
                if self.transport.wait(max(0.0, min(tick_s, next_tick - now))):
                    data = self.transport.recv()
                    if data:
                        self.handle(data)
        finally:
            for sink in self.sinks.values():
                sink.flush(2.0)
                sink.close()
            self.transport.close()
            self.log(self.status())
