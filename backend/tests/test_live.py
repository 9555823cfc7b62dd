"""Deploy and live streams against the real base station: the C++ PubBroker
(build/bin/modd-pubbroker), the SubBroker (modd-subbroker) and a publisher,
all on loopback, started and stopped by PID (station.py). The backend joins
the SubBroker's zenoh endpoint as a peer, as in the embedded default."""

from __future__ import annotations

import io
import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app
from modd_contracts.schema import validate
from modd_model import load_model
from starlette.testclient import WebSocketTestSession

from .conftest import ADMIN_PASSWORD, Headers, login
from .station import HEALTH, Station

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Station]:
    """PubBroker + SubBroker + publishers for the demo mission: scenario 1
    plus position, attitude and water probes."""
    model = load_model(DEMO)
    st = Station(tmp_path_factory.mktemp("station"), model)
    try:
        st.start()
        yield st
    finally:
        st.stop()


@pytest.fixture(scope="module")
def live(station: Station, tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("backend"),
        zenoh_connect=(station.zenoh,),
        zenoh_credentials=station.credentials.cred_file("backend"),
        deploy_key_file=station.credentials.deploy_key_file,
        initial_admin_password=ADMIN_PASSWORD,
        deploy_timeout_s=5.0,
        archive_dir=station.archive.parent,
        scene_port=0,
    )
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        yield c


@pytest.fixture(scope="module")
def people(live: TestClient) -> dict[str, Headers]:
    admin = login(live, "admin", ADMIN_PASSWORD)
    out = {"admin": admin}
    for role in ("operator", "scientist", "designer", "integrator"):
        live.post(
            "/api/users",
            headers=admin,
            json={"username": role, "password": f"{role}-password", "roles": [role]},
        )
        out[role] = login(live, role, f"{role}-password")
    return out


def _receive_until(
    ws: WebSocketTestSession, pred: Callable[[dict[str, Any]], bool], limit: int = 500
) -> dict[str, Any]:
    for _ in range(limit):
        msg: dict[str, Any] = ws.receive_json()
        if pred(msg):
            return msg
    raise AssertionError("the expected message never came")


def test_deploy_is_acked_recorded_and_diffed(
    live: TestClient, people: dict[str, Headers], station: Station
) -> None:
    admin, operator = people["admin"], people["operator"]
    pid = live.post(
        "/api/projects", headers=admin, json={"name": "mission", "model": {"model": station.model}}
    ).json()["id"]
    before = live.get(f"/api/projects/{pid}/deployed-diff", headers=operator).json()
    assert before["deployed"] is None and before["changes"]
    r = live.post(f"/api/projects/{pid}/deployments", headers=operator, json={})
    assert r.status_code == 201, r.text
    record = r.json()
    assert record["status"] == "acked", record
    assert record["reply"]["status"] == "ACKED"
    assert record["reply"]["buffer_sizes"]["usv.accelerometer.accel_z"] == 6
    listed = live.get(f"/api/projects/{pid}/deployments", headers=people["scientist"]).json()
    assert [d["id"] for d in listed] == [record["id"]]
    same = live.get(f"/api/projects/{pid}/deployed-diff", headers=operator).json()
    assert same["changes"] == [] and same["same_project"]
    # a new project starts from the running drone's link ends
    running = live.get("/api/running-drones", headers=people["designer"]).json()
    usv = next(d for d in running if d["drone"] == "usv")
    assert (usv["project_id"], usv["revision"]) == (pid, 1)
    assert usv["pub_broker"] == station.model["pubBroker"]["endpoint"]
    assert usv["sub_broker"] == station.model["subBroker"]["endpoint"]
    model = live.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    model["subscribers"][0]["periodS"] = "4"
    live.put(f"/api/projects/{pid}/model", headers=admin, json={"base_revision": 1, "model": model})
    changed = live.get(f"/api/projects/{pid}/deployed-diff", headers=operator).json()
    assert changed["changes"] == [
        {"op": "replace", "pointer": "/subscribers/0/periodS", "before": "2.0", "after": "4"}
    ]
    denied = live.post(f"/api/projects/{pid}/deployments", headers=people["designer"], json={})
    assert denied.status_code == 403


