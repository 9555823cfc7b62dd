"""modd-sensors' per-sensor health as it leaves for the PubBroker (ingress HEALTH, then the
link's STATUS): each counter under its protocol name, the state's code, the last value time,
and the runner reporting it while it runs and once more when it stops."""

from __future__ import annotations

import threading
import time
from pathlib import Path

from modd.link import codec
from modd.link.frames import HEALTH_FIELDS, HEALTH_STATES, SensorHealth, Status
from modd.sensors.health import Health
from modd.sensors.plan import Device, Mapping, SensorPlan
from modd.sensors.run import Runner


class Sink:
    def declare(self, topic: str, vtype: str) -> None:
        pass

    def publish(self, topic: str, timestamp_ns: int, value: float) -> bool:
        return True

    def flush(self, timeout: float = 5.0) -> bool:
        return True

    def close(self, timeout: float = 2.0) -> None:
        pass


def test_every_counter_travels_under_its_protocol_name() -> None:
    h = Health(connected=True, lines_ok=7, values=12, missing=1, refused=2, reconnects=3)
    h.bad("checksum")
    h.timeouts, h.exceptions, h.silences = 4, 5, 6
    h.ignored = 8
    h.no_value(2, "GGA fix quality 0 (no fix)", no_fix=True)
    h.last_value_ns = 1_700_000_000_123_456_789
    # through the link's codec, as the SubBroker reads it
    frame = codec.split_frame(codec.encode(Status((1,), (h.report("ctd"),))))
    assert frame is not None
    status = codec.decode(frame)
    assert isinstance(status, Status)
    (got,) = status.sensors
    assert got.name == "ctd"
    assert got.as_dict() == {
        "state": HEALTH_STATES.index("open"),
        "lines_ok": 7,
        "lines_bad": 1,
        "reconnects": 3,
        "last_value_ms": 1_700_000_000_123,
        "values": 12,
        "missing": 3,
        "refused": 2,
        "timeouts": 4,
        "exceptions": 5,
        "silences": 6,
        "ignored": 8,
        "no_fix": 2,
    }
    assert len(got.fields) == len(HEALTH_FIELDS)


def test_state_codes() -> None:
    assert Health().report("x").as_dict()["state"] == HEALTH_STATES.index("closed")
    assert Health(connected=True, silent=True).report("x").as_dict()["state"] == 2
    assert Health(connected=False, silent=True).report("x").as_dict()["state"] == 0
    assert Health().report("x").as_dict()["last_value_ms"] == 0  # none yet


def test_the_runner_reports_health_while_it_runs_and_when_it_stops(tmp_path: Path) -> None:
    plan = SensorPlan(
        "gnss",
        "nmea",
        Device(str(tmp_path / "absent")),  # never there: the sensor stays closed
        (Mapping("usv.gnss.lat", "float64", "nav", ("GGA", "lat")),),
    )
    reports: list[list[SensorHealth]] = []
    runner = Runner([plan], {"nav": Sink()}, lambda _: None, None, 60.0, reports.append, 0.1)
    stop = threading.Event()
    t = threading.Thread(target=runner.run, args=(stop, 0.02))
    t.start()
    deadline = time.monotonic() + 20
    while len(reports) < 3 and time.monotonic() < deadline:
        time.sleep(0.02)
    stop.set()
    t.join(10)
    assert len(reports) >= 4  # periodic ones, then the last at stop
    assert all([h.name for h in r] == ["gnss"] for r in reports)
    assert reports[-1][0].as_dict()["state"] == HEALTH_STATES.index("closed")
