"""Issue 39, item 5: a deploy reaches every on-board process. Under ``modd up``
(PubBroker, SubBroker, modd-sensors) and a ``modd-mavlink --watch`` on the run's
on-board model, signed deploys over zenoh add, change and remove an instrument
and a MAVLink-mapped variable; each is applied within 2 s, the PubBroker keeps
its PID, the acknowledgement says what each process did (a missing device
included), and no sample of the untouched GNSS nor of the autopilot's yaw is
lost: the archive, read with the official MCAP reader, holds every GGA the
test wrote (decoded by pynmea2) and every ATTITUDE it sent."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import pynmea2  # type: ignore[import-untyped]
import pytest
from devices import PtyDevice, gga, nmea, run_health, wait_until
from mavlink_harness import Autopilot, f32, read_archive
from modd.ports import free_port

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from support.processes import pid_alive  # noqa: E402

pytestmark = pytest.mark.e2e

BIN = Path(sys.executable).parent

HEAD = """
PubBroker onboard("127.0.0.1":{port}, "/tmp/unused");
SubBroker base("127.0.0.1":{port2}, "/tmp/unused");
"""
GNSS = """Sensor gnss kind nmea on "{dev}/gnss" { baud = 9600; } measures {
        lat("deg", float64) from sentence GGA.lat; }"""
CTD1 = """Sensor ctd kind ascii on "{dev}/ctd" { separator = ","; } measures {
        temperature(DEGREE_CELSIUS) from column 1; }"""
CTD2 = """Sensor ctd kind ascii on "{dev}/ctd" { separator = ","; } measures {
        temperature(DEGREE_CELSIUS) from column 1;
        conductivity("mS/cm") from key "C" scale 0.001; }"""
SOUNDER = """Sensor sounder kind nmea on "{dev}/sounder" { baud = 4800; } measures {
        depth(METER) from sentence DBT.depth_meters; }"""
ECHO = """Sensor echo kind nmea on "{dev}/unplugged" { baud = 4800; } measures {
        depth(METER) from sentence DBT.depth_meters; }"""


def _autopilot(pitch: bool) -> str:
    more = "pitch(RADIAN) from ATTITUDE.pitch;" if pitch else ""
    return f"Sensor autopilot kind mavlink measures {{ yaw(RADIAN) from ATTITUDE.yaw; {more} }}"


def model_text(
    sensors: list[str], nav: list[str], water: list[str], subscribed: str = "ctd.temperature"
) -> str:
    """The drone with ``sensors``; publishers nav (10 Hz) and, if ``water``, water
    (2 Hz); one subscriber averaging ``subscribed`` each second."""
    quoted = ", ".join(f'"usv.{t}"' for t in nav)
    wq = ", ".join(f'"usv.{t}"' for t in water)
    publishers = f"    Publisher nav(0.1, {quoted});\n"
    publishers += f"    Publisher water(0.5, {wq});\n" if water else ""
    return (
        "Drone usv { Sensors { " + "\n".join(sensors) + " } }" + HEAD + "Publishers {\n"
        f"{publishers}}}\n"
        f'Subscriptions {{ Subscriber t("usv.{subscribed}", 1.0, AVERAGE); }}\n'
    )


class Feeder:
    """Writes GGA to the GNSS and ATTITUDE (with HEARTBEAT) to the bridge at 10 Hz."""

    def __init__(self, gnss: PtyDevice, bridge_port: int) -> None:
        self.gnss, self.port = gnss, bridge_port
        self.ap = Autopilot()
        self.gga: list[bytes] = []
        self.yaw: list[float] = []
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

    def _run(self) -> None:
        from modd.mavlink.dialect import MAV

        i = 0
        while not self.stop.wait(0.1):
            line = gga(47.70 + i * 0.0001)
            self.gnss.write(line)
            self.gga.append(line)
            yaw = 0.001 * i
            msg = MAV.MAVLink_attitude_message(1000 + i, 0.0, 0.5, yaw, 0.0, 0.0, 0.0)
            if i % 5 == 0:
                self.udp.sendto(self.ap.heartbeat(), ("127.0.0.1", self.port))
            self.udp.sendto(self.ap.frame(msg), ("127.0.0.1", self.port))
            self.yaw.append(yaw)
            i += 1


def _deploy(endpoint: str, creds: Path, text: str, revision: int) -> tuple[dict[str, Any], float]:
    from modd.subbroker.client import request
    from modd.zenoh_auth import CredentialStore
    from modd.zenoh_session import client_settings, open_session, wait_connected
    from modd_model.signing import sign_request

    store = CredentialStore(creds)
    body = {"text": text, "format": "modd", "project_id": 1, "revision": revision}
    session = open_session(client_settings(endpoint, store.cred_file("backend")))
    try:
        assert wait_connected(session, 10)
        start = time.monotonic()
        signed = sign_request(store.deploy_key(), {**body, "deployed_by": "operator"})
        reply: dict[str, Any] = request(session, "modd/usv/deploy", signed, timeout_s=20)
        return reply, time.monotonic() - start
    finally:
        session.close()  # type: ignore[no-untyped-call]


def _by_sensor(reply: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {s["sensor"]: s for s in reply["onboard"]["sensors"]["sensors"]}


def _applied_within(reply: dict[str, Any], sent_ns: int) -> float:
    """Seconds from the deploy request to the last on-board process's answer."""
    last = max(int(r["at_ns"]) for r in reply["onboard"].values())
    return (last - sent_ns) / 1e9


