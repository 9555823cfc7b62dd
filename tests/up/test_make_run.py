"""`make run`'s main job (scripts/run.sh, which `make run` calls after set-up
and build): the demo drone simulated locally and the workbench, with the demo
project loaded and deployed. Checked as a user sees it: the page, the login
printed, the deployment acked, live values over the WebSocket and the 3D track;
then SIGTERM stops every process it started, and a second start on the same
data keeps the login and adds no revision."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import pytest
from modd.sim import LEG_M, METERS_PER_DEG_LAT, ORIGIN_LAT
from websockets.sync.client import connect

from .conftest import FreePort, WaitFor

REPO = Path(__file__).resolve().parents[2]
LIVE_TIMEOUT_S = 90.0


def start(
    data: Path, port: int, zenoh_port: int, run: int, foxglove_port: int = 0, replay_port: int = 0
) -> tuple[subprocess.Popen[bytes], Path]:
    log = data.parent / f"run-{run}.log"
    env = {
        **os.environ,
        "MODD_PORT": str(port),
        "MODD_ZENOH_PORT": str(zenoh_port),
        "MODD_DATA": str(data),
        "MODD_FOXGLOVE_PORT": str(foxglove_port),
        "MODD_FOXGLOVE_REPLAY_PORT": str(replay_port),
    }
    with log.open("ab") as out:
        proc = subprocess.Popen(
            ["bash", str(REPO / "scripts" / "run.sh")],
            cwd=REPO,
            env=env,
            stdout=out,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
    return proc, log


def stop(proc: subprocess.Popen[bytes], log: Path) -> None:
    """SIGTERM to run.sh; it must stop every process it started, by PID."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            raise AssertionError(f"run.sh did not stop on SIGTERM:\n{log.read_text()}") from None


def api(url: str, token: str | None = None, body: Any = None) -> Any:
    req = urllib.request.Request(
        url,
        data=None if body is None else json.dumps(body).encode(),
        headers={"Content-Type": "application/json"},
    )
    if token:
        req.add_header("Authorization", f"Bearer {token}")
    with urllib.request.urlopen(req, timeout=10) as resp:
        return json.loads(resp.read())


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # A zombie is dead too (its parent has not reaped it yet).
    stat = Path(f"/proc/{pid}/stat").read_text()
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def check_zenoh_is_closed(data: Path, zport: int, log: Path) -> None:
    """The SubBroker's zenoh endpoint refuses anonymous and wrong-password
    clients, the viewer reads values but cannot deploy; credentials are 0600
    files, named in the output and never printed."""
    from modd.subbroker.client import NoReply, request
    from modd.zenoh_auth import Credentials, read_credentials
    from modd.zenoh_session import client_settings, open_session

    endpoint = f"tcp/127.0.0.1:{zport}"
    creds = data / "credentials"
    out = log.read_text()
    assert f"need credentials: {creds / 'viewer.cred'}" in out
    for name in ("viewer.cred", "backend.cred", "subbroker.cred", "deploy.key", "users"):
        assert (creds / name).stat().st_mode & 0o777 == 0o600, name
        if name.endswith(".cred"):
            assert read_credentials(creds / name).password not in out
    # the data directory and the backend's log are the user's alone (the log
    # was 0644 in a 0755 directory: requests, user names for every local user)
    assert data.stat().st_mode & 0o077 == 0, oct(data.stat().st_mode)
    assert (data / "backend.log").stat().st_mode & 0o077 == 0
    for who in (None, Credentials("viewer", "wrong")):
        with pytest.raises(ValueError, match="cannot open"):
            open_session(client_settings(endpoint, who))
    viewer = open_session(client_settings(endpoint, creds / "viewer.cred"))
    try:
        with pytest.raises(NoReply):
            request(viewer, "modd/usv/deploy", {"text": ""}, timeout_s=1)
    finally:
        viewer.close()  # type: ignore[no-untyped-call]


