"""The bridge against a hand-driven autopilot on a raw UDP socket: junk bytes,
frames with a wrong CRC, unknown message ids, a refused rate, another vehicle
on the link, a reboot and a silent autopilot — counted, reported, and the
bridge keeps mapping."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
from mavlink_harness import (
    HERE,
    Autopilot,
    Recorder,
    corrupt_crc,
    load_model,
    unknown_frame,
)
from modd.mavlink.bridge import Bridge, BridgeSettings
from modd.mavlink.decode import Decoder, Kind
from modd.mavlink.dialect import MAV
from modd.mavlink.mapping import plan_bridge
from modd.mavlink.transport import open_transport
from modd.ports import free_port

TIMEOUT_S = 0.6  # the bridge's heartbeat timeout here


def wait_until(what: Callable[[], bool], timeout: float, why: Callable[[], str]) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if what():
            return
        time.sleep(0.02)
    raise AssertionError(why())


@dataclass
class Rig:
    bridge: Bridge
    sinks: dict[str, Recorder]
    sock: socket.socket
    port: int
    logs: list[str]
    commands: list[Any] = field(default_factory=list)  # COMMAND_LONGs the bridge sent

    def send(self, data: bytes) -> None:
        self.sock.sendto(data, ("127.0.0.1", self.port))

    def receive(self, seconds: float) -> None:
        """Collects what the bridge sends us for a while."""
        decoder = Decoder()
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.sock.settimeout(max(0.001, deadline - time.monotonic()))
            try:
                data = self.sock.recv(4096)
            except TimeoutError:
                break
            for f in decoder.feed(data, datagram=True):
                if f.kind is Kind.MESSAGE and f.message.get_type() == "COMMAND_LONG":
                    self.commands.append(f.message)

    def samples(self, topic: str) -> list[Any]:
        return [v for s in self.sinks.values() for t, _, v in s.samples if t == topic]

    def log_text(self) -> str:
        return "\n".join(self.logs)


@pytest.fixture
def rig() -> Iterator[Rig]:
    model = load_model(HERE / "boat.modd", free_port())
    plan = plan_bridge(model)
    port = free_port("udp")
    sinks = {p.name: Recorder() for p in plan.publishers}
    logs: list[str] = []
    bridge = Bridge(
        plan,
        open_transport(f"udpin:127.0.0.1:{port}"),
        sinks,
        BridgeSettings(heartbeat_timeout_s=TIMEOUT_S, status_period_s=0.5),
        logs.append,
    )
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop,))
    thread.start()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    try:
        yield Rig(bridge, sinks, sock, port, logs)
    finally:
        stop.set()
        thread.join(10)
        sock.close()
    assert not thread.is_alive()
    assert all(s.flushed and s.closed for s in sinks.values())


def _answer_rates(rig: Rig, refuse: str, per_round: list[int] | None = None) -> dict[int, float]:
    """Acknowledges each SET_MESSAGE_INTERVAL as it comes (refusing one message), with a
    HEARTBEAT every 0.3 s; returns message id → interval asked. ``per_round`` gets the
    number of requests received in each 0.3 s round."""
    asked: dict[int, float] = {}
    deadline = time.monotonic() + 10
    while len(asked) < 4 and time.monotonic() < deadline:
        rig.send(Autopilot().heartbeat())
        rig.receive(0.3)
        if per_round is not None and rig.commands:
            per_round.append(len(rig.commands))
        for cmd in rig.commands:
            if cmd.command == MAV.MAV_CMD_SET_MESSAGE_INTERVAL and int(cmd.param1) not in asked:
                asked[int(cmd.param1)] = cmd.param2
                name = MAV.mavlink_map[int(cmd.param1)].msgname
                result = MAV.MAV_RESULT_DENIED if name == refuse else MAV.MAV_RESULT_ACCEPTED
                rig.send(Autopilot().ack(cmd.command, result))
        rig.commands.clear()
    return asked


def test_rates_are_asked_one_by_one_and_refusals_reported(rig: Rig) -> None:
    rig.send(Autopilot().heartbeat())
    per_round: list[int] = []
    asked = _answer_rates(rig, refuse="SYS_STATUS", per_round=per_round)
    assert per_round == [1, 1, 1, 1]  # the next request only after the last one's ACK
    assert asked == {
        MAV.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 100_000,
        MAV.MAVLINK_MSG_ID_ATTITUDE: 100_000,
        MAV.MAVLINK_MSG_ID_SYS_STATUS: 500_000,
        MAV.MAVLINK_MSG_ID_WIND: 500_000,
    }, rig.log_text()
    wait_until(
        lambda: "REFUSED SYS_STATUS" in rig.log_text() and len(rig.bridge.autopilot.accepted) == 3,
        3,
        rig.log_text,
    )
    assert rig.bridge.autopilot.refused == {"SYS_STATUS": "MAV_RESULT_DENIED"}
    assert set(rig.bridge.autopilot.accepted) == {"GLOBAL_POSITION_INT", "ATTITUDE", "WIND"}


def test_junk_bad_crc_and_unknown_messages_are_counted_and_mapping_goes_on(rig: Rig) -> None:
    ap = Autopilot()
    rig.send(ap.position(477_000_000, -33_500_000, 1500))  # before any HEARTBEAT: not mapped
    rig.send(ap.heartbeat())
    wait_until(lambda: rig.bridge.autopilot.known, 3, rig.log_text)
    rig.send(ap.attitude(1.25))
    rig.send(b"\x00\x01 junk bytes \x7f")  # junk: one bad run of bytes
    rig.send(corrupt_crc(ap.attitude(0.5)))  # wrong CRC
    rig.send(unknown_frame())  # an id no dialect defines
    rig.send(b"garbage" + ap.attitude(-0.75))  # junk, then a good frame in the same datagram
    rig.send(ap.position(477_000_000, -33_500_000, 1500)[:15])  # cut short
    rig.send(Autopilot(system=42).attitude(3.0))  # another vehicle: ignored
    rig.send(ap.position(477_123_456, -33_500_000, 1500))
    wait_until(lambda: len(rig.samples("boat.autopilot.latitude")) == 1, 3, rig.log_text)
    c = rig.bridge.counters
    assert rig.samples("boat.autopilot.yaw") == pytest.approx([1.25, -0.75])
    assert rig.samples("boat.autopilot.latitude") == pytest.approx([47.7123456], abs=1e-12)
    assert rig.samples("boat.autopilot.height") == pytest.approx([11.5])  # 1500 mm + 10 m
    assert (c.bad, c.unknown, c.mapped) == (4, 1, 3)
    assert c.ignored >= 2  # the early GLOBAL_POSITION_INT, the other vehicle's ATTITUDE
    wait_until(
        lambda: "status: mapped 3 (samples 5), unknown 1, bad 4" in rig.log_text(), 3, rig.log_text
    )
    log = rig.log_text()
    assert "ignoring unknown MAVLink message id 61680" in log
    assert "invalid MAVLink CRC" in log and "truncated frame" in log


def test_a_silent_autopilot_is_reported_lost_once_then_back(rig: Rig) -> None:
    ap = Autopilot()
    rig.send(ap.heartbeat())
    _answer_rates(rig, refuse="")
    rig.send(ap.heartbeat())  # the last one
    t_quiet = time.monotonic()
    wait_until(lambda: "LOST" in rig.log_text(), 3 * TIMEOUT_S + 1, rig.log_text)
    assert time.monotonic() - t_quiet >= TIMEOUT_S - 0.1
    time.sleep(3 * TIMEOUT_S)  # still silent: reported once, and the bridge runs on
    assert rig.log_text().count("LOST:") == 1
    assert "LOST" in rig.bridge.status()
    rig.commands.clear()
    rig.send(ap.heartbeat())
    wait_until(lambda: "back after" in rig.log_text(), 3, rig.log_text)
    again = _answer_rates(rig, refuse="")  # the rates are asked again
    assert len(again) == 4
    rig.send(ap.attitude(0.1))
    wait_until(lambda: rig.samples("boat.autopilot.yaw") == pytest.approx([0.1]), 3, rig.log_text)


def test_a_reboot_asks_for_the_rates_again(rig: Rig) -> None:
    ap = Autopilot()
    rig.send(ap.heartbeat())
    _answer_rates(rig, refuse="")
    rig.send(ap.attitude(0.2, boot_ms=600_000))
    rig.send(ap.attitude(0.3, boot_ms=400))  # time since boot went back: it rebooted
    wait_until(lambda: "rebooted" in rig.log_text(), 3, rig.log_text)
    assert len(_answer_rates(rig, refuse="")) == 4
