"""The autopilot as the bridge sees it: which system it is (its first HEARTBEAT),
whether it is alive (a HEARTBEAT within the timeout), whether it rebooted (its
``time_boot_ms`` went back), and the message rates asked of it.

Rates are asked with MAV_CMD_SET_MESSAGE_INTERVAL in a COMMAND_LONG, one
message at a time, because a COMMAND_ACK does not say which message it answers.
An unanswered request is sent again after ``ack_timeout_s`` (``confirmation``
counts the attempts) up to ``attempts`` times; a refusal is reported and not
retried. Everything is asked again when the autopilot reappears after being
lost, when it reboots, or when another system takes its place.

The class does no I/O: ``on_message`` takes decoded messages, ``poll`` returns
the messages to send, and reports go to ``log``. Time comes in as arguments.

Example::

    ap = Autopilot({"ATTITUDE": 200_000}, log=print)
    ap.on_message(heartbeat, now=time.monotonic())
    for msg in ap.poll(time.monotonic()):
        transport.write(msg.pack(packer))
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .dialect import MAV, message_id, result_name

REBOOT_JUMP_MS = 2000  # time_boot_ms going back by more than this means a reboot


@dataclass
class Request:
    message: str
    interval_us: int
    attempts: int = 0
    sent_at: float = 0.0


class Autopilot:
    def __init__(
        self,
        intervals_us: dict[str, int],
        log: Callable[[str], None],
        heartbeat_timeout_s: float = 3.0,
        target_system: int | None = None,
        ack_timeout_s: float = 1.0,
        attempts: int = 3,
        target_component: int | None = None,
    ) -> None:
        self.intervals_us = dict(intervals_us)
        self.log = log
        self.heartbeat_timeout_s = heartbeat_timeout_s
        self.ack_timeout_s = ack_timeout_s
        self.max_attempts = attempts
        self.system: int | None = target_system
        self._fixed = target_system is not None
        self.component: int | None = target_component
        self._fixed_component = target_component
        self.last_heartbeat: float | None = None
        self.lost = False
        self.accepted: dict[str, int] = {}  # message → interval the autopilot accepted
        self.refused: dict[str, str] = {}  # message → MAV_RESULT name
        self._queue: deque[Request] = deque()
        self._in_flight: Request | None = None
        self._boot_ms: int | None = None

    @property
    def known(self) -> bool:
        return self.last_heartbeat is not None

    def heartbeat_age(self, now: float) -> float | None:
        return None if self.last_heartbeat is None else now - self.last_heartbeat

    def is_mine(self, msg: Any) -> bool:
        """Whether a decoded message comes from the autopilot (after its first HEARTBEAT)."""
        return (
            self.known
            and msg.get_srcSystem() == self.system
            and msg.get_srcComponent() == self.component
        )

    def on_message(self, msg: Any, now: float) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            self._on_heartbeat(msg, now)
        elif not self.is_mine(msg):
            return
        elif kind == "COMMAND_ACK":
            self._on_ack(msg)
        boot_ms = getattr(msg, "time_boot_ms", None)
        if isinstance(boot_ms, int) and self.is_mine(msg):
            if self._boot_ms is not None and boot_ms + REBOOT_JUMP_MS < self._boot_ms:
                self.log(
                    f"autopilot {self.system} rebooted (time since boot went back from "
                    f"{self._boot_ms / 1000:.1f} s to {boot_ms / 1000:.1f} s): "
                    "asking for the message rates again"
                )
                self.ask_all()
            self._boot_ms = boot_ms

    def _on_heartbeat(self, msg: Any, now: float) -> None:
        if msg.autopilot == MAV.MAV_AUTOPILOT_INVALID or msg.type == MAV.MAV_TYPE_GCS:
            return  # a ground station or a companion computer, not an autopilot
        src, comp = msg.get_srcSystem(), msg.get_srcComponent()
        if self._fixed and src != self.system:
            return  # --target-system: only that one
        if self._fixed_component is not None and comp != self._fixed_component:
            return  # --target-component: only that one
        if self.known and src == self.system and comp != self.component and not self.lost:
            return  # another component claiming our system id
        if self.known and src != self.system:
            if not self.lost:
                return  # another vehicle on the same link while ours is alive
            self.log(f"autopilot {self.system} replaced by system {src}")
        if not self.known or src != self.system:
            version = 2 if msg.get_msgbuf()[0] == MAV.PROTOCOL_MARKER_V2 else 1
            self.log(
                f"autopilot found: system {src} component {comp} "
                f"(MAV_TYPE {msg.type}, MAV_AUTOPILOT {msg.autopilot}, "
                f"MAVLink {version})"
            )
            self.system, self.component = src, comp
            self._boot_ms = None
            self.ask_all()
        elif self.lost:
            self.log(
                f"autopilot {src} back after {now - (self.last_heartbeat or now):.1f} s "
                "of silence: asking for the message rates again"
            )
            self.ask_all()
        self.lost = False
        self.last_heartbeat = now

    def _on_ack(self, msg: Any) -> None:
        req = self._in_flight
        if req is None or msg.command != MAV.MAV_CMD_SET_MESSAGE_INTERVAL:
            return
        if msg.result in (MAV.MAV_RESULT_IN_PROGRESS, MAV.MAV_RESULT_TEMPORARILY_REJECTED):
            return  # still in flight: asked again after ack_timeout_s while attempts remain
        self._in_flight = None
        if msg.result == MAV.MAV_RESULT_ACCEPTED:
            self.accepted[req.message] = req.interval_us
            self.refused.pop(req.message, None)
            self.log(f"autopilot accepted {req.message} every {req.interval_us / 1e6:g} s")
        else:
            self.refused[req.message] = result_name(msg.result)
            self.log(
                f"autopilot REFUSED {req.message} every {req.interval_us / 1e6:g} s: "
                f"{result_name(msg.result)}"
            )

    def ask_all(self) -> None:
        self._queue = deque(Request(m, i) for m, i in sorted(self.intervals_us.items()))
        self._in_flight = None

    def check(self, now: float) -> None:
        """Reports the autopilot lost once when its HEARTBEAT is overdue."""
        age = self.heartbeat_age(now)
        if age is not None and not self.lost and age > self.heartbeat_timeout_s:
            self.lost = True
            self.log(f"autopilot {self.system} LOST: no HEARTBEAT for {age:.1f} s")

    def poll(self, now: float) -> list[Any]:
        """The COMMAND_LONG messages due now (at most one request in flight)."""
        self.check(now)
        if not self.known or self.lost:
            return []
        req = self._in_flight
        if req is not None and now - req.sent_at < self.ack_timeout_s:
            return []
        if req is not None and req.attempts >= self.max_attempts:
            self.log(
                f"autopilot never answered SET_MESSAGE_INTERVAL for {req.message} "
                f"({req.attempts} attempts)"
            )
            self.refused[req.message] = "NO_ANSWER"
            req = self._in_flight = None
        if req is None:
            if not self._queue:
                return []
            req = self._in_flight = self._queue.popleft()
        req.attempts += 1
        req.sent_at = now
        return [
            MAV.MAVLink_command_long_message(
                self.system,
                self.component or 0,
                MAV.MAV_CMD_SET_MESSAGE_INTERVAL,
                req.attempts - 1,
                message_id(req.message),
                req.interval_us,
                0,
                0,
                0,
                0,
                0,
            )
        ]