def test_stream_relays_values_and_status(live: TestClient, people: dict[str, Headers]) -> None:
    token = people["scientist"]["Authorization"].split()[1]
    with live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws:
        ws.send_json({"op": "auth", "token": token})
        assert ws.receive_json()["type"] == "authenticated"
        ws.send_json({"op": "subscribe", "subscriber": "sub_5", "id": 1})
        ack = _receive_until(ws, lambda m: m["type"] == "subscribed")
        assert ack == {
            "type": "subscribed",
            "subscriber": "sub_5",
            "key": "modd/usv/sub/sub_5",
            "id": 1,
        }
        value = _receive_until(ws, lambda m: m["type"] == "value")
        data = value["data"]
        assert value["subscriber"] == "sub_5"
        assert data["aggregation"] == "MIN" and data["topic"] == "usv.accelerometer.accel_z"
        assert data["end_ns"] - data["start_ns"] == 250_000_000
        status = _receive_until(ws, lambda m: m["type"] == "status")
        assert status["data"]["drone"] == "usv" and "rtt_s" in status["data"]
        ws.send_json({"op": "unsubscribe", "subscriber": "sub_5"})
        _receive_until(ws, lambda m: m["type"] == "unsubscribed")
        ws.send_json({"op": "subscribe", "subscriber": "no such/key"})
        err = _receive_until(ws, lambda m: m["type"] == "error")
        assert "identifier" in err["message"]


def test_stream_relays_the_instruments_health(live: TestClient, people: dict[str, Headers]) -> None:
    """What a publisher reports in HEALTH reaches the browser in the status (issue 32)."""
    token = people["operator"]["Authorization"].split()[1]
    with live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws:
        ws.send_json({"op": "auth", "token": token})
        assert ws.receive_json()["type"] == "authenticated"
        status = _receive_until(ws, lambda m: m["type"] == "status" and "sensors" in m["data"])
        assert status["data"]["sensors"] == HEALTH


def test_dynamic_subscriptions(live: TestClient, people: dict[str, Headers]) -> None:
    sci = people["scientist"]
    token = sci["Authorization"].split()[1]
    with live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws:
        ws.send_json({"op": "auth", "token": token})
        assert ws.receive_json()["type"] == "authenticated"
        ws.send_json(
            {
                "op": "dynamic",
                "topic": "usv.accelerometer.accel_x",
                "period_s": "4",
                "aggregation": "AVERAGE",
                "subscriber": "dyn_avg4",
            }
        )
        reply = _receive_until(ws, lambda m: m["type"] == "dynamic")["reply"]
        assert reply["status"] == "ACCEPTED", reply
        assert reply["key"] == "modd/usv/sub/dyn_avg4"
        ws.send_json({"op": "ping"})
        pong = _receive_until(ws, lambda m: m["type"] == "pong")
        assert "dyn_avg4" in pong["subscribers"]
        ws.send_json({"op": "cancel", "subscriber": "dyn_avg4"})
        cancelled = _receive_until(ws, lambda m: m["type"] == "dynamic")["reply"]
        assert cancelled["status"] == "CANCELLED"
    r = live.post(
        "/api/drones/usv/subscriptions",
        headers=sci,
        json={"topic": "usv.accelerometer.accel_x", "period_s": "1", "aggregation": "MIN"},
    )
    assert r.status_code == 200
    assert r.json()["status"] == "NOT_AVAILABLE" and r.json()["reason"]
    op = live.post(
        "/api/drones/usv/subscriptions",
        headers=people["operator"],
        json={"topic": "usv.accelerometer.accel_x", "period_s": "4", "aggregation": "AVERAGE"},
    )
    assert op.status_code == 403


def test_deploy_to_a_silent_drone_fails_and_is_recorded(
    live: TestClient, people: dict[str, Headers], station: Station
) -> None:
    model = json.loads(json.dumps(station.model))
    model["drone"]["name"] = "ghost"
    text = json.dumps(model).replace('"usv.', '"ghost.')
    pid = live.post(
        "/api/projects",
        headers=people["admin"],
        json={"name": "ghost", "model": {"text": text, "format": "json"}},
    ).json()["id"]
    start = time.monotonic()
    record = live.post(
        f"/api/projects/{pid}/deployments", headers=people["operator"], json={}
    ).json()
    assert record["status"] == "failed"
    assert "nobody answers on modd/ghost/deploy" in record["error"]
    assert time.monotonic() - start < 5
    listed = live.get(f"/api/projects/{pid}/deployments", headers=people["operator"]).json()
    assert listed[0]["status"] == "failed"
    # The deploy matrix: operator and admin deploy; the other roles may not.
    for role, status in (
        ("admin", 201),
        ("scientist", 403),
        ("designer", 403),
        ("integrator", 403),
    ):
        r = live.post(f"/api/projects/{pid}/deployments", headers=people[role], json={})
        assert r.status_code == status, role