def test_a_deploy_reaches_modd_sensors_and_modd_mavlink(tmp_path: Path) -> None:
    dev, run, creds = tmp_path / "dev", tmp_path / "run", tmp_path / "creds"
    dev.mkdir()
    gnss, ctd, sounder = (PtyDevice(dev / n) for n in ("gnss", "ctd", "sounder"))
    ports = {"port": free_port(), "port2": free_port()}
    zenoh = f"tcp/127.0.0.1:{free_port()}"

    def text(sensors: list[str], nav: list[str], water: list[str]) -> str:
        body = model_text([s.replace("{dev}", str(dev)) for s in sensors], nav, water)
        return body.replace("{port}", str(ports["port"])).replace("{port2}", str(ports["port2"]))

    v1 = text([GNSS, CTD1, _autopilot(False)], ["gnss.lat", "autopilot.yaw"], ["ctd.temperature"])
    model = tmp_path / "boat.modd"
    model.write_text(v1)
    env = dict(os.environ, MODD_LINK_KEY="deploy-test-link-key")
    argv = [str(BIN / "modd"), "up", str(model), "--workdir", str(run), "--credentials"]
    argv += [str(creds), "--zenoh-listen", zenoh]
    up = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
    )
    bridge_port = free_port("udp")
    feeder = Feeder(gnss, bridge_port)
    bridge: subprocess.Popen[bytes] | None = None
    try:
        wait_until(lambda: (run / "onboard" / "applied" / "sensors.json").exists(), 30, "sensors")
        with (tmp_path / "bridge.log").open("wb") as bridge_log:
            bridge = subprocess.Popen(
                [str(BIN / "modd-mavlink"), "--model", str(run / "onboard" / "model.json")]
                + ["--watch", "--connect", f"udpin:127.0.0.1:{bridge_port}"]
                + ["--ingress", f"unix:{run / 'ingress.sock'}"],
                stdout=bridge_log,
                stderr=subprocess.STDOUT,
            )
        wait_until(lambda: (run / "onboard" / "applied" / "mavlink.json").exists(), 30, "bridge")
        wait_until(lambda: (run / "logs" / "subbroker.log").exists(), 10, "subbroker log")
        wait_until(
            lambda: "config 1 running" in (run / "logs" / "subbroker.log").read_text(), 30, "config"
        )
        pid = _pid(up.pid)
        feeder.thread.start()
        ctd.write(b"12.5\r\n")
        wait_until(lambda: run_health(run).get("gnss", {}).get("values", 0) >= 3, 10, "GNSS values")

        # add: a sounder, an unplugged echo sounder, the CTD's conductivity, the pitch
        v2 = text(
            [GNSS, CTD2, SOUNDER, ECHO, _autopilot(True)],
            ["gnss.lat", "autopilot.yaw", "autopilot.pitch", "sounder.depth", "echo.depth"],
            ["ctd.temperature", "ctd.conductivity"],
        )
        sent = time.time_ns()
        reply, took = _deploy(zenoh, creds, v2, 2)
        assert reply["status"] == "ACKED", reply
        assert _applied_within(reply, sent) < 2.0, reply
        sensors = _by_sensor(reply)
        assert sensors["gnss"]["action"] == "unchanged" and sensors["gnss"]["ok"]
        assert sensors["ctd"]["action"] == "restarted" and sensors["ctd"]["state"] == "open"
        assert sensors["sounder"] == {
            "sensor": "sounder",
            "action": "started",
            "ok": True,
            "state": "open",
        }
        assert not sensors["echo"]["ok"] and "unplugged missing" in sensors["echo"]["problem"]
        assert reply["onboard"]["sensors"]["ok"] is False  # the echo sounder cannot read
        assert reply["onboard"]["mavlink"]["added"] == ["usv.autopilot.pitch"]
        print(f"deploy round trip {took:.3f} s, applied {_applied_within(reply, sent):.3f} s")
        sounder.write(nmea("SDDBT,11.48,f,3.50,M,1.91,F"))
        ctd.write(b"12.6,C=45100\r\n")
        wait_until(lambda: run_health(run).get("sounder", {}).get("values", 0) == 1, 3, "sounder")

        # remove the sounder and the pitch
        v3 = text(
            [GNSS, CTD2, _autopilot(False)],
            ["gnss.lat", "autopilot.yaw"],
            ["ctd.temperature", "ctd.conductivity"],
        )
        sent = time.time_ns()
        reply, took = _deploy(zenoh, creds, v3, 3)
        assert reply["status"] == "ACKED" and _applied_within(reply, sent) < 2.0, reply
        sensors = _by_sensor(reply)
        assert sensors["sounder"]["action"] == "stopped" and sensors["echo"]["action"] == "stopped"
        assert sensors["ctd"]["action"] == "unchanged" and reply["onboard"]["sensors"]["ok"]
        assert reply["onboard"]["mavlink"]["removed"] == ["usv.autopilot.pitch"]
        sounder.write(nmea("SDDBT,13.12,f,4.00,M,2.19,F"))  # nobody reads it now
        wait_until(lambda: "sounder" not in run_health(run), 1, "the sounder's health gone")
        time.sleep(0.5)
        assert _pid(up.pid) == pid and pid_alive(pid), "the PubBroker was restarted"
        feeder.stop.set()
        feeder.thread.join()
        time.sleep(0.5)  # the last samples reach the archive before the stop
    finally:
        feeder.stop.set()
        feeder.udp.close()
        if bridge is not None:
            bridge.send_signal(signal.SIGTERM)
            bridge.wait(30)
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
        for device in (gnss, ctd, sounder):
            device.close()
    assert up.returncode == 0, out
    assert out.count("started pubbroker") == 1, out
    archive = read_archive(run / "archive")
    got = {t: [v for _, v in samples] for t, samples in archive.items()}
    # every GGA written, read by pynmea2: not one lost across the three deploys
    expected = [pynmea2.parse(g.decode().strip(), check=True).latitude for g in feeder.gga]
    assert got["usv.gnss.lat"] == [pytest.approx(x, abs=1e-12) for x in expected]
    assert got["usv.autopilot.yaw"] == [f32(y) for y in feeder.yaw]
    assert got["usv.sounder.depth"] == [f32(3.5)]
    assert got["usv.ctd.conductivity"] == [f32(45.1)]
    assert 0 < len(got["usv.autopilot.pitch"]) < len(feeder.yaw)
    assert set(got["usv.autopilot.pitch"]) == {0.5}


def _pid(up: int) -> int:
    """The PubBroker's PID: the child of ``modd up`` that runs modd-pubbroker."""
    for child in Path(f"/proc/{up}/task/{up}/children").read_text().split():
        if b"modd-pubbroker" in Path(f"/proc/{child}/cmdline").read_bytes():
            return int(child)
    raise AssertionError("modd up runs no PubBroker")
