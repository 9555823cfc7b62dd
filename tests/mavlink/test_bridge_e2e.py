"""The bridge between the simulated autopilot and a real PubBroker: the rates it
asks for, the values that reach the MCAP archive (checked against the track the
simulator follows, within MAVLink's quantisation and the time the frame took
to arrive), and the split of topics between the bridge and the simulator."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from mavlink_harness import (
    BIN,
    HERE,
    Proc,
    load_model,
    read_archive,
    start_pubbroker,
)
from modd.ports import free_port
from modd.sim.track import METERS_PER_DEG_LAT, SPEED_MS, altitude, battery, survey_pose

LAG_S = 0.5  # bound on send → receive → timestamp on a loaded 2-core machine
RUN_S = 4.0
AUTOPILOT = ("latitude", "longitude", "height", "yaw", "battery_mv", "battery_v")


@dataclass
class Run:
    archive: dict[str, list[tuple[int, Any]]]
    start: float  # the track's start, Unix seconds
    ready_ns: int  # every rate accepted by then
    bridge_log: str
    sim_log: str
    codes: dict[str, int]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Run:
    tmp = tmp_path_factory.mktemp("bridge")
    model = load_model(HERE / "boat.modd", free_port())
    broker, _local, model_json = start_pubbroker(model, tmp / "run")
    port = free_port("udp")
    start = time.time() - 195.0  # the first turn comes 5 s into the run
    procs: dict[str, Proc] = {"pubbroker": broker}
    try:
        procs["bridge"] = Proc(
            [
                str(BIN / "modd-mavlink"),
                "--model",
                str(model_json),
                "--connect",
                f"udpin:127.0.0.1:{port}",
                "--status-period",
                "1",
            ],
            tmp / "bridge.log",
        )
        procs["bridge"].wait_for("waiting for the autopilot", 20)
        procs["sim"] = Proc(
            [
                str(BIN / "modd-sim"),
                "--model",
                str(model_json),
                "--mavlink",
                f"udpout:127.0.0.1:{port}",
                "--start-time",
                repr(start),
            ],
            tmp / "sim.log",
        )
        for line in (
            "accepted ATTITUDE",
            "accepted GLOBAL_POSITION_INT",
            "accepted SYS_STATUS",
            "REFUSED WIND",
        ):
            procs["bridge"].wait_for(line, 20)
        ready_ns = time.time_ns()
        time.sleep(RUN_S)
    finally:
        codes: dict[str, int] = {
            name: procs[name].stop() for name in ("sim", "bridge", "pubbroker") if name in procs
        }
    return Run(
        read_archive(tmp / "run" / "archive"),
        start,
        ready_ns,
        procs["bridge"].log(),
        procs["sim"].log(),
        codes,
    )


def test_the_processes_stop_cleanly(run: Run) -> None:
    assert run.codes == {"sim": 0, "bridge": 0, "pubbroker": 0}, run.bridge_log
    assert "modd-mavlink: stopped" in run.bridge_log


def test_the_autopilot_gets_the_rates_the_model_needs(run: Run) -> None:
    # nav publishes every 0.1 s, power every 0.5 s (boat.modd)
    asked = dict(re.findall(r"SET_MESSAGE_INTERVAL (\w+) (\d+) us", run.sim_log))
    assert asked == {
        "GLOBAL_POSITION_INT": "100000",
        "ATTITUDE": "100000",
        "SYS_STATUS": "500000",
        "WIND": "500000",
    }, run.sim_log
    assert "WIND 500000 us: MAV_RESULT_DENIED" in run.sim_log
    assert "REFUSED WIND every 0.5 s: MAV_RESULT_DENIED" in run.bridge_log


@pytest.mark.parametrize(("topic", "hz"), [("latitude", 10.0), ("yaw", 10.0), ("battery_mv", 2.0)])
def test_the_observed_rate_is_the_rate_asked(run: Run, topic: str, hz: float) -> None:
    t0, t1 = run.ready_ns + 300_000_000, run.ready_ns + int((RUN_S - 0.3) * 1e9)
    n = sum(1 for ts, _ in run.archive[f"boat.autopilot.{topic}"] if t0 <= ts < t1)
    observed = n / ((t1 - t0) / 1e9)
    assert abs(observed - hz) <= 0.2 * hz + 0.5, (topic, observed)


def _near_track(
    value: float, ts: int, start: float, quantum: float, f: Callable[[float], float], speed: float
) -> bool:
    """Whether value is f(t) for some t in [receive - LAG_S, receive], within quantum."""
    t = ts / 1e9 - start
    samples = [f(t - LAG_S * k / 10) for k in range(11)]
    lo, hi = min(samples), max(samples)
    return lo - quantum - speed * LAG_S / 10 <= value <= hi + quantum + speed * LAG_S / 10


def test_archived_values_follow_the_simulated_track(run: Run) -> None:
    a = {t.rsplit(".", 1)[1]: v for t, v in run.archive.items() if t.startswith("boat.autopilot")}
    assert set(a) == set(AUTOPILOT), sorted(run.archive)
    deg_per_s = SPEED_MS / METERS_PER_DEG_LAT / math.cos(math.radians(47.7))
    checks: dict[str, tuple[Callable[[float], float], float, float]] = {
        "latitude": (lambda t: survey_pose(t).lat, 0.5e-7, deg_per_s),
        "longitude": (lambda t: survey_pose(t).lon, 0.5e-7, deg_per_s),
        # alt in mm, then * 0.001 + 10 (the offset of boat.modd)
        "height": (lambda t: altitude(t) + 10.0, 0.0005 + 1e-9, 0.1),
        "yaw": (lambda t: survey_pose(t).yaw, 1e-6, 0.0),
        "battery_mv": (lambda t: battery(t)[0] * 1000, 0.5, 0.3),
        "battery_v": (lambda t: battery(t)[0], 0.5e-3, 0.3e-3),
    }
    for name, (f, quantum, speed) in checks.items():
        assert len(a[name]) >= 5, name
        bad = [(ts, v) for ts, v in a[name] if not _near_track(v, ts, run.start, quantum, f, speed)]
        assert not bad, (name, bad[:3], [f(ts / 1e9 - run.start) for ts, _ in bad[:3]])
    assert all(isinstance(v, int) for _, v in a["battery_mv"])
    # the same SYS_STATUS frame gives both battery topics, scaled by 1e-3
    assert [ts for ts, _ in a["battery_mv"]] == [ts for ts, _ in a["battery_v"]]
    assert all(
        abs(v - mv * 1e-3) < 1e-9
        for (_, mv), (_, v) in zip(a["battery_mv"], a["battery_v"], strict=True)
    )


def test_autopilot_topics_come_only_through_the_bridge(run: Run) -> None:
    # the bridge's last status line counts every sample it published
    samples = int(re.findall(r"samples (\d+)", run.bridge_log)[-1])
    archived = sum(len(v) for t, v in run.archive.items() if t.startswith("boat.autopilot"))
    assert archived == samples > 0, run.bridge_log
    # the simulator still publishes the scientific sensor itself, at 2 Hz
    assert len(run.archive["boat.ctd.water_temperature"]) >= 2 * RUN_S - 1
    assert "boat.wind.speed" not in run.archive  # never streamed (refused)
    assert re.search(r"status: mapped \d+ \(samples \d+\), unknown 0, bad 0", run.bridge_log)


def test_bridge_refuses_a_model_it_cannot_map(tmp_path: Path) -> None:
    import subprocess

    text = (HERE / "boat.modd").read_text().replace("ATTITUDE.yaw", "ATTITUDE.heading")
    (tmp_path / "bad.modd").write_text(text)
    res = subprocess.run(
        [str(BIN / "modd-mavlink"), "--model", str(tmp_path / "bad.modd")],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert res.returncode == 1
    assert (
        "/drone/sensors/0/variables/3/source/field: ATTITUDE has no field heading" in res.stderr
    ), res.stderr
