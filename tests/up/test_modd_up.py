"""`modd up` runs a model locally from generated configs and stops every
process it started when it is told to stop."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_up_runs_the_brokers_and_stops_them(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model = tmp_path / "model.modd"
    port = free_port()
    model.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{port}')
    )
    up = subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model),
            "--workdir",
            str(tmp_path / "run"),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{free_port()}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        # the SubBroker planned the model and the PubBroker acknowledged its CONFIG
        wait_for(tmp_path / "run" / "logs" / "subbroker.log", "config 1 running", 30)
        assert (tmp_path / "run" / "generated" / "operator" / "pubbroker.json").is_file()
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    pids = [int(p) for p in re.findall(r"\(pid (\d+)\)", out)]
    # modd-sensors runs with no instrument in the model (issue 39): idle, it follows
    # the on-board model file, so a deploy that adds the first needs no restart
    assert len(pids) == 3, out
    assert not any(_alive(pid) for pid in pids)
    assert "stopped pubbroker" in out and "stopped subbroker" in out
    assert "stopped sensors" in out  # (SIGTERM may come before its handler: a short run)


def test_up_refuses_an_invalid_model(tmp_path: Path, modd_cmd: str) -> None:
    bad = tmp_path / "bad.modd"
    bad.write_text("Drone d { }")
    res = subprocess.run(
        [modd_cmd, "up", str(bad), "--workdir", str(tmp_path / "run")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 1 and "no PubBroker block" in res.stderr


def test_up_with_simulator_delivers_live_values(
    tmp_path: Path, modd_cmd: str, free_port: Callable[[], int], wait_for: Callable[..., None]
) -> None:
    """The demo of `make run`: modd up --simulate; values arrive on zenoh, the water
    temperature from the simulator, the latitude from its autopilot through the bridge."""
    import modd
    from modd.sim import ORIGIN_LAT
    from modd.sim.track import LEG_M, METERS_PER_DEG_LAT

    demo = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"
    model = tmp_path / "demo.modd"
    port = free_port()
    model.write_text(demo.read_text().replace('"127.0.0.1":7171', f'"127.0.0.1":{port}'))
    zenoh_port = free_port()
    up = subprocess.Popen(
        [
            modd_cmd,
            "up",
            str(model),
            "--simulate",
            "--workdir",
            str(tmp_path / "run"),
            "--zenoh-listen",
            f"tcp/127.0.0.1:{zenoh_port}",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    values: dict[str, list[float]] = {"water_temp": [], "track_lat": []}
    try:
        wait_for(tmp_path / "run" / "logs" / "subbroker.log", "config 1 running", 30)
        viewer = tmp_path / "run" / "credentials" / "viewer.cred"  # what modd up printed
        subs = {
            name: modd.subscribe(
                "usv", name, connect=f"tcp/127.0.0.1:{zenoh_port}", credentials=viewer
            )
            for name in values
        }
        deadline = time.monotonic() + 30
        while any(len(v) < 3 for v in values.values()) and time.monotonic() < deadline:
            for name, sub in subs.items():
                sample = sub.get(timeout_s=0.5)
                if sample is not None and sample.value is not None:
                    assert (
                        sample.topic
                        == {
                            "water_temp": "usv.ctd.water_temperature",
                            "track_lat": "usv.autopilot.latitude",
                        }[name]
                    )
                    values[name].append(sample.value)
        for sub in subs.values():
            sub.close()
        assert all(len(v) >= 3 for v in values.values()), f"live values within 30 s: {values}"
    finally:
        up.send_signal(signal.SIGTERM)
        out, _ = up.communicate(timeout=60)
    assert up.returncode == 0, out
    assert all(8.0 < v < 20.0 for v in values["water_temp"])  # the simulated water temperature
    # the survey's latitudes, scaled from degE7 by the bridge
    assert all(
        ORIGIN_LAT - 1e-6 <= v <= ORIGIN_LAT + LEG_M / METERS_PER_DEG_LAT + 1e-6
        for v in values["track_lat"]
    ), values
    bridge_log = (tmp_path / "run" / "logs" / "bridge.log").read_text()
    assert "autopilot accepted GLOBAL_POSITION_INT every 0.2 s" in bridge_log, bridge_log
    assert len(re.findall(r"\(pid (\d+)\)", out)) == 5, out  # + modd-sensors (the CTD)
    assert "stopped bridge (exit 0)" in out and "stopped simulator (exit 0)" in out
    assert "stopped sensors (exit 0)" in out
    assert f"credentials='{viewer}'" in out


def test_up_in_two_parts_drone_and_station(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    """`--part drone` runs the PubBroker only, `--part station` the SubBroker only (joining a
    zenoh endpoint with --zenoh-connect); together they reach the running config."""
    model = tmp_path / "model.modd"
    port = free_port()
    model.write_text(
        (scenarios_dir / "scenario1.modd")
        .read_text()
        .replace('"127.0.0.1":7171', f'"127.0.0.1":{port}')
    )
    env = {k: v for k, v in os.environ.items() if k != "MODD_LINK_KEY"}
    refused = subprocess.run(
        [modd_cmd, "up", str(model), "--part", "drone", "--workdir", str(tmp_path / "nokey")],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert refused.returncode == 1 and "MODD_LINK_KEY" in refused.stderr
    env["MODD_LINK_KEY"] = "a key both parts share"
    procs = {
        part: subprocess.Popen(
            [
                modd_cmd,
                "up",
                str(model),
                "--part",
                part,
                "--workdir",
                str(tmp_path / part),
                "--zenoh-listen",
                f"tcp/127.0.0.1:{free_port()}",
                "--zenoh-connect",
                f"tcp/127.0.0.1:{free_port()}",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=env,
        )
        for part in ("drone", "station")
    }
    outs = {}
    try:
        wait_for(tmp_path / "station" / "logs" / "subbroker.log", "config 1 running", 30)
    finally:
        for part, proc in procs.items():
            proc.send_signal(signal.SIGTERM)
            outs[part] = proc.communicate(timeout=60)[0]
    assert all(p.returncode == 0 for p in procs.values()), outs
    assert "started pubbroker" in outs["drone"] and "subbroker" not in outs["drone"]
    assert "started subbroker" in outs["station"] and "pubbroker" not in outs["station"]
    assert not (tmp_path / "station" / "logs" / "pubbroker.log").exists()
    assert not any(
        _alive(int(pid)) for out in outs.values() for pid in re.findall(r"\(pid (\d+)\)", out)
    )
