"""Issue 39, item 5, on two machines: a deploy reaches the on-board processes over
the link alone. The PubBroker (with ``--onboard-model`` in the drone's directory)
and the SubBroker (``--onboard-over-link``, its state in the station's directory)
share nothing but the link, over TCP and over serial through ``modd-radio`` (two
pseudo-terminals, 252-byte packets: the model goes as control fragments). Signed
deploys add a depth sounder and change the GNSS (a new mapping), then remove the
sounder: the PubBroker writes the on-board model file, ``modd-sensors --watch``
applies it, the answers come back in the deploy's reply (ONBOARD_ACK), values of the
added instrument reach the archive (read with the official MCAP reader, the
sentences decoded by pynmea2), and the PubBroker keeps its PID. A model whose
on-board part does not fit ONBOARD is refused before its CONFIG, located."""

from __future__ import annotations

import json
import secrets
import sys
import time
from pathlib import Path
from typing import Any

import pynmea2  # type: ignore[import-untyped]
import pytest
from modd.onboard import pack
from modd.ports import free_port
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from modd_contracts.link_wire_gen import MAX_ONBOARD_WIRE
from modd_model import load_text
from radio_harness import start_pubbroker_dgram, start_radio_serial
from subbroker_harness import (
    PUBBROKER,
    PYTHON,
    SUBBROKER,
    Proc,
    processes,
    signed,
    start_pubbroker,
    subbroker_config,
    wait_port,
)

TESTS = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TESTS / "sensors"))  # the instruments on pseudo-terminals
sys.path.insert(0, str(TESTS / "mavlink"))  # the archive read with the official MCAP reader
from devices import PtyDevice, nmea, wait_until  # noqa: E402
from mavlink_harness import read_archive  # noqa: E402

pytestmark = pytest.mark.e2e

GNSS1 = """Sensor gnss kind nmea on "{dev}/gnss" { baud = 9600; } measures {
        lat("deg", float64) from sentence GGA.lat; }"""
GNSS2 = """Sensor gnss kind nmea on "{dev}/gnss" { baud = 9600; } measures {
        lat("deg", float64) from sentence GGA.lat; lon("deg", float64) from sentence GGA.lon; }"""
SOUNDER = """Sensor sounder kind nmea on "{dev}/sounder" { baud = 4800; } measures {
        depth(METER) from sentence DBT.depth_meters; }"""


