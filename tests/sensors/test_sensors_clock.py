"""Done when (issue 39, item 3): at a real pace (9600 baud, sentences in fix-epoch
order) a ``modd-sensors`` process with ``clock = instrument`` stamps GGA, GNS,
GLL and RMC with each sentence's own UTC (within 1 ms), VTG and GSA with their
epoch's, across a midnight, while the receiver states its dates 1024 GPS weeks
early (a week-rollover bug) and its first epoch comes before any date (held,
then stamped on the instrument's clock: no sample carries the computer's)."""

from __future__ import annotations

import datetime
import time
from pathlib import Path

from devices import PtyDevice, nmea, wait_until
from ingress_stub import RecordingIngress
from test_sensors_corpus import _health, start_reader, stop_reader

BAUD_BYTES_S = 960  # 9600 baud, 10 bits a byte
ROLLOVER = datetime.timedelta(weeks=1024)
TIMED = ("gga", "gns", "gll", "rmc")

MODEL = """
Drone c {{ Sensors {{
    Sensor gnss kind nmea on "{dev}" {{ baud = 9600; clock = instrument; }} measures {{
        gga("deg", float64) from sentence GGA.lat; gns("deg", float64) from sentence GNS.lat;
        gll("deg", float64) from sentence GLL.lat; rmc("deg", float64) from sentence RMC.lat;
        vtg("deg") from sentence VTG.course_true; gsa(NONE) from sentence GSA.pdop;
    }}
}} }}
PubBroker("127.0.0.1":7171, "/tmp/unused"); SubBroker("127.0.0.1":7272, "/tmp/unused");
Publishers {{ Publisher p(0.1, "c.gnss.gga", "c.gnss.gns", "c.gnss.gll", "c.gnss.rmc",
                          "c.gnss.vtg", "c.gnss.gsa"); }}
"""


def epoch(i: int, t: datetime.datetime) -> list[bytes]:
    """One fix epoch as a receiver sends it; latitude 47° + i minutes names the epoch."""
    hms = t.strftime("%H%M%S.") + f"{t.microsecond // 10000:02d}"
    lat = f"47{i:02d}.0000,N,00321.0000,W"
    early = (t - ROLLOVER).strftime("%d%m%y")  # the week-rollover bug
    return [
        nmea(f"GPGGA,{hms},{lat},1,09,0.9,4.2,M,50.1,M,,"),
        nmea(f"GNGNS,{hms},{lat},AAN,12,0.9,4.2,50.1,,,V"),
        nmea(f"GNGSA,A,3,01,02,03,04,,,,,,,,,{1 + i / 10:.1f},0.9,1.0,1"),
        nmea(f"GPGLL,{lat},{hms},A,A"),
        nmea(f"GPVTG,{i}.0,T,,M,0.1,N,0.2,K,A"),
        nmea(f"GPRMC,{hms},A,{lat},0.1,{i}.0,{early},,,A,V"),
    ]


def test_instrument_clock_at_9600_baud_across_midnight_and_rollover(tmp_path: Path) -> None:
    device = PtyDevice(tmp_path / "gnss")
    model = tmp_path / "clock.modd"
    model.write_text(MODEL.format(dev=device.path))
    ingress = RecordingIngress(tmp_path / "ingress.sock", "c")
    status = tmp_path / "sensors.json"
    proc = start_reader(model, tmp_path / "ingress.sock", status)
    today = datetime.datetime.now(datetime.UTC).replace(hour=0, minute=0, second=0, microsecond=0)
    midnight = today + datetime.timedelta(days=1)
    times = [midnight + datetime.timedelta(seconds=i - 5, milliseconds=250) for i in range(10)]
    try:
        wait_until(lambda: _health(status).get("gnss", {}).get("connected"), 30, "device open")
        for i, t in enumerate(times):
            for line in epoch(i, t):
                device.write(line)
                time.sleep(len(line) / BAUD_BYTES_S)
        wait_until(lambda: len(ingress.topic("c.gnss.gsa")) == len(times), 10, "every epoch")
    finally:
        log = stop_reader(proc)
        device.close()
        ingress.close()
    expected = [int(t.timestamp() * 10**6) * 1000 for t in times]
    for name in TIMED:
        got = ingress.topic(f"c.gnss.{name}")
        assert [round((v - 47) * 60) for _, v in got] == list(range(10)), (name, got, log)
        for (stamp, _), want in zip(got, expected, strict=True):
            assert abs(stamp - want) <= 1_000_000, (name, stamp, want)
    for name in ("vtg", "gsa"):  # no time of their own: their epoch's
        assert [s for s, _ in ingress.topic(f"c.gnss.{name}")] == expected, name
    health = _health(status)["gnss"]
    assert health["linesBad"] == 0 and health["missing"] == 0, health
