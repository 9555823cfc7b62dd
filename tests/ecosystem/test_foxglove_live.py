"""A Foxglove client (@foxglove/ws-protocol, subprotocol foxglove.sdk.v1)
connected to the backend's Foxglove server, itself fed by a real base station
(PubBroker + SubBroker + publisher, backend/tests/station.py): it receives
every subscriber's values live, each equal to the value delivered on zenoh
(the oracle: an independent zenoh subscriber), plus the link status; a
dynamic subscription appears as a channel and goes when cancelled."""

from __future__ import annotations

import io
import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh
from ecosystem_support import foxglove_links, node_json
from fastapi.testclient import TestClient
from modd.ports import free_port
from modd.zenoh_session import client_settings, open_session
from modd_backend import Settings, create_app
from modd_contracts.schema import load as contract_schema
from modd_model import load_model
from served import serve
from station import PUBBROKER, Station
from test_viewer_schemas import violations
from viewer_schema import refusals

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


@pytest.fixture(autouse=True)
def _pubbroker_built() -> None:
    """make test builds it: missing is a setup bug, not a skip."""
    if not PUBBROKER.exists():
        pytest.fail(f"{PUBBROKER} is missing: run make build")


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Station]:
    st = Station(tmp_path_factory.mktemp("station"), load_model(DEMO))
    try:
        st.start()
        yield st
    finally:
        st.stop()


