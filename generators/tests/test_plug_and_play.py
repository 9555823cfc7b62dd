"""The integrator download for plug-and-play sensors: no driver for what
modd-sensors or modd-mavlink reads, and a note that says so plainly."""

from __future__ import annotations

from modd_gen import generate
from modd_model import parse_text

SENSORS = """
Sensor gnss kind nmea on "/dev/ttyACM0" measures { lat("deg", float64) from sentence GGA.lat; }
Sensor ctd kind ascii on "/dev/ttyUSB1" measures { t(DEGREE_CELSIUS) from column 1; }
Sensor sonde kind modbus on "/dev/ttyUSB2" measures { ph(NONE) from register 0 float32; }
"""
BROKERS = 'PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");'


def _files(sensors: str, publishers: str) -> dict[str, str]:
    doc, _ = parse_text(
        f"Drone d {{ Sensors {{ {sensors} }} }} {BROKERS} Publishers {{ {publishers} }}"
    )
    return {a.path: a.content for a in generate(doc, "integrator")}


def test_only_plug_and_play_sensors_need_no_driver() -> None:
    files = _files(
        SENSORS, 'Publisher nav(0.2, "d.gnss.lat"); Publisher water(1, "d.ctd.t", "d.sonde.ph");'
    )
    note = files["integrator/PLUG-AND-PLAY.md"]
    assert "only plug-and-play sensors: there is no driver to write" in note
    for sensor, reader in (("gnss", "modd-sensors"), ("sonde", "modd-sensors")):
        assert f"| `{sensor}` |" in note and reader in note
    assert not any("-driver/" in p or p.startswith("integrator/python/") for p in files)


def test_a_generic_sensor_still_gets_its_driver() -> None:
    files = _files(
        SENSORS + "Sensor imu measures { ax(METER_PER_SECOND_SQUARED); }",
        'Publisher nav(0.2, "d.gnss.lat", "d.imu.ax"); Publisher water(1, "d.ctd.t");',
    )
    assert "integrator/nav-driver/src/driver.cpp" in files
    assert "d.imu.ax" in files["integrator/nav-driver/generated/nav_topics.hpp"]
    assert "d.gnss.lat" not in files["integrator/nav-driver/generated/nav_topics.hpp"]
    assert not any(p.startswith("integrator/water-driver/") for p in files)
    assert "only plug-and-play" not in files["integrator/PLUG-AND-PLAY.md"]
