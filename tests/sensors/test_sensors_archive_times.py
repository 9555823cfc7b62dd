"""Both times reach the archive (issue 39, item 3): with ``clock = instrument`` the
real PubBroker, fed by ``modd-sensors`` reading a GNSS on a pseudo-terminal, archives
each sample with the instrument's time as the MCAP ``publish_time`` and its receive
time (the PubBroker's ingest stamp) as the MCAP ``log_time``: a dataset offers both
(``instrument_time`` / ``receive_time``). The receiver's clock here runs 90 s behind
the computer's, so the two cannot be mistaken for each other. Read back with the
official ``mcap`` reader."""

from __future__ import annotations

import datetime
import json
import time
from pathlib import Path

import pytest
from devices import PtyDevice, nmea, wait_until
from mavlink_harness import load_model, start_pubbroker
from modd.ports import free_port
from test_sensors_corpus import _health, start_reader, stop_reader

MODEL = """
Drone c { Sensors {
    Sensor gnss kind nmea on "DEV" { clock = instrument; } measures {
        lat("deg", float64) from sentence GGA.lat;
    }
} }
PubBroker("127.0.0.1":7171, "/tmp/unused"); SubBroker("127.0.0.1":7272, "/tmp/unused");
Publishers { Publisher p(0.1, "c.gnss.lat"); }
"""
BEHIND = datetime.timedelta(seconds=90)  # the instrument's clock, behind the computer's
N = 8
EPOCH = datetime.datetime(1970, 1, 1, tzinfo=datetime.UTC)


def _hms(t: datetime.datetime) -> str:
    return t.strftime("%H%M%S.") + f"{t.microsecond // 10000:02d}"


def _archive(directory: Path) -> list[tuple[float, int, int]]:
    """(latitude, log_time, publish_time) of every archived sample."""
    from mcap.reader import make_reader

    out = []
    for path in sorted(directory.glob("*.mcap")):
        with path.open("rb") as f:
            for _schema, channel, message in make_reader(f).iter_messages():
                assert channel.topic == "c.gnss.lat"
                value = json.loads(message.data)["value"]
                out.append((value, message.log_time, message.publish_time))
    return out


def test_the_archive_keeps_the_receive_time_and_the_instruments(tmp_path: Path) -> None:
    device = PtyDevice(tmp_path / "gnss")
    src = tmp_path / "gnss.modd"
    src.write_text(MODEL.replace("DEV", str(device.path)))
    broker, local, model_json = start_pubbroker(load_model(src, free_port()), tmp_path / "run")
    status = tmp_path / "sensors.json"
    reader = start_reader(model_json, Path(local["pubBroker"]["ingress"]["unixSocket"]), status)
    sent: list[tuple[int, int, int]] = []  # (instrument ns, written after ns, before ns)
    try:
        wait_until(lambda: _health(status).get("gnss", {}).get("connected"), 30, "gnss open")
        t0 = (datetime.datetime.now(datetime.UTC) - BEHIND).replace(microsecond=250_000)
        day = t0.strftime("%d%m%y")
        device.write(nmea(f"GPRMC,{_hms(t0)},A,4700.0000,N,00321.0000,W,0.1,1.0,{day},,,A"))
        for i in range(1, N + 1):
            t = t0 + datetime.timedelta(seconds=i)
            before = time.time_ns()
            device.write(nmea(f"GPGGA,{_hms(t)},47{i:02d}.0000,N,00321.0000,W,1,09,0.9,4,M,,M,,"))
            ns = (t - EPOCH) // datetime.timedelta(microseconds=1) * 1000
            sent.append((ns, before, time.time_ns()))
            time.sleep(0.2)
        wait_until(lambda: _health(status)["gnss"]["values"] == N, 20, "every GGA read")
    finally:
        out = stop_reader(reader)
        broker.stop()
        device.close()
    archived = _archive(tmp_path / "run" / "archive")
    lats = [v for v, _, _ in archived]
    assert lats == [pytest.approx(47 + i / 60, abs=1e-9) for i in range(1, N + 1)], out
    for (_, log_time, publish_time), (instrument_ns, before, after) in zip(
        archived, sent, strict=True
    ):
        assert publish_time == instrument_ns  # the sentence's own UTC, to the ns
        # the receive time: after the line was written, within 1 s of it
        assert before <= log_time <= after + 1_000_000_000, (log_time - before) / 1e9
        # the instrument's clock runs 90 s behind (its sentences a second apart,
        # written 0.2 s apart): two different times, both kept
        assert log_time - publish_time > (BEHIND.total_seconds() - N) * 1e9