@pytest.fixture(scope="module")
def backend(station: Station, tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The backend's base URL (served: the Foxglove client comes in through
    its ``/foxglove/live``)."""
    settings = Settings(
        data_dir=tmp_path_factory.mktemp("backend"),
        zenoh_connect=(station.zenoh,),
        initial_admin_password="pw-12345678",
        zenoh_credentials=station.credentials.cred_file("backend"),
        deploy_key_file=station.credentials.deploy_key_file,
        foxglove_port=free_port(),
    )
    with serve(settings) as base:
        yield base


class ZenohOracle:
    """Every delivered value on ``modd/usv/sub/*``, by subscriber."""

    def __init__(self, endpoint: str, credentials: Path) -> None:
        # the backend's identity: it may subscribe to values and ask for subscriptions
        self.session = open_session(client_settings(endpoint, credentials))
        self.values: dict[str, list[dict[str, Any]]] = {}
        self._lock = threading.Lock()
        self.sub = self.session.declare_subscriber("modd/usv/sub/*", self._on)

    def _on(self, sample: zenoh.Sample) -> None:
        name = str(sample.key_expr).rsplit("/", 1)[-1]
        with self._lock:
            self.values.setdefault(name, []).append(json.loads(sample.payload.to_bytes()))

    def query(self, key: str, request: dict[str, Any]) -> dict[str, Any]:
        for reply in self.session.get(key, payload=json.dumps(request).encode(), timeout=5):
            if reply.ok is not None:
                out: dict[str, Any] = json.loads(reply.ok.payload.to_bytes())
                return out
        raise AssertionError(f"no reply on {key}")

    def close(self) -> None:
        self.sub.undeclare()  # type: ignore[no-untyped-call]
        self.session.close()  # type: ignore[no-untyped-call]


def test_every_subscriber_live_in_foxglove(backend: str, station: Station) -> None:
    live_url = foxglove_links(backend, "admin", "pw-12345678")["live"]
    oracle = ZenohOracle(station.zenoh, station.credentials.cred_file("backend"))
    try:
        time.sleep(1.0)  # the zenoh oracle is connected before the Foxglove client
        dyn = "dyn_min05"

        def dynamic() -> None:
            time.sleep(3.0)
            reply = oracle.query(
                "modd/usv/subscribe",
                {
                    "topic": "usv.accelerometer.accel_z",
                    "period_s": "0.5",
                    "aggregation": "MIN",
                    "subscriber": dyn,
                },
            )
            assert reply["status"] == "ACCEPTED", reply
            time.sleep(3.0)
            cancel = oracle.query("modd/usv/subscribe", {"action": "cancel", "subscriber": dyn})
            assert cancel["status"] == "CANCELLED", cancel

        t = threading.Thread(target=dynamic)
        t.start()
        report = node_json("foxglove_client.cjs", live_url, "9", timeout=60)
        t.join()
        time.sleep(0.5)
    finally:
        oracle.close()
    assert report["protocol"] == "foxglove.sdk.v1"
    assert not report["errors"], report["errors"]
    # the SDK's advertise/subscribe race (docs/ecosystem.md): answered by subscribing again
    print(f"foxglove live: subscribed again after 'Unknown channel ID': {report['resubscribed']}")
    received = report["messages"]
    expected = {s["name"] for s in station.model["subscribers"]}
    got = {t.split("/")[2] for t in received if t.startswith("/usv/")}
    assert {"link", "position"} <= got
    assert expected <= got, f"no Foxglove values for {sorted(expected - got)}"
    # latency: SubBroker's put (delivered) to the client's receipt, same machine and clock
    lat_ms = sorted(
        m["recvMs"] - (m["msg"]["delivered"]["sec"] * 1e3 + m["msg"]["delivered"]["nsec"] / 1e6)
        for t, msgs in received.items()
        if t.split("/")[2] not in ("link", "position")
        for m in msgs
    )
    print(
        f"foxglove live: {len(lat_ms)} values, SubBroker put -> client: median "
        f"{lat_ms[len(lat_ms) // 2]:.1f} ms, p95 {lat_ms[int(len(lat_ms) * 0.95)]:.1f} ms"
    )
    # each Foxglove message is a value delivered on zenoh, field for field
    for topic, msgs in received.items():
        name = topic.split("/")[2]
        if name == "link":
            assert msgs[-1]["msg"]["link"] == "up"
            continue
        if name == "position":  # LocationFix from track_lat and track_lon
            lats = {v["end_ns"]: v["value"] for v in oracle.values["track_lat"]}
            lons = {v["end_ns"]: v["value"] for v in oracle.values["track_lon"]}
            for m in msgs:
                fix, end = m["msg"], int(m["logTime"])
                assert fix["latitude"] == lats[end] and fix["longitude"] == lons[end], fix
            continue
        delivered = {v["end_ns"]: v for v in oracle.values[name]}
        for m in msgs:
            w = m["msg"]
            v = delivered.get(int(m["logTime"]))  # log time = window end, exact (BigInt)
            assert v is not None, f"{topic}: {w} was never delivered on zenoh"
            assert w.get("value") == v["value"], (topic, w, v)  # a null is left out
            assert w.get("count") == v["count"] and w["aggregation"] == v["aggregation"]
            assert w["backfilled"] is False
            assert w["window_end"] == {"sec": v["end_ns"] // 10**9, "nsec": v["end_ns"] % 10**9}
            assert w["window_start"] == {
                "sec": v["start_ns"] // 10**9,
                "nsec": v["start_ns"] % 10**9,
            }
    schema = next(a for a in report["advertised"] if a["topic"] == "/usv/sub_5")
    assert schema["encoding"] == "json" and schema["schemaName"] == "modd.Window"
    # every channel is one the viewers can read (else Lichtblick drops it), and
    # every message validates against its channel's schema (a JSON Schema validator)
    schemas = {a["topic"]: json.loads(a["schema"]) for a in report["advertised"]}
    for topic, declared in schemas.items():
        assert not refusals(declared), (topic, declared)
    bad = [
        (t, m["msg"], violations(schemas[t], m["msg"]))
        for t, msgs in received.items()
        for m in msgs
        if violations(schemas[t], m["msg"])
    ]
    checked = sum(len(msgs) for msgs in received.values())
    print(
        f"foxglove live: {checked} messages on {len(received)} channels validated, "
        f"{len(bad)} invalid"
    )
    assert not bad, bad[:3]
    assert len(schemas["/usv/link"]["properties"]) == len(contract_schema("status")["properties"])
    assert set(json.loads(schema["schema"])["properties"]) >= {
        "value",
        "count",
        "aggregation",
        "window_start",
        "window_end",
        "backfilled",
    }
    # the dynamic subscription came and went
    assert f"/usv/{dyn}" in received and received[f"/usv/{dyn}"]
    assert f"/usv/{dyn}" in report["unadvertised"]


def test_a_taken_port_leaves_the_backend_running(tmp_path: Path) -> None:
    import socket

    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        out = io.StringIO()
        settings = Settings(
            data_dir=tmp_path,
            zenoh_connect=(f"tcp/127.0.0.1:{free_port()}",),
            initial_admin_password="pw-12345678",
            foxglove_port=port,
        )
        with TestClient(create_app(settings, out=out), base_url="http://127.0.0.1") as c:
            assert c.get("/api/health").status_code == 200
            assert c.app.state.modd.foxglove is None  # type: ignore[attr-defined]
        assert f"no Foxglove server on 127.0.0.1:{port}" in out.getvalue()


def test_channels_follow_a_new_deploy() -> None:
    """A deploy that drops a subscriber (its status routes no longer name it)
    withdraws its channel; a new subscriber's first value advertises one."""
    from modd_backend.foxglove import FoxgloveLive

    live = FoxgloveLive("127.0.0.1", free_port())
    try:
        v = {
            "v": 1,
            "value": 1.0,
            "count": None,
            "aggregation": "MIN",
            "start_ns": 0,
            "end_ns": 250_000_000,
            "topic": "usv.a.z",
            "delivered_ns": 1,
        }
        for name in ("sub_1", "sub_2"):
            live.on_value(f"modd/usv/sub/{name}", json.dumps(v).encode())
        live.on_value("modd/usv/sub/bad key", b"not json")
        assert live.topics() == ["/usv/sub_1", "/usv/sub_2"]
        status = {
            "drone": "usv",
            "link": "up",
            "time_ns": 5,
            "routes": {"usv.a.z/MIN/0.25": ["sub_2"]},
            "dynamic": [],
        }
        live.on_status("modd/usv/status", json.dumps(status).encode())
        assert live.topics() == ["/usv/link", "/usv/sub_2"]
        live.on_value("modd/usv/sub/sub_9", json.dumps(v).encode())
        live.on_status("modd/usv/status", json.dumps({"link": "down"}).encode())  # no routes
        assert live.topics() == ["/usv/link", "/usv/sub_2", "/usv/sub_9"]
    finally:
        live.stop()


def test_an_all_subscriber_changes_its_channel_schema() -> None:
    """An ``ALL`` subscriber's value is an array of numbers in its schema; a
    deploy that changes its aggregation advertises the channel again."""
    from modd_backend.foxglove import FoxgloveLive

    live = FoxgloveLive("127.0.0.1", free_port())
    try:
        v = {
            "value": [1.0, 2.0],
            "count": 2,
            "aggregation": "ALL",
            "start_ns": 0,
            "end_ns": 250_000_000,
            "topic": "usv.a.z",
            "delivered_ns": 1,
        }
        live.on_value("modd/usv/sub/s", json.dumps(v).encode())
        first = live._channels["/usv/s"]
        assert json.loads(live._schemas["/usv/s"])["properties"]["value"]["type"] == "array"
        live.on_value("modd/usv/sub/s", json.dumps(v).encode())
        assert live._channels["/usv/s"] is first  # same schema: same channel
        live.on_value("modd/usv/sub/s", json.dumps(dict(v, value=1.5, aggregation="MAX")).encode())
        assert live._channels["/usv/s"] is not first
        assert json.loads(live._schemas["/usv/s"])["properties"]["value"]["type"] == "number"
        assert live.topics() == ["/usv/s"]
    finally:
        live.stop()


def test_a_backfilled_window_is_marked_and_never_a_position() -> None:
    """A backfilled (historical) window goes out on its subscriber's channel
    with ``backfilled`` true, logged at its own window's end (a plot places it
    in time); it never makes a ``/position`` fix (a LocationFix cannot say it is
    old, and an old latitude would pair with a live longitude)."""
    from modd_backend.foxglove import FoxgloveLive

    live = FoxgloveLive("127.0.0.1", free_port())
    logged: list[tuple[str, dict[str, Any], int | None]] = []

    class Spy:
        def __init__(self, topic: str) -> None:
            self.topic = topic

        def log(self, msg: dict[str, Any], log_time: int | None = None) -> None:
            logged.append((self.topic, msg, log_time))

    live._channel = lambda topic, schema, title: Spy(topic)  # type: ignore[method-assign]
    try:

        def put(name: str, topic: str, end_s: int, value: float, backfilled: bool) -> None:
            v = {
                "value": value,
                "count": None,
                "aggregation": "LAST",
                "topic": topic,
                "start_ns": (end_s - 1) * 10**9,
                "end_ns": end_s * 10**9,
                "delivered_ns": 1,
            }
            live.on_value(
                f"modd/usv/sub/{name}",
                json.dumps(v | ({"backfilled": True} if backfilled else {})).encode(),
            )

        put("track_lat", "usv.gps.latitude", 10, 43.0, False)
        put("track_lon", "usv.gps.longitude", 10, 5.0, False)
        put("track_lat", "usv.gps.latitude", 4, 42.0, True)  # an old window, filled late
        put("track_lon", "usv.gps.longitude", 4, 4.0, True)
        put("track_lat", "usv.gps.latitude", 11, 43.5, False)
        put("track_lon", "usv.gps.longitude", 11, 5.5, False)
    finally:
        live.stop()
    fixes = [
        (m["latitude"], m["longitude"], t) for topic, m, t in logged if topic == "/usv/position"
    ]
    assert fixes == [(43.0, 5.0, 10 * 10**9), (43.5, 5.5, 11 * 10**9)]
    windows = [
        (m["backfilled"], m["value"], t) for topic, m, t in logged if topic == "/usv/track_lat"
    ]
    assert windows == [
        (False, 43.0, 10 * 10**9),
        (True, 42.0, 4 * 10**9),
        (False, 43.5, 11 * 10**9),
    ]
