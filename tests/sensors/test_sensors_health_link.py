"""Per-sensor health reaches the base station (issue 32, item 3): ``modd-sensors`` tells
the real PubBroker its instruments' health through the ingress (HEALTH), and the
PubBroker forwards it in the link's STATUS. The test writes the GNSS's side on a
pseudo-terminal (good and bad sentences it counts itself), unplugs and replugs it, and
reads STATUS as a base station does (the Python link codec after the handshake)."""

from __future__ import annotations

import socket
import sys
import threading
import time
from pathlib import Path

from devices import PtyDevice, nmea, wait_until
from mavlink_harness import LINK_KEY, Proc, load_model, start_pubbroker
from modd.link import codec
from modd.link.auth import client_handshake
from modd.link.frames import HEALTH_STATES, Status
from modd.ports import free_port
from modd.subbroker.planning import config_for
from modd_plan import make_plan

MODEL = """
Drone usv { Sensors {
    Sensor gnss kind nmea on "DEV/gnss" measures { lat("deg", float64) from sentence GGA.lat; }
} }
PubBroker onboard("127.0.0.1":7171, "/tmp/unused");
SubBroker base("127.0.0.1":7272, "/tmp/unused");
Publishers { Publisher nav(0.1, "usv.gnss.lat"); }
"""


class Station:
    """Reads the link and keeps the last STATUS's instruments, by name."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        _, self.splitter = client_handshake(self.sock, LINK_KEY.encode())
        self.sensors: dict[str, dict[str, int]] = {}
        self.lock = threading.Lock()
        self.sock.settimeout(0.2)
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:
                return
            for f in self.splitter.feed(data):
                m = None if codec.is_data_type(f.type) else codec.decode(f)
                if isinstance(m, Status) and m.sensors:
                    with self.lock:
                        self.sensors = {h.name: h.as_dict() for h in m.sensors}

    def gnss(self) -> dict[str, int]:
        with self.lock:
            return dict(self.sensors.get("gnss", {}))

    def close(self) -> None:
        self.sock.close()
        self.thread.join(2)


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
    station = None
    try:
        station = Station(link_port)
        # the running plan, as the SubBroker sends it, with one STATUS a second
        station.sock.sendall(codec.encode(config_for(make_plan(model), 1, status_period_s=1)))
        wait_until(
            lambda: station.gnss().get("state") == HEALTH_STATES.index("open"),
            30,
            "the GNSS reported open in STATUS",
        )
        before_ms = time.time_ns() // 10**6
        for i in range(5):
            gnss.write(_gga(47.7 + i * 0.001))
        gnss.write(_gga(48.0).replace(b"*", b"0*"))  # bad checksum
        gnss.write(b"\x80\xfe garbage\r\n")
        wait_until(lambda: station.gnss().get("lines_ok") == 5, 20, "5 good sentences counted")
        after_ms = time.time_ns() // 10**6
        h = station.gnss()
        assert h["lines_bad"] == 2 and h["values"] == 5 and h["reconnects"] == 0, h
        assert before_ms <= h["last_value_ms"] <= after_ms, h
        gnss.unplug()
        wait_until(
            lambda: station.gnss()["state"] == HEALTH_STATES.index("closed"),
            20,
            "the loss in STATUS",
        )
        gnss.plug()
        wait_until(lambda: station.gnss()["reconnects"] == 1, 20, "the replug in STATUS")
        assert station.gnss()["lines_ok"] == 5
    finally:
        if station is not None:
            station.close()
        assert sensors.stop() == 0, sensors.log()
        broker.stop()
        gnss.close()
    assert "ingress_malformed_frames=0" in broker.log(), broker.log()  # HEALTH understood
