"""The faults instruments really have, each against the real reader code
(``modd.sensors.run.Runner``) on pseudo-terminals: bad checksum, truncated
and merged lines, garbage at the wrong baud rate, unplug/replug, a silent
instrument, a flooding device next to quiet ones, Modbus timeouts and
exceptions (pymodbus's server as the device). Each is counted in the
sensor's health, never crashes the reader, and never publishes a wrong value."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from devices import ModbusDevice, PtyDevice, nmea, wait_until
from modd.sensors.plan import plan_sensors
from modd.sensors.run import Runner
from modd_model import parse_text


class Recorder:
    """A publisher stand-in, thread-safe: records what the reader publishes."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.samples: list[tuple[str, int, float]] = []

    def declare(self, topic: str, vtype: str) -> None:
        pass

    def publish(self, topic: str, timestamp_ns: int, value: float) -> bool:
        with self.lock:
            self.samples.append((topic, timestamp_ns, value))
        return True

    def values(self, topic: str) -> list[float]:
        with self.lock:
            return [v for t, _, v in self.samples if t.endswith("." + topic)]

    def has(self, topic: str, value: float) -> Callable[[], bool]:
        return lambda: value in self.values(topic)

    def flush(self, timeout: float = 5.0) -> bool:
        return True

    def close(self, timeout: float = 2.0) -> None:
        pass


def _model(tmp: Path, extra: str = "", topics: str = "") -> dict[str, Any]:
    doc, _ = parse_text(f'''
Drone usv {{ Sensors {{
    Sensor sounder kind nmea on "{tmp}/sounder" measures {{ depth(METER) from sentence DPT.depth; }}
    Sensor ctd kind ascii on "{tmp}/ctd" {{ start = "GO"; }} measures {{
        t(DEGREE_CELSIUS) from column 1; c("mS/cm") from column 2; }}
    {extra}
}} }}
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers {{ Publisher p(0.1, "usv.sounder.depth", "usv.ctd.t", "usv.ctd.c"{topics}); }}''')
    return doc


class Reader:
    def __init__(self, model: dict[str, Any]) -> None:
        self.out = Recorder()
        self.runner = Runner(
            plan_sensors(model), {"p": self.out}, log=lambda _: None, status_period_s=3600
        )
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.runner.run, args=(self.stop,), daemon=True)
        self.thread.start()

    def health(self, sensor: str) -> dict[str, Any]:
        return self.runner.health()[sensor]

    def close(self) -> None:
        self.stop.set()
        self.thread.join(10)
        assert not self.thread.is_alive()


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[tuple[Reader, PtyDevice, PtyDevice]]:
    sounder, ctd = PtyDevice(tmp_path / "sounder"), PtyDevice(tmp_path / "ctd")
    reader = Reader(_model(tmp_path))
    wait_until(
        lambda: reader.health("sounder")["connected"] and reader.health("ctd")["connected"],
        10,
        "both devices opened",
    )
    yield reader, sounder, ctd
    reader.close()
    sounder.close()
    ctd.close()


def test_bad_lines_are_counted_and_never_published(
    rig: tuple[Reader, PtyDevice, PtyDevice],
) -> None:
    reader, sounder, ctd = rig
    good = nmea("SDDPT,3.2,0.5")
    bad_checksum = good.replace(b"*", b"0*")
    truncated = good[:9] + b"\r\n"
    merged = good[:12] + nmea("SDDPT,9.9,0.5")
    sounder.write(bad_checksum + truncated + merged + good)
    ctd.write(b"12.5,45.1\r\n12.6\r\nS>\r\n12.7,4x\r\n")
    wait_until(
        lambda: bool(reader.out.values("depth")) and len(reader.out.values("t")) == 1,
        10,
        "the good lines published",
    )
    time.sleep(0.3)  # nothing else may come
    assert reader.out.values("depth") == [3.2]
    assert reader.out.values("t") == [12.5] and reader.out.values("c") == [45.1]
    assert reader.health("sounder")["linesBad"] == 3
    assert reader.health("ctd")["linesBad"] == 3


def test_start_command_is_sent_at_each_open(rig: tuple[Reader, PtyDevice, PtyDevice]) -> None:
    reader, _, ctd = rig
    wait_until(lambda: b"GO\r\n" in ctd.read(0.1), 5, "the start command")
    ctd.unplug()
    ctd.plug()
    wait_until(lambda: b"GO\r\n" in ctd.read(0.1), 5, "the start command after a replug")


def test_garbage_at_the_wrong_baud_rate(rig: tuple[Reader, PtyDevice, PtyDevice]) -> None:
    reader, sounder, _ = rig
    junk = bytes(b % 250 + 1 for b in range(8192)).replace(b"\n", b"").replace(b"\r", b"")
    sounder.write(junk * 4 + b"\r\n" + nmea("SDDPT,7.5,0.5"))
    wait_until(lambda: reader.out.values("depth") == [7.5], 10, "the line after the garbage")
    assert reader.health("sounder")["linesBad"] >= 1


