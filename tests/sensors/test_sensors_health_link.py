"""Per-sensor health reaches the base station (issue 32, item 3): ``modd-sensors`` tells
the real PubBroker its instruments' health through the ingress (HEALTH), and the
PubBroker forwards it in the link's STATUS. The test writes the GNSS's side on a
pseudo-terminal (good and bad sentences it counts itself), unplugs and replugs it, and
reads STATUS as a base station does (tests/runtime's BaseStation: the Python link codec)."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from devices import PtyDevice, nmea, wait_until
from mavlink_harness import LINK_KEY, Proc, load_model, start_pubbroker
from modd.link.frames import HEALTH_STATES
from modd.ports import free_port
from modd.subbroker.planning import config_for
from modd_plan import make_plan
from pubbroker_harness import BaseStation

MODEL = """
Drone usv { Sensors {
    Sensor gnss kind nmea on "DEV/gnss" measures { lat("deg", float64) from sentence GGA.lat; }
} }
PubBroker onboard("127.0.0.1":7171, "/tmp/unused");
SubBroker base("127.0.0.1":7272, "/tmp/unused");
Publishers { Publisher nav(0.1, "usv.gnss.lat"); }
"""


def _gga(lat: float) -> bytes:
    return nmea(
        f"GPGGA,101500.00,{int(lat):02d}{(lat % 1) * 60:07.4f},N,00321.0000,W,1,09,0.9,4,M,,M,,"
    )


def test_the_base_station_sees_each_instruments_health_in_status(tmp_path: Path) -> None:
    dev = tmp_path / "dev"
    dev.mkdir()
    gnss = PtyDevice(dev / "gnss")
    src = tmp_path / "boat.modd"
    src.write_text(MODEL.replace("DEV", str(dev)))
    link_port = free_port()
    model = load_model(src, link_port)
    broker, _, model_json = start_pubbroker(model, tmp_path / "run")
    sensors = Proc(
        [str(Path(sys.executable).parent / "modd-sensors"), "--model", str(model_json)],
        tmp_path / "sensors.log",
    )
    try:
        station = BaseStation(link_port, LINK_KEY.encode()).start()
        try:
            # the running plan, as the SubBroker sends it, with one STATUS a second
            station.configure(config_for(make_plan(model), 1, status_period_s=1))
            _watch(station, gnss)
        finally:
            station.close()
    finally:
        assert sensors.stop() == 0, sensors.log()
        broker.stop()
        gnss.close()
    assert "ingress_malformed_frames=0" in broker.log(), broker.log()  # HEALTH understood


def _watch(station: BaseStation, device: PtyDevice) -> None:
    """Good and bad sentences, an unplug and a replug, each seen in STATUS."""

    def gnss() -> dict[str, int]:
        return station.snapshot().sensors.get("gnss", {})

    open_, closed = HEALTH_STATES.index("open"), HEALTH_STATES.index("closed")
    wait_until(lambda: gnss().get("state") == open_, 30, "the GNSS reported open in STATUS")
    before_ms = time.time_ns() // 10**6
    for i in range(5):
        device.write(_gga(47.7 + i * 0.001))
    device.write(_gga(48.0).replace(b"*", b"0*"))  # bad checksum
    device.write(b"\x80\xfe garbage\r\n")
    wait_until(lambda: gnss().get("lines_ok") == 5, 20, "5 good sentences counted")
    after_ms = time.time_ns() // 10**6
    h = gnss()
    assert h["lines_bad"] == 2 and h["values"] == 5 and h["reconnects"] == 0, h
    assert before_ms <= h["last_value_ms"] <= after_ms, h
    device.unplug()
    wait_until(lambda: gnss()["state"] == closed, 20, "the loss in STATUS")
    device.plug()
    wait_until(lambda: gnss()["reconnects"] == 1, 20, "the replug in STATUS")
    assert gnss()["lines_ok"] == 5
