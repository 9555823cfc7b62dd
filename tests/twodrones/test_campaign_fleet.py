"""A campaign of three drones from one mission model (issue 44, items 1 and
6): each drone a real C++ PubBroker fed by ``modd-sim`` and its own SubBroker
(test_two_drones.start_drone), one zenoh router, the backend as a process.

One project holds the mission model and a ``Campaign`` of three vehicles
(each its PubBroker endpoint); the backend lists three drones, deploys to
the three at once (each acked by its own SubBroker, whose status then runs
that config), rolls one back alone, and subscribes to one variable of every
drone in one step (each SubBroker accepts its own topic and its values come
on that drone's stream)."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from support.loopback import (  # noqa: E402
    DEMO,
    Backend,
    Proc,
    StatusWatch,
    receive_until,
    router_and_watch,
    start_signed_in_backend,
    started,  # noqa: F401  (the fixture)
)
from test_two_drones import Drone, start_drone  # noqa: E402

ADMIN_PASSWORD = "campaign-fleet-admin-password"
NAMES = ("usv1", "usv2", "usv3")


def campaign_text(drones: list[Drone]) -> str:
    """The demo mission, once, with a vehicle per drone on its own link port."""
    vehicles = "".join(
        f'    Vehicle {d.name} "{d.name} boat" {{ channel = lake; '
        f'PubBroker("127.0.0.1":{d.link}); }}\n'
        for d in drones
    )
    return (
        DEMO.read_text()
        + 'Campaign survey "Three boats" {\n    Channel lake { rate = 100000; }\n'
        + vehicles
        + "}\n"
    )


def create_project(backend: Backend, text: str) -> int:
    """The campaign's .modd text imported as it is (the workbench's import)."""
    r = backend.request(
        "POST",
        "/projects/import",
        params={"name": "survey"},
        content=text.encode(),
    )
    assert r.status_code == 201, r.text
    return int(r.json()["id"])


@pytest.mark.timeout(150)
def test_campaign_of_three_deploys_and_subscribes_in_one_step(
    tmp_path: Path,
    started: list[Proc],  # noqa: F811
) -> None:
    with router_and_watch() as (router, watch):
        drones = [start_drone(tmp_path, n, router) for n in NAMES]
        for d in drones:
            started.extend(d.procs)
        backend = start_signed_in_backend(tmp_path, router, ADMIN_PASSWORD, started)
        for d in drones:
            watch.wait(d.name, lambda s: s["link"] == "up" and s["config_id"], 30)
        pid = create_project(backend, campaign_text(drones))
        fleet = backend.request("GET", f"/projects/{pid}/drones").json()
        assert [x["name"] for x in fleet["drones"]] == list(NAMES), fleet
        assert fleet["channels"] == {"lake": list(NAMES)}
        assert all(x["status"]["link"] == "up" for x in fleet["drones"]), fleet
        check_deploy_and_rollback(backend, watch, pid, drones)
        check_one_step_subscription(backend, pid)
        for p in started:
            assert p.alive(), f"{p.name} died:\n{p.log()}"


def _fleet_deploy(backend: Backend, pid: int, **body: Any) -> list[dict[str, Any]]:
    r = backend.request("POST", f"/projects/{pid}/fleet/deployments", json=body)
    assert r.status_code == 201, r.text
    out: list[dict[str, Any]] = r.json()
    return out


def runs_config(config: int) -> Callable[[dict[str, Any]], bool]:
    return lambda s: bool(s["config_id"] == config)


def runs_revision(revision: int) -> Callable[[dict[str, Any]], bool]:
    return lambda s: bool((s.get("deployment") or {}).get("revision") == revision)


def check_deploy_and_rollback(
    backend: Backend, watch: StatusWatch, pid: int, drones: list[Drone]
) -> None:
    records = _fleet_deploy(backend, pid)
    assert [r["drone"] for r in records] == list(NAMES)
    for r in records:
        assert r["status"] == "acked", r
        assert r["reply"]["status"] == "ACKED"
        status = watch.wait(r["drone"], runs_config(int(r["reply"]["config_id"])), 10)
        assert status["deployment"]["revision"] == 1, status
        assert status["deployment"]["project_id"] == pid, status
    # revision 2 everywhere, then usv2 alone back to revision 1
    model = backend.request("GET", f"/projects/{pid}/model").json()["model"]
    model["subscribers"][0]["periodS"] = "4"
    saved = backend.request(
        "PUT", f"/projects/{pid}/model", json={"base_revision": 1, "model": model}
    )
    assert saved.status_code in (200, 201), saved.text
    assert all(x["status"] == "acked" for x in _fleet_deploy(backend, pid))
    (back,) = _fleet_deploy(backend, pid, revision=1, drones=["usv2"])
    assert (back["drone"], back["revision"], back["status"]) == ("usv2", 1, "acked"), back
    for name, revision in (("usv1", 2), ("usv2", 1), ("usv3", 2)):
        status = watch.wait(name, runs_revision(revision), 10)
        assert status["deployment"]["project_id"] == pid
    listed = backend.request("GET", f"/projects/{pid}/deployments").json()
    assert sorted(x["drone"] for x in listed) == sorted([*NAMES, *NAMES, "usv2"])
    unknown = backend.request(
        "POST", f"/projects/{pid}/fleet/deployments", json={"drones": ["nobody"]}
    )
    assert unknown.status_code == 404 and "nobody" in unknown.text


def check_one_step_subscription(backend: Backend, pid: int) -> None:
    r = backend.request(
        "POST",
        f"/projects/{pid}/fleet/subscriptions",
        json={
            "variable": "ctd.water_temperature",
            "period_s": "2",
            "aggregation": "AVERAGE",
            "subscriber": "temp_all",
        },
    )
    assert r.status_code == 200, r.text
    answers = r.json()
    assert [(a["drone"], a["topic"], a["status"]) for a in answers] == [
        (n, f"{n}.ctd.water_temperature", "ACCEPTED") for n in NAMES
    ], answers
    assert [a["key"] for a in answers] == [f"modd/{n}/sub/temp_all" for n in NAMES]
    for name in NAMES:
        with backend.stream(name) as ws:
            ws.send('{"op": "subscribe", "subscriber": "temp_all"}')
            got = receive_until(
                ws, lambda m: m["type"] == "value" and m["data"]["subscriber"] == "temp_all", 20
            )[-1]
            assert got["data"]["topic"] == f"{name}.ctd.water_temperature", got