def test_unplug_and_replug_resume_within_2_s(rig: tuple[Reader, PtyDevice, PtyDevice]) -> None:
    reader, sounder, _ = rig
    sounder.write(nmea("SDDPT,1.0,0.5"))
    wait_until(lambda: reader.out.values("depth") == [1.0], 10, "the first value")
    sounder.unplug()
    wait_until(lambda: not reader.health("sounder")["connected"], 5, "the loss seen")
    sounder.plug()  # a new pty: another /dev/pts number behind the same link
    start = time.monotonic()
    while 2.0 not in reader.out.values("depth"):
        assert time.monotonic() - start < 2.0, reader.health("sounder")
        sounder.write(nmea("SDDPT,2.0,0.5"))
        time.sleep(0.05)
    h = reader.health("sounder")
    assert h["reconnects"] == 1 and h["connected"]


def test_silent_instrument_is_reported(rig: tuple[Reader, PtyDevice, PtyDevice]) -> None:
    reader, sounder, _ = rig
    sounder.write(nmea("SDDPT,1.0,0.5"))
    wait_until(lambda: reader.health("sounder")["values"] == 1, 10, "the first value")
    wait_until(lambda: reader.health("sounder")["silent"], 10, "silence detected")
    assert reader.health("sounder")["silences"] == 1
    sounder.write(nmea("SDDPT,1.5,0.5"))
    wait_until(lambda: not reader.health("sounder")["silent"], 10, "speaking again")


def test_a_flooding_device_does_not_starve_the_others(
    rig: tuple[Reader, PtyDevice, PtyDevice],
) -> None:
    """The sounder floods ~1 MB/s of valid lines for 3 s; the CTD's lines at 10 Hz still
    arrive, each within 0.5 s."""
    reader, sounder, ctd = rig
    line = nmea("SDDPT,4.25,0.5")
    burst = line * (100_000 // len(line))
    stop = threading.Event()

    def flood() -> None:
        while not stop.is_set():
            t0 = time.monotonic()
            sounder.write(burst)
            time.sleep(max(0.0, 0.1 - (time.monotonic() - t0)))

    flooder = threading.Thread(target=flood, daemon=True)
    flooder.start()
    try:
        for i in range(30):
            ctd.write(f"{i}.5,1.0\r\n".encode())
            wait_until(reader.out.has("t", i + 0.5), 0.5, f"CTD line {i} under the flood")
            time.sleep(0.1)
    finally:
        stop.set()
        flooder.join(5)
    assert reader.health("sounder")["values"] > 10_000
    assert set(reader.out.values("depth")) == {4.25}


SONDE = """Sensor sonde kind modbus on "{tmp}/sonde" {{ baud = 19200; }} measures {{
    ph(NONE) from register 0 float32; temp(DEGREE_CELSIUS) from register 2 int16 scale 0.01;
    far(NONE) from register 500 uint16 unit 1; }}"""


def test_modbus_values_timeouts_and_exceptions(tmp_path: Path) -> None:
    from pymodbus.client import ModbusSerialClient as Client

    words = [
        *Client.convert_to_registers(7.25, Client.DATATYPE.FLOAT32),
        *Client.convert_to_registers(-1234, Client.DATATYPE.INT16),
    ]
    device = ModbusDevice(tmp_path / "sonde", words)
    sounder, ctd = PtyDevice(tmp_path / "sounder"), PtyDevice(tmp_path / "ctd")
    reader = Reader(
        _model(
            tmp_path,
            SONDE.format(tmp=tmp_path),
            ', "usv.sonde.ph", "usv.sonde.temp", "usv.sonde.far"',
        )
    )
    try:
        wait_until(lambda: len(reader.out.values("ph")) >= 2, 15, "two polls of the sonde")
        assert set(reader.out.values("ph")) == {7.25}
        assert reader.out.values("temp")[0] == pytest.approx(-12.34)
        assert len(set(reader.out.values("temp"))) == 1
        # register 500 is outside the device's block: pymodbus answers exception 2
        wait_until(lambda: reader.health("sonde")["exceptions"] >= 2, 10, "exceptions counted")
        assert reader.out.values("far") == []
        device.mute = True
        wait_until(lambda: reader.health("sonde")["timeouts"] >= 2, 10, "timeouts counted")
        n = len(reader.out.values("ph"))
        device.mute = False
        wait_until(lambda: len(reader.out.values("ph")) > n + 1, 10, "polling resumed")
        assert set(reader.out.values("ph")) == {7.25}  # nothing else, timeouts included
    finally:
        reader.close()
        device.close()
        sounder.close()
        ctd.close()