def test_websocket_needs_a_token(live: TestClient) -> None:
    from starlette.websockets import WebSocketDisconnect

    with (
        pytest.raises(WebSocketDisconnect) as exc,
        live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws,
    ):
        ws.send_json({"op": "auth", "token": "bad"})
        ws.receive_json()
    assert exc.value.code == 4401
    # a token in the URL is refused outright (URLs end up in logs)
    with (
        pytest.raises(WebSocketDisconnect) as exc,
        live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream?token=x") as ws,
    ):
        ws.receive_json()
    assert exc.value.code == 4400


def test_archive_of_the_running_pubbroker(live: TestClient, people: dict[str, Headers]) -> None:
    """The PubBroker's own MCAP file, read while it is being written."""
    h = people["scientist"]
    deadline = time.monotonic() + 10
    while True:
        files = live.get("/api/drones/usv/archives", headers=h).json()
        counts = {t["topic"]: t["messages"] for f in files for t in f["topics"]}
        if counts.get("usv.accelerometer.accel_z", 0) > 5:
            break
        assert time.monotonic() < deadline, files
        time.sleep(0.2)
    name = files[0]["name"]
    series = live.get(
        f"/api/drones/usv/archives/{name}/series",
        headers=h,
        params={"topic": "usv.accelerometer.accel_z"},
    ).json()
    assert series["total"] > 5
    assert all(-9 <= v <= 9 for _t, v in series["points"])  # the publisher's range


def test_scene_draws_the_track_of_the_deployed_model(
    live: TestClient, people: dict[str, Headers]
) -> None:
    """After the deploy (first test), the scene reads the deployed model's
    position subscribers (track_lat, track_lon) and draws their values."""
    h = people["scientist"]
    assert (
        live.put("/api/scene/usv/colour", headers=h, json={"subscriber": "water_temp"}).status_code
        == 204
    )
    deadline = time.monotonic() + 15
    while True:
        scene = live.get("/api/scene", headers=h).json()
        usv = next((d for d in scene["drones"] if d["drone"] == "usv"), None)
        if usv and usv["points"] >= 2:
            break
        assert time.monotonic() < deadline, scene
        time.sleep(0.25)
    assert usv["roles"]["track_lat"] == "lat" and usv["roles"]["track_lon"] == "lon"
    assert usv["colour_by"] == "water_temp"
    assert scene["url"] == "/scene/"  # viser's own client, through the backend's proxy
    page = live.get(scene["url"], headers=h)
    assert page.status_code == 200 and "<html" in page.text.lower()
    assert live.get(scene["url"]).status_code == 401


def test_backfill_routes_and_roles(live: TestClient, people: dict[str, Headers]) -> None:
    """A scientist starts a backfill of a subscriber's gaps and follows it; the
    operator caps and cancels; the other roles may not."""
    sci, op = people["scientist"], people["operator"]
    body = {"subscriber": "sub_5", "gaps": True}
    assert (
        live.post("/api/drones/usv/backfill", headers=people["designer"], json=body).status_code
        == 403
    )
    assert (
        live.post("/api/drones/usv/backfill", headers=sci, json={"subscriber": "sub_5"}).status_code
        == 422
    )
    started = live.post("/api/drones/usv/backfill", headers=sci, json=body).json()
    assert started["status"] in ("RUNNING", "DONE"), started
    job = started["id"]
    p = live.get(f"/api/drones/usv/backfill/{job}", headers=sci).json()
    assert p["id"] == job and p["windows_total"] >= p["windows_done"] >= 0
    assert validate("backfill", p) == [], p  # relayed as the contract says
    if p["status"] == "RUNNING":  # the SubBroker's view of its queue, this job in it
        assert job in [j["id"] for j in p["queue"]["jobs"]], p
    assert (
        live.post(
            f"/api/drones/usv/backfill/{job}/cap", headers=sci, json={"rate_bps": 100}
        ).status_code
        == 403
    )
    capped = live.post(
        f"/api/drones/usv/backfill/{job}/cap", headers=op, json={"rate_bps": 100}
    ).json()
    assert capped["id"] == job
    assert (
        live.delete(f"/api/drones/usv/backfill/{job}", headers=people["integrator"]).status_code
        == 403
    )
    gone = live.delete(f"/api/drones/usv/backfill/{job}", headers=op).json()
    assert gone["status"] in ("CANCELLED", "DONE"), gone
    unknown = live.get("/api/drones/usv/backfill/999999", headers=sci).json()
    assert unknown["status"] == "UNKNOWN"


