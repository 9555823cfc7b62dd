"""`modd up` of a campaign (issue 44): scenario 1's model flown by three vehicles,
brought up in one command with --simulate. Each drone's values arrive on its own
zenoh key (`modd/<drone>/sub/*`, read raw at the campaign's one router), each equal
to the aggregate recomputed from that drone's archive with the official `mcap`
reader; a process of one vehicle that stops is restarted while the others run;
SIGTERM stops every process (checked by PID). A vehicle whose process keeps dying
stops the whole campaign, named; one that cannot start fails the up before anything
runs; no process is left either way."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from modd.subbroker.payload import DeliveredValue  # noqa: E402
from subbroker_harness import check_against_archive, read_archive  # noqa: E402
from support.processes import pid_alive  # noqa: E402

VEHICLES = ("usv1", "usv2", "usv3")
SUBSCRIBERS = ("sub_3", "sub_5")  # accel_x 0.25 s AVERAGE, accel_z 0.25 s MIN
PIDS = re.compile(r"started (\S+) \(pid (\d+)\)")


def campaign_model(scenarios_dir: Path, tmp: Path, free_port: Callable[[], int]) -> Path:
    """Scenario 1 (its subscribers delivered on zenoh only: no endpoint of theirs) as the
    mission of three vehicles, each its own PubBroker on a free loopback port."""
    text = (scenarios_dir / "scenario1.modd").read_text()
    text = re.sub(r'"127\.0\.0\.1":7[34]\d\d, ', "", text)  # publisher and subscriber endpoints
    text = text.replace('"127.0.0.1":7171', f'"127.0.0.1":{free_port()}')
    vehicles = "".join(
        f'    Vehicle {v} "{v} boat" {{ PubBroker("127.0.0.1":{free_port()}); }}\n'
        for v in VEHICLES
    )
    model = tmp / "campaign.modd"
    model.write_text(text + f'Campaign lake "Three boats" {{\n{vehicles}}}\n')
    return model


def raw_values(
    endpoint: str, viewer: Path, until: Callable[[dict[str, list[DeliveredValue]]], bool]
) -> dict[str, list[DeliveredValue]]:
    """Every delivered value put on `modd/*/sub/*` at the router, by key, until ``until``
    holds (40 s at most)."""
    from modd.zenoh_session import client_settings, open_session

    got: dict[str, list[DeliveredValue]] = {}
    session = open_session(client_settings(endpoint, viewer))
    session.declare_subscriber(
        "modd/*/sub/*",
        lambda s: got.setdefault(str(s.key_expr), []).append(
            DeliveredValue.from_json(s.payload.to_bytes())
        ),
    )
    deadline = time.monotonic() + 40
    while not until(got) and time.monotonic() < deadline:
        time.sleep(0.2)
    session.close()  # type: ignore[no-untyped-call]
    return {k: list(v) for k, v in got.items()}


def test_a_campaign_of_three_comes_up_in_one_command_and_goes_down_on_sigterm(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
    wait_for: Callable[..., None],
) -> None:
    model = campaign_model(scenarios_dir, tmp_path, free_port)
    run, endpoint = tmp_path / "run", f"tcp/127.0.0.1:{free_port()}"
    out_path = tmp_path / "up.out"
    argv = [modd_cmd, "up", str(model), "--simulate", "--workdir", str(run)]
    with out_path.open("w") as out:
        up = subprocess.Popen(
            [*argv, "--zenoh-listen", endpoint], stdout=out, stderr=subprocess.STDOUT
        )
    pids: list[int] = []
    try:
        for v in VEHICLES:
            wait_for(run / v / "logs" / "subbroker.log", "config 1 running", 60)
        keys = [f"modd/{v}/sub/{s}" for v in VEHICLES for s in SUBSCRIBERS]
        values = raw_values(
            endpoint,
            run / "credentials" / "viewer.cred",
            lambda got: all(len(got.get(k, [])) >= 8 for k in keys),
        )
        text = out_path.read_text()
        for v in VEHICLES:  # one status line per drone
            assert f"modd up: drone {v} (all) running" in text, text
        pids = [int(p) for _, p in PIDS.findall(text)]
        # a process of one vehicle stops: restarted, the other vehicles untouched
        first = {name: int(p) for name, p in PIDS.findall(text)}
        os.kill(first["usv2/pubbroker"], signal.SIGTERM)
        wait_for(out_path, "restarted usv2/pubbroker", 20)
        assert all(pid_alive(first[f"{v}/pubbroker"]) for v in ("usv1", "usv3"))
    finally:
        up.send_signal(signal.SIGTERM)
        up.wait(90)
    text = out_path.read_text()
    assert up.returncode == 0, text
    pids = [int(p) for p in re.findall(r"\(pid (\d+)\)", text)]
    # the station router, and per vehicle PubBroker, SubBroker, sensors, bridge, simulator;
    # the restarted PubBroker
    assert len(pids) == 1 + 5 * len(VEHICLES) + 1, text
    assert not [p for p in pids if pid_alive(p)], text
    for key in keys:
        assert len(values.get(key, [])) >= 8, (key, {k: len(v) for k, v in values.items()})
    assert {k.split("/")[1] for k in values} == set(VEHICLES), sorted(values)
    for v in VEHICLES:
        mine = {k: vals for k, vals in values.items() if k.startswith(f"modd/{v}/sub/")}
        for k, vals in mine.items():  # on its own key, its own topics and identity
            assert all(x.topic.startswith(f"{v}.accelerometer.") for x in vals), (k, vals[0])
            assert all(x.drone in (v, None) for x in vals), (k, vals[0])
        # float32 values read back as float32: the vehicle's own model, as generated
        archive = read_archive(
            run / v / "archive", run / v / "generated" / "operator" / "model.json"
        )
        assert check_against_archive(mine, archive) >= 16


def test_a_vehicle_that_cannot_start_fails_the_up_and_leaves_nothing(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
) -> None:
    """--part station without the link key: the campaign's router had started, the first
    vehicle cannot: the up fails naming it, and the router is stopped. An unknown
    --vehicle is refused with the campaign's vehicles."""
    model = campaign_model(scenarios_dir, tmp_path, free_port)
    env = {k: v for k, v in os.environ.items() if k != "MODD_LINK_KEY"}
    base = [modd_cmd, "up", str(model), "--workdir", str(tmp_path / "run")]
    res = subprocess.run(
        [*base, "--part", "station", "--zenoh-listen", f"tcp/127.0.0.1:{free_port()}"],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 1, res
    assert "modd up: vehicle usv1: --part station needs the link key" in res.stderr, res.stderr
    started = [int(p) for p in re.findall(r"\(pid (\d+)\)", res.stdout)]
    assert started and not [p for p in started if pid_alive(p)], res.stdout
    res = subprocess.run(
        [*base, "--vehicle", "usv2", "--vehicle", "usv9"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert res.returncode == 1
    assert "--vehicle usv9: the campaign has no such vehicle (usv1, usv2, usv3)" in res.stderr
    assert "started" not in res.stdout  # nothing started


def test_a_vehicle_that_keeps_dying_stops_the_whole_campaign_named(
    scenarios_dir: Path,
    tmp_path: Path,
    modd_cmd: str,
    free_port: Callable[[], int],
) -> None:
    """usv2's PubBroker exits at once every time (a wrapper fails for usv2 alone): it is
    restarted per the policy while usv1 and usv3 run, then the run gives up, naming usv2,
    and every process of every vehicle is stopped (exit 1)."""
    from modd_launch.drone import pubbroker_binary

    wrapper = tmp_path / "pubbroker"
    wrapper.write_text(
        '#!/bin/sh\ncase "$*" in */usv2/*) echo "usv2 fails" >&2; exit 3;; esac\n'
        f'exec {pubbroker_binary()} "$@"\n'
    )
    wrapper.chmod(0o755)
    model = campaign_model(scenarios_dir, tmp_path, free_port)
    argv = [modd_cmd, "up", str(model), "--workdir", str(tmp_path / "run")]
    res = subprocess.run(
        [*argv, "--zenoh-listen", f"tcp/127.0.0.1:{free_port()}"],
        env={**os.environ, "MODD_PUBBROKER": str(wrapper)},
        capture_output=True,
        text=True,
        timeout=120,
    )
    out = res.stdout + res.stderr
    assert res.returncode == 1, out
    assert "restarted usv2/pubbroker (pid" in out and "restart 5 of at most 5" in out, out
    assert "usv2/pubbroker exited (3)" in out and "stopping the run" in out, out
    assert "modd up: vehicle usv2 failed; every drone of campaign lake was stopped" in out
    assert "restarted usv1/" not in out and "restarted usv3/" not in out, out
    pids = [int(p) for p in re.findall(r"\(pid (\d+)\)", out)]
    assert len(pids) == 1 + 3 * len(VEHICLES) + 5, out  # router, 3 a vehicle, 5 restarts
    assert not [p for p in pids if pid_alive(p)], out
    for v in ("usv1", "usv3"):
        assert f"stopped {v}/pubbroker (exit 0)" in out, out
