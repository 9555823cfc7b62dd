"""A simulated autopilot speaking MAVLink 2 over UDP: the drone of ``track.py``
as a flight controller would report it.

It sends HEARTBEAT at 1 Hz and streams GLOBAL_POSITION_INT, ATTITUDE,
SYS_STATUS, VFR_HUD, GPS_RAW_INT and SYSTEM_TIME, each every
``DEFAULT_INTERVAL_S`` until someone asks otherwise. It answers
MAV_CMD_SET_MESSAGE_INTERVAL (COMMAND_LONG) with a COMMAND_ACK — ACCEPTED for a
message it streams (then streams it at the interval asked; -1 stops it, 0
restores the default), DENIED for one it does not — and any other command
with UNSUPPORTED. Units are MAVLink's: lat/lon in degE7, alt in mm, speeds in
cm/s, headings in cdeg, attitude in radians.

Example::

    ap = SimAutopilot("udpout:127.0.0.1:14550", start=time.time())
    ap.run(stop_event)
    ap.asked      # [("GLOBAL_POSITION_INT", 200000, "MAV_RESULT_ACCEPTED"), ...]
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from ..mavlink.decode import Decoder, Kind
from ..mavlink.dialect import MAV, message_class, parser, result_name
from ..mavlink.transport import open_transport
from .track import altitude, battery, survey_pose, waves

DEFAULT_INTERVAL_S = 1.0
HEARTBEAT_INTERVAL_S = 1.0
MIN_INTERVAL_S = 0.005
SENSORS = 1 | 2 | 4 | 32  # MAV_SYS_STATUS_SENSOR 3D gyro, accel, mag and GPS


def _cdeg(yaw: float) -> int:
    return round(math.degrees(yaw) * 100) % 36000


def messages_at(t: float, boot_ms: int, now_us: int) -> dict[str, tuple[Any, ...]]:
    """Each streamed message's fields, in pymavlink's constructor order, at t
    seconds into the track."""
    p = survey_pose(t)
    lat, lon, alt_mm = round(p.lat * 1e7), round(p.lon * 1e7), round(altitude(t) * 1000)
    north, east = p.velocity
    roll, pitch = waves(t)
    volts, amps, left = battery(t)
    return {
        "GLOBAL_POSITION_INT": (
            boot_ms,
            lat,
            lon,
            alt_mm,
            alt_mm,
            round(north * 100),
            round(east * 100),
            0,
            _cdeg(p.yaw),
        ),
        "ATTITUDE": (boot_ms, roll, pitch, p.yaw, 0.0, 0.0, 0.0),
        "SYS_STATUS": (
            SENSORS,
            SENSORS,
            SENSORS,
            250,
            round(volts * 1000),
            round(amps * 100),
            left,
            0,
            0,
            0,
            0,
            0,
            0,
        ),
        "VFR_HUD": (
            0.0,
            math.hypot(north, east),
            round(math.degrees(p.yaw)) % 360,
            40,
            altitude(t),
            0.0,
        ),
        "GPS_RAW_INT": (
            now_us,
            3,
            lat,
            lon,
            alt_mm,
            90,
            150,
            round(math.hypot(north, east) * 100),
            _cdeg(p.yaw),
            14,
        ),
        "SYSTEM_TIME": (now_us, boot_ms),
    }


class SimAutopilot:
    def __init__(
        self,
        url: str,
        start: float,
        system: int = 1,
        component: int = 1,
        log: Callable[[str], None] = print,
    ) -> None:
        self.start = start
        self.log = log
        self.transport = open_transport(url, system, component)
        self.decoder = Decoder()
        self.packer = parser(system, component)
        self.system = system
        self.intervals: dict[str, float] = {m: DEFAULT_INTERVAL_S for m in messages_at(0.0, 0, 0)}
        self.asked: list[tuple[str, int, str]] = []  # (message, interval µs, MAV_RESULT name)
        self._boot = time.monotonic()
        self._due: dict[str, float] = {}

    def _send(self, msg: Any) -> None:
        self.transport.write(bytes(msg.pack(self.packer)))
        self.packer.seq = (self.packer.seq + 1) % 256

    def _send_due(self, now: float) -> None:
        due = [
            m
            for m, interval in self.intervals.items()
            if interval > 0 and now >= self._due.get(m, 0.0)
        ]
        if now >= self._due.get("HEARTBEAT", 0.0):
            self._due["HEARTBEAT"] = now + HEARTBEAT_INTERVAL_S
            self._send(
                MAV.MAVLink_heartbeat_message(
                    MAV.MAV_TYPE_SURFACE_BOAT,
                    MAV.MAV_AUTOPILOT_ARDUPILOTMEGA,
                    MAV.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | MAV.MAV_MODE_FLAG_SAFETY_ARMED,
                    10,
                    MAV.MAV_STATE_ACTIVE,
                    3,
                )
            )
        if not due:
            return
        now_us = time.time_ns() // 1000
        fields = messages_at(
            now_us / 1e6 - self.start, int((now - self._boot) * 1000) % 2**32, now_us
        )
        for m in due:
            last = self._due.get(m, now)
            # keep the cadence (no drift) unless we fell more than one interval behind
            self._due[m] = max(last + self.intervals[m], now)
            cls = message_class(m)
            assert cls is not None, m  # every streamed message is in the dialect
            self._send(cls(*fields[m]))

    def _on_command(self, msg: Any) -> None:
        if msg.target_system not in (0, self.system):
            return
        if msg.command != MAV.MAV_CMD_SET_MESSAGE_INTERVAL:
            result = MAV.MAV_RESULT_UNSUPPORTED
        else:
            result = self._set_interval(int(msg.param1), msg.param2)
        self._send(
            MAV.MAVLink_command_ack_message(
                msg.command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
            )
        )

    def _set_interval(self, msgid: int, interval_us: float) -> int:
        cls = MAV.mavlink_map.get(msgid)
        name = cls.msgname if cls is not None else f"message id {msgid}"
        if name not in self.intervals:
            result = MAV.MAV_RESULT_DENIED
        else:
            result = MAV.MAV_RESULT_ACCEPTED
            if interval_us < 0:
                self.intervals[name] = 0.0
            elif interval_us == 0:
                self.intervals[name] = DEFAULT_INTERVAL_S
            else:
                self.intervals[name] = max(MIN_INTERVAL_S, interval_us / 1e6)
            self._due.pop(name, None)
        self.asked.append((name, int(interval_us), result_name(result)))
        self.log(
            f"autopilot: SET_MESSAGE_INTERVAL {name} {int(interval_us)} us: {result_name(result)}"
        )
        return int(result)

    def handle(self, data: bytes) -> None:
        for frame in self.decoder.feed(data, datagram=self.transport.datagram):
            if frame.kind is Kind.MESSAGE and frame.message.get_type() == "COMMAND_LONG":
                self._on_command(frame.message)

    def run(self, stop: threading.Event) -> None:
        self.log(f"autopilot: system {self.system}, MAVLink 2 to {self.transport_url()}")
        try:
            while not stop.is_set():
                now = time.monotonic()
                self._send_due(now)
                nxt = min(
                    [self._due["HEARTBEAT"]]
                    + [self._due.get(m, now) for m, i in self.intervals.items() if i > 0]
                )
                if self.transport.wait(max(0.0, min(0.1, nxt - time.monotonic()))):
                    data = self.transport.recv()
                    if data:
                        self.handle(data)
        finally:
            self.transport.close()

    def transport_url(self) -> str:
        return str(getattr(self.transport, "url", "?"))