def _model(dev: Path, sensors: list[str], topics: list[str], link: str) -> dict[str, Any]:
    quoted = ", ".join(f'"usv.{t}"' for t in topics)
    text = (
        "Drone usv { Sensors { " + "\n".join(sensors).replace("{dev}", str(dev)) + " } }\n"
        'PubBroker onboard("127.0.0.1":1, "/tmp/unused");\n'
        'SubBroker base("127.0.0.1":2, "/tmp/unused");\n'
        f"Publishers {{ Publisher nav(0.1, {quoted}); }}\n"
        'Subscriptions { Subscriber lat("usv.gnss.lat", 1.0, LAST); }\n' + link
    )
    result = load_text(text, "boat.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    return result.model


def _gga(i: int) -> bytes:
    return nmea(f"GNGGA,101500.00,47{42 + i * 0.001:07.4f},N,00321.0000,W,1,09,0.9,4.2,M,,M,,")


def _deploy(session: Any, model: dict[str, Any], revision: int) -> dict[str, Any]:
    body = {"text": json.dumps(model), "format": "json", "project_id": 1, "revision": revision}
    reply: dict[str, Any] = request(session, "modd/usv/deploy", signed(body), timeout_s=30)
    return reply


def _actions(reply: dict[str, Any]) -> dict[str, str]:
    return {s["sensor"]: s["action"] for s in reply["onboard"]["sensors"]["sensors"]}


def _subbroker(tmp: Path, model: Path, endpoint: str, zport: int, link: dict[str, Any]) -> Proc:
    """The station: its own directory, state and record; ONBOARD over the link."""
    station = tmp / "station"
    station.mkdir()
    state = station / "state"
    path = subbroker_config(station, model, endpoint, zport, state_dir=state, **link)
    cmd = [*SUBBROKER, "--config", str(path), "--onboard-over-link"]
    return Proc("sb", cmd, station / "sb.log", dumps_stacks=True)


@pytest.mark.usefixtures("needs_pubbroker")
@pytest.mark.parametrize("transport", ["tcp", "serial"])
def test_a_deploy_reaches_modd_sensors_over_the_link_alone(
    transport: str, tmp_path: Path, zenoh_client: Any
) -> None:
    dev, drone = tmp_path / "dev", tmp_path / "drone"
    dev.mkdir()
    drone.mkdir()
    gnss, sounder = PtyDevice(dev / "gnss"), PtyDevice(dev / "sounder")
    zport, ingress = free_port(), free_port()
    serial = 'Link { transport = serial; device = "/dev/null"; packet = 252; }\n'
    link = serial if transport == "serial" else ""
    v1 = _model(dev, [GNSS1], ["gnss.lat"], link)
    model_path = tmp_path / "station-model.json"  # the station's copy only
    model_path.write_text(json.dumps(v1))
    onboard = drone / "onboard" / "model.json"  # the drone's own copy, on its side
    onboard.parent.mkdir()
    onboard.write_text(json.dumps(v1))
    procs: list[Proc] = []
    if transport == "tcp":
        port = free_port()
        cmd = [str(PUBBROKER), "--onboard-model", str(onboard)]
        pb = start_pubbroker(drone, model_path, port, ingress, command=cmd)
        sb = _subbroker(tmp_path, model_path, f"127.0.0.1:{port}", zport, {})
    else:
        radio, base, tty = start_radio_serial(tmp_path, "packet=252,latency_ms=20,seed=5")
        procs.append(radio)
        dgram = {"transport": "serial", "device": tty, "port": 1, "max_packet": 252}
        pb = start_pubbroker_dgram(
            drone, model_path, dgram, ingress, args=("--onboard-model", str(onboard))
        )
        sb = _subbroker(
            tmp_path,
            model_path,
            "127.0.0.1:1",
            zport,
            {"transport": "serial", "device": base},
        )
    sensors = Proc(
        "sensors",
        [str(PYTHON), "-m", "modd.sensors.cli", "--model", str(onboard), "--watch"]
        + ["--ingress", f"tcp:127.0.0.1:{ingress}", "--status-file", str(drone / "sensors.json")],
        drone / "sensors.log",
    )
    written: list[bytes] = []
    with processes(*procs, pb, sb, sensors):
        wait_port(zport, 40)
        session = zenoh_client(zport)
        assert wait_connected(session)
        assert sb.wait_log("running", 40), sb.log()[-3000:]
        applied = drone / "onboard" / "applied" / "sensors.json"
        wait_until(applied.exists, 30, "modd-sensors following the on-board model file")
        pid = pb.pid
        # add the sounder, change the GNSS (its longitude mapped too)
        v2 = _model(dev, [GNSS2, SOUNDER], ["gnss.lat", "gnss.lon", "sounder.depth"], link)
        reply = _deploy(session, v2, 2)
        assert reply["status"] == "ACKED", reply
        assert reply["onboard"]["sensors"]["ok"], reply["onboard"]
        assert _actions(reply) == {"gnss": "restarted", "sounder": "started"}, reply
        assert "on-board model" in pb.log() and "written to " + str(onboard) in pb.log()
        for i in range(3):
            written.append(_gga(i))
            gnss.write(written[-1])
            sounder.write(nmea(f"SDDBT,11.48,f,{3.5 + i:.2f},M,1.91,F"))
            time.sleep(0.1)
        health = drone / "sensors.json"
        wait_until(
            lambda: json.loads(health.read_text())["sensors"]["sounder"]["values"] == 3,
            5,
            "sounder",
        )
        # remove the sounder
        v3 = _model(dev, [GNSS2], ["gnss.lat", "gnss.lon"], link)
        reply = _deploy(session, v3, 3)
        assert reply["status"] == "ACKED" and reply["onboard"]["sensors"]["ok"], reply
        assert _actions(reply) == {"gnss": "unchanged", "sounder": "stopped"}, reply
        # an on-board model beyond what ONBOARD carries: refused before its CONFIG, located
        crowd = [GNSS2] + [
            f's{i:03d}{secrets.token_hex(6)} kind nmea on "/dev/x{secrets.token_hex(8)}" '
            "{ baud = 4800; } measures { depth(METER) from sentence DBT.depth_meters; }"
            for i in range(200)
        ]
        big = _model(
            dev, ["Sensor " + c if i else c for i, c in enumerate(crowd)], ["gnss.lat"], link
        )
        assert len(pack(big)) > MAX_ONBOARD_WIRE
        refused = _deploy(session, big, 4)
        assert refused["status"] == "REJECTED" and "ONBOARD" in refused["reason"], refused
        assert refused["diagnostics"][0]["pointer"] == "/drone/sensors"
        assert pb.pid == pid and pb.alive(), "the PubBroker was restarted"
        time.sleep(0.6)  # the last samples reach the archive before the stop
    archive = read_archive(drone / "archive")
    got = {t: [v for _, v in samples] for t, samples in archive.items()}
    assert got["usv.sounder.depth"] == [3.5, 4.5, 5.5]
    lats = [pynmea2.parse(g.decode().strip(), check=True).latitude for g in written]
    assert got["usv.gnss.lat"][-3:] == [pytest.approx(x, abs=1e-12) for x in lats]
    # nothing shared: the station's directory holds no on-board model file
    assert not list((tmp_path / "station").rglob("model.json"))
    assert "config 3 accepted" in pb.log() and "config 4" not in pb.log()
    gnss.close()
    sounder.close()