def check_foxglove_live(base: str, token: str, log: Path) -> None:
    """A Foxglove client (@foxglove/ws-protocol, as Foxglove and Lichtblick
    speak it) on `make run`'s live server gets values of every subscriber of
    the demo model, its link status and its position (docs/ecosystem.md)."""
    sys.path.insert(0, str(REPO / "tests" / "ecosystem"))
    from ecosystem_support import node_json
    from modd_model.io import load_model

    port = base.rsplit(":", 1)[1]
    assert f"Foxglove/Lichtblick live at ws://127.0.0.1:{port}/foxglove/live" in log.read_text()
    model = load_model(REPO / "metamodel" / "examples" / "demo.modd")
    req = urllib.request.Request(
        f"{base}/api/foxglove/links",
        data=b"",
        method="POST",
        headers={"Authorization": f"Bearer {token}"},
    )
    with urllib.request.urlopen(req, timeout=30) as resp:
        live = json.loads(resp.read())["live"]
    # 6 s: every demo subscriber's period is at most 2 s
    report = node_json("foxglove_client.cjs", live, "6", timeout=60)
    assert report["protocol"] == "foxglove.sdk.v1" and not report["errors"], report["errors"]
    got = {
        t.split("/")[2] for t, msgs in report["messages"].items() if t.startswith("/usv/") and msgs
    }
    expected = {s["name"] for s in model["subscribers"]} | {"link", "position"}
    assert expected <= got, f"no Foxglove values for {sorted(expected - got)}"
    lat = report["messages"]["/usv/track_lat"][-1]["msg"]
    assert lat["aggregation"] == "LAST" and lat["value"] >= ORIGIN_LAT - 1e-6, lat


def check_foxglove_replay(base: str, token: str) -> None:
    """Archives panel > Replay in Foxglove on the archive the drone is
    writing: a Foxglove client seeks into it and plays from there, in order,
    every value equal to the archive's (read by the Python MCAP reader)."""
    from ecosystem_support import node_json

    files = api(f"{base}/api/drones/usv/archives", token)
    name = files[-1]["name"]
    req = urllib.request.Request(
        f"{base}/api/drones/usv/archives/{name}/replay",
        data=b"{}",
        method="POST",
        headers={"Content-Type": "application/json", "Authorization": f"Bearer {token}"},
    )
    with urllib.request.urlopen(req, timeout=30) as resp:
        info = json.loads(resp.read())
    assert (
        info["url"].startswith(f"ws://{base[7:]}/foxglove/replay?ticket=")
        and "usv.ctd.water_temperature" in info["topics"]
    ), info
    seek = (info["start_ns"] + info["end_ns"]) // 2
    report = node_json(
        "foxglove_client.cjs", info["url"], "3", "--seek", str(seek), "--after", "1", timeout=30
    )
    assert not report["errors"] and int(report["playbackStates"][0]["currentTime"]) == seek
    temps = report["messages"]["usv.ctd.water_temperature"]
    times = [int(m["logTime"]) for m in temps]
    assert times and times[0] >= seek and times == sorted(times), times[:5]
    series = api(
        f"{base}/api/drones/usv/archives/{name}/series?topic=usv.ctd.water_temperature"
        f"&start_ns={seek}&max_points=100000",
        token,
    )
    archived = {t: v for t, v in series["points"]}
    assert all(archived[int(m["logTime"])] == m["msg"]["value"] for m in temps)


