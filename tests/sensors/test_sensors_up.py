"""Done when (issue 32): a model with an NMEA GNSS, an NMEA depth sounder, an
ASCII CTD and a Modbus sonde runs under ``modd up`` with no driver code. The
test writes the instruments' side on pseudo-terminals (pymodbus's server is
the sonde) and reads the PubBroker's archive with the official MCAP reader:
every valid sentence, line and register value is there with the right value
in the model's unit, no bad one is, each bad one is counted in the sensor's
health, and an unplugged GNSS resumes within 2 s of being plugged back in."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pynmea2  # type: ignore[import-untyped]
import pytest
from devices import ModbusDevice, PtyDevice, nmea, run_health, wait_until
from mavlink_harness import f32, read_archive
from modd.ports import free_port

MODEL = """
Drone usv {{ Sensors {{
    Sensor gnss "u-blox" kind nmea on "{dev}/gnss" {{ baud = 9600; }} measures {{
        lat("deg", float64) from sentence GGA.lat; lon("deg", float64) from sentence GGA.lon;
        speed(METER_PER_SECOND) from sentence RMC.speed_knots scale 0.514444;
    }}
    Sensor sounder kind nmea on "{dev}/sounder" {{ baud = 4800; }} measures {{
        depth(METER) from sentence DBT.depth_meters;
    }}
    Sensor ctd kind ascii on "{dev}/ctd" {{ separator = ","; start = "START"; }} measures {{
        temperature(DEGREE_CELSIUS) from column 1;
        conductivity("mS/cm") from key "C" scale 0.001;
    }}
    Sensor sonde kind modbus on "{dev}/sonde" {{ baud = 19200; }} measures {{
        ph(NONE) from register 0 float32; oxygen("mg/l") from register 2 uint16 scale 0.01;
    }}
}} }}
PubBroker onboard("127.0.0.1":{port}, "/tmp/unused");
SubBroker base("127.0.0.1":{port2}, "/tmp/unused");
Publishers {{
    Publisher nav(0.1, "usv.gnss.lat", "usv.gnss.lon", "usv.gnss.speed", "usv.sounder.depth");
    Publisher water(0.5, "usv.ctd.temperature", "usv.ctd.conductivity", "usv.sonde.ph",
                    "usv.sonde.oxygen");
}}
"""


def _gga(lat: float) -> bytes:
    minutes = (lat - int(lat)) * 60
    return nmea(
        f"GNGGA,101500.00,{int(lat):02d}{minutes:07.4f},N,00321.0000,W,1,09,0.9,4.2,M,50.1,M,,"
    )


def test_four_instruments_archived_with_no_driver_code(tmp_path: Path) -> None:
    from pymodbus.client import ModbusSerialClient as Client

    dev, run = tmp_path / "dev", tmp_path / "run"
    dev.mkdir()
    gnss, sounder, ctd = (PtyDevice(dev / n) for n in ("gnss", "sounder", "ctd"))
    sonde = ModbusDevice(
        dev / "sonde", [*Client.convert_to_registers(7.25, Client.DATATYPE.FLOAT32), 812]
    )
    model = tmp_path / "boat.modd"
    model.write_text(MODEL.format(dev=dev, port=free_port(), port2=free_port()))
    env = dict(os.environ, MODD_LINK_KEY="sensors-test-key")
    up = subprocess.Popen(
        [
            str(Path(sys.executable).parent / "modd"),
            "up",
            str(model),
            "--part",
            "drone",
            "--workdir",
            str(run),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env=env,
    )
    try:
        wait_until(
            lambda: (
                len(run_health(run)) == 4
                and all(h.get("connected") for h in run_health(run).values())
            ),
            30,
            "modd-sensors opened the four devices",
        )
        assert b"START\r\n" in ctd.read(1.0)
        lats = [47.70 + i * 0.0001 for i in range(10)]
        for i, lat in enumerate(lats):
            gnss.write(_gga(lat))
            if i == 3:  # bad checksum, truncated line, a line glued to the next
                gnss.write(
                    _gga(48.0).replace(b"*", b"1*")
                    + _gga(49.0)[:20]
                    + b"\r\n"
                    + _gga(50.0)[:30]
                    + _gga(lat + 0.00005)
                )
            time.sleep(0.02)
        gnss.write(nmea("GPRMC,101500.00,A,4742.0000,N,00321.0000,W,3.5,90.0,271126,,,A"))
        gnss.write(nmea("GPRMC,101501.00,V,,,,,,,271126,,,N"))  # no fix: nothing archived
        depths = [3.5, 3.75, 4.0]
        for d in depths:
            sounder.write(nmea(f"SDDBT,{d * 3.28084:.2f},f,{d:.2f},M,{d * 0.5468:.2f},F"))
        sounder.write(b"\x80\xfe\x13garbage at 9600 read as 4800\r\n")
        ctd.write(b"12.5,C=45100\r\n12.6;C=45200\r\nS>\r\n12.7,C=\r\n12.8,C=45300\r\n")
        wait_until(lambda: run_health(run)["sonde"]["values"] >= 4, 15, "two polls of the sonde")
        wait_until(lambda: run_health(run)["gnss"]["values"] == 2 * 10 + 1, 10, "GNSS values")

        gnss.unplug()
        wait_until(lambda: not run_health(run)["gnss"]["connected"], 5, "the GNSS loss seen")
        gnss.plug()
        start = time.monotonic()
        while run_health(run)["gnss"]["values"] < 2 * 10 + 3:
            assert time.monotonic() - start < 2.0, run_health(run)["gnss"]
            gnss.write(_gga(47.71))
            time.sleep(0.1)
        n_replug = (run_health(run)["gnss"]["values"] - 2 * 10 - 1) // 2
        health = run_health(run)
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
        for device in (gnss, sounder, ctd):
            device.close()
        sonde.close()
    assert up.returncode == 0, out
    assert "started sensors" in out

    archive = read_archive(run / "archive")
    got = {t: [v for _, v in samples] for t, samples in archive.items()}
    # what each valid GGA says, read by pynmea2 (the merged one is lost with its fragment)
    expected = [pynmea2.parse(_gga(x).decode().strip(), check=True) for x in lats]
    expected += [pynmea2.parse(_gga(47.71).decode().strip(), check=True)] * n_replug
    assert got["usv.gnss.lat"] == [pytest.approx(g.latitude, abs=1e-12) for g in expected]
    assert got["usv.gnss.lon"] == [pytest.approx(g.longitude, abs=1e-12) for g in expected]
    assert got["usv.gnss.speed"] == [f32(3.5 * 0.514444)]
    assert got["usv.sounder.depth"] == [f32(d) for d in depths]
    assert got["usv.ctd.temperature"] == [f32(12.5), f32(12.8)]
    assert got["usv.ctd.conductivity"] == [f32(45.1), f32(45.3)]
    assert set(got["usv.sonde.ph"]) == {7.25} and set(got["usv.sonde.oxygen"]) == {f32(8.12)}
    assert health["gnss"]["linesBad"] == 3 and health["gnss"]["missing"] >= 1
    assert health["gnss"]["reconnects"] == 1
    assert health["sounder"]["linesBad"] == 1
    assert health["ctd"]["linesBad"] == 3
