"""The simulator's instruments (modd.sim.instruments) read by the real reader:
an NMEA GNSS, an ASCII CTD and a Modbus sonde on the simulator's
pseudo-terminals give the values the simulator's track says, as under
``modd up --simulate``; a device path that is not a link is never replaced."""

from __future__ import annotations

import threading
from pathlib import Path

import pytest
from devices import wait_until
from modd.sensors.plan import plan_sensors
from modd.sensors.run import Runner
from modd.sim.instruments import open_device, simulated_devices, start_instruments
from modd.sim.track import ORIGIN_LAT
from modd_model import parse_text
from test_sensors_faults import Recorder

MODEL = """
Drone usv { Sensors {
    Sensor gnss kind nmea on "/dev/ttyACM0" { clock = instrument; } measures {
        lat("deg", float64) from sentence GGA.lat; }
    Sensor ctd kind ascii on "/dev/ttyUSB1" measures {
        water_temperature(DEGREE_CELSIUS) from column 1; conductivity("mS/cm") from key "C"; }
    Sensor sonde kind modbus on "/dev/ttyUSB2" measures {
        temperature(DEGREE_CELSIUS) from register 4 float32 order little;
        depth(METER) from register 0 uint16 unit 2 scale 0.01; }
} }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers { Publisher p(0.2, "usv.gnss.lat", "usv.ctd.water_temperature",
                          "usv.ctd.conductivity", "usv.sonde.temperature", "usv.sonde.depth"); }
"""


def test_simulated_instruments_read_by_the_reader(tmp_path: Path) -> None:
    doc, _ = parse_text(MODEL)
    local = simulated_devices(doc, tmp_path / "devices")
    assert {s["device"]["path"] for s in local["drone"]["sensors"]} == {
        str(tmp_path / "devices" / n) for n in ("gnss", "ctd", "sonde")
    }
    assert doc["drone"]["sensors"][0]["device"]["path"] == "/dev/ttyACM0"  # the model is kept
    stop = threading.Event()
    threads = start_instruments(local, start=0.0, stop=stop, log=lambda _: None)
    out = Recorder()
    runner = Runner(plan_sensors(local), {"p": out}, log=lambda _: None, status_period_s=3600)
    reader = threading.Thread(target=runner.run, args=(stop,), daemon=True)
    reader.start()
    try:
        for topic in ("lat", "water_temperature", "conductivity", "temperature", "depth"):
            wait_until(lambda topic=topic: len(out.values(topic)) >= 2, 15, topic)  # type: ignore[misc]
    finally:
        stop.set()
        reader.join(10)
        for th in threads:
            th.join(5)
    assert all(abs(v - ORIGIN_LAT) < 0.01 for v in out.values("lat"))
    assert all(8 < v < 20 for v in out.values("water_temperature") + out.values("temperature"))
    assert all(20 < v < 60 for v in out.values("conductivity"))
    assert all(0 < v < 10 for v in out.values("depth"))
    health = runner.health()
    assert all(h["linesBad"] == 0 and h["timeouts"] == 0 for h in health.values()), health


def test_a_real_file_is_never_replaced(tmp_path: Path) -> None:
    device = tmp_path / "ttyUSB0"
    device.write_text("not a link")
    with pytest.raises(FileExistsError):
        open_device(device)
    assert device.read_text() == "not a link"
