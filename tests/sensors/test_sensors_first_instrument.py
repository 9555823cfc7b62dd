"""Issue 39: ``modd up`` starts ``modd-sensors`` even when the starting model has
no instrument, so a deploy that adds the first one works without a restart. The
run starts with a model whose only topic comes from a plain publisher; a signed
deploy adds an NMEA GNSS on a pseudo-terminal; the acknowledgement says the
reader started and opened its device, its values reach the archive (read with the
official MCAP reader, the positions decoded by pynmea2 as the oracle), and the
PubBroker and modd-sensors keep their PIDs."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from pathlib import Path

import pynmea2  # type: ignore[import-untyped]
import pytest
from devices import PtyDevice, gga, run_health, wait_until
from mavlink_harness import read_archive
from modd.ports import free_port
from test_sensors_deploy import BIN, GNSS, _by_sensor, _deploy, model_text

pytestmark = pytest.mark.e2e

PLAIN = "Sensor hull measures { temperature(DEGREE_CELSIUS, float32); }"


def test_a_deploy_adds_the_first_instrument_without_a_restart(tmp_path: Path) -> None:
    dev, run, creds = tmp_path / "dev", tmp_path / "run", tmp_path / "creds"
    dev.mkdir()
    gnss = PtyDevice(dev / "gnss")
    ports = {"{port}": str(free_port()), "{port2}": str(free_port()), "{dev}": str(dev)}
    zenoh = f"tcp/127.0.0.1:{free_port()}"

    def text(sensors: list[str], topics: list[str]) -> str:
        body = model_text(sensors, topics, [], subscribed="hull.temperature")
        for k, v in ports.items():
            body = body.replace(k, v)
        return body

    model = tmp_path / "boat.modd"
    model.write_text(text([PLAIN], ["hull.temperature"]))
    env = dict(os.environ, MODD_LINK_KEY="first-instrument-test-key")
    argv = [str(BIN / "modd"), "up", str(model), "--workdir", str(run), "--credentials"]
    argv += [str(creds), "--zenoh-listen", zenoh]
    up = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env
    )
    written: list[bytes] = []
    try:
        wait_until(lambda: (run / "onboard" / "applied" / "sensors.json").exists(), 30, "sensors")
        wait_until(lambda: (run / "logs" / "subbroker.log").exists(), 10, "subbroker log")
        wait_until(
            lambda: "config 1 running" in (run / "logs" / "subbroker.log").read_text(), 30, "config"
        )
        pid = _child(up.pid, b"modd-pubbroker")
        sensors_pid = _child(up.pid, b"modd-sensors")
        reply, _ = _deploy(zenoh, creds, text([PLAIN, GNSS], ["hull.temperature", "gnss.lat"]), 2)
        assert reply["status"] == "ACKED", reply
        assert _by_sensor(reply)["gnss"] == {
            "sensor": "gnss",
            "action": "started",
            "ok": True,
            "state": "open",
        }, reply
        for i in range(5):
            written.append(gga(47.70 + i * 0.0001))
            gnss.write(written[-1])
            time.sleep(0.1)
        wait_until(lambda: run_health(run).get("gnss", {}).get("values", 0) == 5, 5, "values")
        assert _child(up.pid, b"modd-pubbroker") == pid, "the PubBroker was restarted"
        assert _child(up.pid, b"modd-sensors") == sensors_pid, "modd-sensors was restarted"
        time.sleep(0.5)  # the last samples reach the archive before the stop
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
        gnss.close()
    assert up.returncode == 0, out
    assert out.count("started sensors") == 1 and out.count("started pubbroker") == 1, out
    assert re.search(r"stopped sensors \(exit 0\)", out), out
    got = [v for _, v in read_archive(run / "archive")["usv.gnss.lat"]]
    expected = [pynmea2.parse(g.decode().strip(), check=True).latitude for g in written]
    assert got == [pytest.approx(x, abs=1e-12) for x in expected]


def _child(up: int, name: bytes) -> int:
    """The PID of the child of ``modd up`` whose command line holds ``name``."""
    for child in Path(f"/proc/{up}/task/{up}/children").read_text().split():
        if name in Path(f"/proc/{child}/cmdline").read_bytes():
            return int(child)
    raise AssertionError(f"modd up runs no {name.decode()}")
