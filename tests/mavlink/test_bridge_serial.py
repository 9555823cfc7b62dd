"""The bridge on a serial device, as on a drone (`--connect /dev/ttyAMA0,921600`):
a pseudo-terminal stands in for the UART, the test drives the autopilot's end.
A byte stream, unlike UDP datagrams: frames arrive split and glued together."""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from collections.abc import Iterator

import pytest
from mavlink_harness import HERE, Autopilot, Recorder, load_model
from modd.mavlink.bridge import Bridge, BridgeSettings
from modd.mavlink.decode import Decoder, Kind
from modd.mavlink.dialect import MAV
from modd.mavlink.mapping import plan_bridge
from modd.mavlink.transport import open_transport
from modd.ports import free_port


@pytest.fixture
def uart() -> Iterator[tuple[int, str]]:
    """(the autopilot's end, the device path the bridge opens)."""
    master, slave = os.openpty()
    tty.setraw(master)
    path = os.ttyname(slave)
    try:
        yield master, path
    finally:
        os.close(master)
        os.close(slave)


def test_bridge_reads_and_writes_a_serial_port(uart: tuple[int, str]) -> None:
    master, path = uart
    plan = plan_bridge(load_model(HERE / "boat.modd", free_port()))
    sinks = {p.name: Recorder() for p in plan.publishers}
    logs: list[str] = []
    bridge = Bridge(
        plan,
        open_transport(f"{path},921600"),
        sinks,
        BridgeSettings(heartbeat_timeout_s=2.0, status_period_s=0.5),
        logs.append,
    )
    stop = threading.Event()
    thread = threading.Thread(target=bridge.run, args=(stop,))
    thread.start()
    ap = Autopilot()
    decoder = Decoder()
    commands: list[int] = []
    try:
        # Frames written in odd-sized pieces and glued together, as a UART delivers them.
        stream = ap.heartbeat() + b"".join(
            ap.position(477_000_000 + i, -33_500_000, 1500 + i, boot_ms=1000 + 100 * i)
            for i in range(20)
        )
        for k in range(0, len(stream), 7):
            os.write(master, stream[k : k + 7])
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and not commands:
            ready, _, _ = select.select([master], [], [], 0.2)
            if ready:
                for f in decoder.feed(os.read(master, 4096)):
                    if f.kind is Kind.MESSAGE and f.message.get_type() == "COMMAND_LONG":
                        commands.append(int(f.message.command))
        lat = [v for s in sinks.values() for t, _, v in s.samples if t.endswith(".latitude")]
        deadline = time.monotonic() + 5
        while len(lat) < 20 and time.monotonic() < deadline:
            time.sleep(0.05)
            lat = [v for s in sinks.values() for t, _, v in s.samples if t.endswith(".latitude")]
    finally:
        stop.set()
        thread.join(10)
    assert not thread.is_alive()
    assert MAV.MAV_CMD_SET_MESSAGE_INTERVAL in commands, "\n".join(logs)  # written to the UART
    assert lat == pytest.approx([(477_000_000 + i) * 1e-7 for i in range(20)]), "\n".join(logs)