def test_drone_wide_fill_gaps_by_the_operator_and_the_scientist_at_once(
    live: TestClient, people: dict[str, Headers], station: Station
) -> None:
    """The workbench's drone-wide Fill gaps, asked by the operator and the scientist at
    the same time (one backfill per subscription each): every job ends DONE, and a job
    that is still running always says why (issue 28)."""
    names = [s["name"] for s in station.model["subscribers"]]
    jobs = []
    for who in ("operator", "scientist"):
        for name in names:
            p = live.post(
                "/api/drones/usv/backfill",
                headers=people[who],
                json={"subscriber": name, "gaps": True},
            ).json()
            assert p["status"] in ("RUNNING", "DONE"), (who, name, p)
            jobs.append((who, p["id"]))
    deadline = time.monotonic() + 60
    ended: dict[int, dict[str, Any]] = {}
    while len(ended) < len(jobs):
        for who, job in jobs:
            if job in ended:
                continue
            p = live.get(f"/api/drones/usv/backfill/{job}", headers=people[who]).json()
            if p["status"] == "RUNNING":
                assert p["reason"], p  # waiting, and saying for what
            else:
                ended[job] = p
        assert time.monotonic() < deadline, [p for p in ended.values()]
        time.sleep(0.2)
    assert {p["status"] for p in ended.values()} == {"DONE"}, ended


def test_saves_are_announced_to_the_project_watchers(
    live: TestClient, people: dict[str, Headers]
) -> None:
    """Everyone with a project open hears of a save over the stream socket."""
    admin = people["admin"]
    pid = live.post(
        "/api/projects",
        headers=admin,
        json={"name": "watched", "model": {"text": DEMO.read_text()}},
    ).json()["id"]
    model = live.get(f"/api/projects/{pid}/model", headers=admin).json()["model"]
    token = people["scientist"]["Authorization"].split()[1]
    with live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws:
        ws.send_json({"op": "auth", "token": token})
        assert ws.receive_json()["type"] == "authenticated"
        ws.send_json({"op": "watch", "project": "x"})
        assert "project id" in _receive_until(ws, lambda m: m["type"] == "error")["message"]
        ws.send_json({"op": "watch", "project": pid, "id": 7})
        assert _receive_until(ws, lambda m: m["type"] == "watching") == {
            "type": "watching",
            "project": pid,
            "id": 7,
        }
        model["subscribers"][0]["periodS"] = "4.0"
        saved = live.put(
            f"/api/projects/{pid}/model",
            headers=people["scientist"],
            json={"model": model, "base_revision": 1, "message": "slower"},
        )
        assert saved.status_code == 200, saved.text
        event = _receive_until(ws, lambda m: m["type"] == "saved")
        assert event == {
            "type": "saved",
            "project": pid,
            "revision": 2,
            "author": "scientist",
            "message": "slower",
        }
        ws.send_json({"op": "unwatch", "project": pid})
        _receive_until(ws, lambda m: m["type"] == "unwatched")
    assert live.app.state.modd.project_events.watchers(pid) == 0  # type: ignore[attr-defined]


def test_batched_stream_keeps_each_subscribers_order(
    live: TestClient, people: dict[str, Headers]
) -> None:
    """``?batch=1``: the values of two subscriptions come in batch frames (and
    lone messages), every message as the unbatched socket sends it, each
    subscriber's windows in time order."""
    token = people["scientist"]["Authorization"].split()[1]
    with live.websocket_connect("ws://127.0.0.1/api/drones/usv/stream?batch=1") as ws:
        ws.send_json({"op": "auth", "token": token})
        assert ws.receive_json()["type"] == "authenticated"
        for name in ("sub_5", "sub_1"):
            ws.send_json({"op": "subscribe", "subscriber": name})
        ends: dict[str, list[int]] = {}
        frames = 0
        while sum(len(v) for v in ends.values()) < 12:
            frame: dict[str, Any] = ws.receive_json()
            frames += 1
            assert frames < 500, ends
            messages = frame["messages"] if frame["type"] == "batch" else [frame]
            if frame["type"] == "batch":
                assert len(messages) > 1
            for m in messages:
                if m["type"] == "value":
                    assert set(m) == {"type", "subscriber", "data"}
                    ends.setdefault(m["subscriber"], []).append(m["data"]["end_ns"])
        assert set(ends) == {"sub_5", "sub_1"}
        for seq in ends.values():
            assert seq == sorted(seq) and len(set(seq)) == len(seq)
