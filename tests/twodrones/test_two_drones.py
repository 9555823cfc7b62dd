"""Two drones, one zenoh router, one workbench: each drone (a C++ PubBroker fed
by ``modd-sim``, and its SubBroker) has its own model, link key, streams and
deploys. The router is a Python zenoh session in router mode in this test; the
SubBrokers join it as clients and the backend (``modd-backend``, a process) as
a peer, everything on loopback and stopped by PID."""

from __future__ import annotations

import re
import secrets
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support.loopback import (  # noqa: E402
    DEMO,
    VENV_BIN,
    Backend,
    Proc,
    StatusWatch,
    free_port,
    receive_until,
    router_and_watch,
    start_client_subbroker,
    start_pubbroker,
    start_signed_in_backend,
    started,  # noqa: F401  (the fixture)
)

ADMIN_PASSWORD = "two-drones-admin-password"


@dataclass
class Drone:
    name: str
    model_path: Path
    model: dict[str, Any]
    link: int
    ingress: int
    key: str
    procs: list[Proc]

    def subscribers(self) -> set[str]:
        return {s["name"] for s in self.model["subscribers"]}


def drone_model(tmp: Path, name: str, extra_subscriber: str | None) -> tuple[Path, int, int]:
    """The demo mission flown by drone ``name``, on free link and ingress ports
    (its topics are named after the drone), with an extra subscriber if asked."""
    link, ingress = free_port(), free_port()
    text = DEMO.read_text()
    text = re.sub(r"Drone usv \"[^\"]*\"", f'Drone {name} "{name} boat"', text)
    text = text.replace('"usv.', f'"{name}.')
    text = text.replace('"127.0.0.1":7171', f'"127.0.0.1":{link}')
    text = text.replace('"127.0.0.1":7373', f'"127.0.0.1":{ingress}')
    if extra_subscriber:
        text = text.replace(
            "Subscriptions {",
            "Subscriptions {\n    Subscriber "
            f'{extra_subscriber}("{name}.ctd.conductivity", 0.5, MAX);',
            1,
        )
    path = tmp / f"{name}.modd"
    path.write_text(text)
    return path, link, ingress


def start_drone(tmp: Path, name: str, router: str, extra_subscriber: str | None = None) -> Drone:
    d = tmp / name
    d.mkdir()
    path, link, ingress = drone_model(d, name, extra_subscriber)
    key = secrets.token_hex(16)
    key_file = d / "link.key"
    key_file.write_text(key)
    drone = Drone(name, path, load_model(path), link, ingress, key, [])
    env = {"MODD_LINK_KEY": "not-this-drone's"}  # each side reads its own key file
    drone.procs.append(
        start_pubbroker(
            d,
            path,
            link,
            ingress,
            tag=f"{name}-pubbroker",
            link={"host": "127.0.0.1", "port": link, "key": f"file:{key_file}"},
        )
    )
    drone.procs.append(
        Proc(
            f"{name}-sim",
            [
                str(VENV_BIN / "modd-sim"),
                "--model",
                str(path),
                "--ingress",
                f"tcp:127.0.0.1:{ingress}",
            ],
            d / f"{name}-sim.log",
            env=env,
        )
    )
    drone.procs.append(start_client_subbroker(d, f"{name}-subbroker", path, link, key_file, router))
    return drone


def deploy(backend: Backend, project: int) -> dict[str, Any]:
    r = backend.request("POST", f"/projects/{project}/deployments", json={})
    assert r.status_code == 201, r.text
    record: dict[str, Any] = r.json()
    assert record["status"] == "acked", record
    return record


def values(messages: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [m for m in messages if m["type"] == "value"]


@pytest.mark.timeout(90)
def test_two_drones_have_their_own_deploys_and_streams(
    tmp_path: Path,
    started: list[Proc],  # noqa: F811
) -> None:
    with router_and_watch() as (router, watch):
        usv = start_drone(tmp_path, "usv", router)
        started.extend(usv.procs)
        asv = start_drone(tmp_path, "asv", router, extra_subscriber="only_asv")
        started.extend(asv.procs)
        backend = start_signed_in_backend(tmp_path, router, ADMIN_PASSWORD, started)
        for d in (usv, asv):
            watch.wait(d.name, lambda s: s["link"] == "up" and s["config_id"], 30)
        check_deploys(backend, watch, usv, asv)
        check_streams(backend, usv, asv)
        for p in started:
            assert p.alive(), f"{p.name} died:\n{p.log()}"


def check_deploys(backend: Backend, watch: StatusWatch, usv: Drone, asv: Drone) -> None:
    """A deploy reaches its own drone's SubBroker and leaves the other's config alone."""
    projects = {}
    for d in (usv, asv):
        r = backend.request(
            "POST", "/projects", json={"name": f"{d.name} mission", "model": {"model": d.model}}
        )
        assert r.status_code == 201, r.text
        projects[d.name] = r.json()["id"]
    for d, other in ((usv, asv), (asv, usv)):
        before = watch.wait(other.name, lambda s: s["link"] == "up", 10)
        record = deploy(backend, projects[d.name])
        assert record["drone"] == d.name, record
        config_id = record["reply"]["config_id"]

        def running(s: dict[str, Any], c: int = config_id) -> bool:
            return bool(s["config_id"] == c)

        watch.wait(d.name, running, 10)
        time.sleep(1.0)  # two status periods of the other SubBroker
        after = watch.get(other.name)
        assert after is not None
        assert (after["config_id"], after["epoch_ns"]) == (
            before["config_id"],
            before["epoch_ns"],
        ), (before, after)
        assert set(after["routes"]) == set(before["routes"])
    for d in (usv, asv):
        listed = backend.request("GET", f"/projects/{projects[d.name]}/deployments").json()
        assert [x["drone"] for x in listed] == [d.name], listed


def check_streams(backend: Backend, usv: Drone, asv: Drone) -> None:
    """Each drone's stream carries that drone's values and status, nothing of the other."""
    with backend.stream("usv") as ws_usv, backend.stream("asv") as ws_asv:
        for ws in (ws_usv, ws_asv):
            for sub in ("sub_5", "water_temp", "only_asv"):
                ws.send(f'{{"op": "subscribe", "subscriber": "{sub}"}}')
        got: dict[str, list[dict[str, Any]]] = {}
        wanted = {"usv": {"sub_5", "water_temp"}, "asv": {"sub_5", "water_temp", "only_asv"}}
        for d, ws in ((usv, ws_usv), (asv, ws_asv)):
            msgs: list[dict[str, Any]] = []

            def enough(
                m: dict[str, Any],
                msgs: list[dict[str, Any]] = msgs,
                want: set[str] = wanted[d.name],
            ) -> bool:
                msgs.append(m)
                return want <= {v["subscriber"] for v in values(msgs)} and any(
                    x["type"] == "status" for x in msgs
                )

            receive_until(ws, enough, 20)
            got[d.name] = msgs
    for d in (usv, asv):
        vals = values(got[d.name])
        assert {v["subscriber"] for v in vals} <= d.subscribers(), vals
        assert all(v["data"]["topic"].startswith(f"{d.name}.") for v in vals), vals
        statuses = [m["data"]["drone"] for m in got[d.name] if m["type"] == "status"]
        assert statuses and set(statuses) == {d.name}
    assert "only_asv" not in {v["subscriber"] for v in values(got["usv"])}