def test_make_run_serves_the_demo_live_and_stops(
    tmp_path: Path, free_port: FreePort, wait_for: WaitFor
) -> None:
    data = tmp_path / "data"
    port, zport, fport, rport = free_port(), free_port(), free_port(), free_port()
    base = f"http://127.0.0.1:{port}"
    t0 = time.monotonic()
    proc, log = start(data, port, zport, 1, fport, rport)
    try:
        wait_for(log, "modd: Ctrl-C to stop", 240)
        out = log.read_text()
        assert "deployed revision 1 to drone 'usv' (acked)" in out, out
        password = (data / "admin-password").read_text().strip()
        assert f"login 'admin', password '{password}'" in out
        assert f"workbench at {base}/" in out
        # the URL and login first (before the deploy's lines), in at most 8 lines
        said = [line for line in out.splitlines() if not line.startswith("modd: building")]
        assert said[0].startswith("modd: workbench at") and "login 'admin'" in said[1], out
        assert len(said[: said.index("modd: Ctrl-C to stop") + 1]) <= 8, out

        with urllib.request.urlopen(base + "/", timeout=10) as resp:
            assert b'<div id="root">' in resp.read()  # the built frontend, not the API only
        token = api(base + "/api/auth/login", body={"username": "admin", "password": password})[
            "token"
        ]
        projects = api(base + "/api/projects", token)
        assert [(p["name"], p["head_revision"]) for p in projects] == [("demo", 1)]
        deployments = api(f"{base}/api/projects/{projects[0]['id']}/deployments", token)
        assert [d["status"] for d in deployments] == ["acked"]

        # Live values through the workbench: latitude from the simulated
        # autopilot over MAVLink (scaled from degE7 by the bridge), water
        # temperature from a scientific sensor.
        seen: dict[str, float] = {}
        ws_url = f"ws://127.0.0.1:{port}/api/drones/usv/stream"
        with connect(ws_url, open_timeout=10) as ws:
            ws.send(json.dumps({"op": "auth", "token": token}))
            for sub in ("track_lat", "water_temp"):
                ws.send(json.dumps({"op": "subscribe", "subscriber": sub}))
            deadline = time.monotonic() + LIVE_TIMEOUT_S
            while len(seen) < 2 and time.monotonic() < deadline:
                msg = json.loads(ws.recv(timeout=LIVE_TIMEOUT_S))
                if msg["type"] == "value":
                    seen[msg["subscriber"]] = float(msg["data"]["value"])
        assert set(seen) == {"track_lat", "water_temp"}, f"live values: {seen}\n{log.read_text()}"
        print(f"first live values {time.monotonic() - t0:.1f} s after make run's start")
        assert ORIGIN_LAT - 1e-6 <= seen["track_lat"] <= ORIGIN_LAT + LEG_M / METERS_PER_DEG_LAT
        assert 5.0 < seen["water_temp"] < 20.0

        scene = api(base + "/api/scene", token)
        assert scene["url"] == "/scene/"  # proxied on the workbench's origin, behind the session
        page = urllib.request.Request(
            base + "/scene/", headers={"Authorization": f"Bearer {token}"}
        )
        with urllib.request.urlopen(page, timeout=30) as resp:
            assert "'sha256-" in resp.headers["Content-Security-Policy"]
        with pytest.raises(urllib.error.HTTPError):  # no session, no scene
            urllib.request.urlopen(base + "/scene/", timeout=30)
        track = {d["drone"]: d for d in scene["drones"]}
        assert track["usv"]["points"] > 0, scene

        check_zenoh_is_closed(data, zport, log)
        check_foxglove_live(base, token, log)
        check_foxglove_replay(base, token)
    finally:
        stop(proc, log)
    out = log.read_text()
    assert out.rstrip().endswith("modd: stopped"), out
    pids = [int(p) for p in re.findall(r"started \w+ \(pid (\d+)\)", (data / "up.log").read_text())]
    assert len(pids) >= 4, out  # PubBroker, SubBroker, simulator, MAVLink bridge
    assert [p for p in pids if alive(p)] == []
    with pytest.raises(OSError):  # nothing serves the workbench any more
        urllib.request.urlopen(base + "/", timeout=2)

    # Again on the same data: the same login, and the project kept as the user left it
    # (no new revision, the stock model not loaded over it).
    proc, log = start(data, port, zport, 2)
    try:
        wait_for(log, "modd: Ctrl-C to stop", 240)
        again = log.read_text()
        assert f"password '{password}'" in again
        assert "project 'demo' (id 1) exists: kept as it is, running revision 1" in again
        assert "not resumed" not in again  # modd up's note on the kept deployment: in its log
    finally:
        stop(proc, log)
