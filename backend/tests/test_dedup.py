"""The backend keeps each window once, by its identity (docs/fleet.md, "Exactly
once at the subscriber"): the hub, where every delivered value comes in, passes
the contracts' repeats (contracts/vectors/delivered_value.json) as the Python and
C++ subscriber clients do; and over zenoh, two stations putting the same windows
reach a browser's WebSocket once each, while the same window of another epoch,
and payloads without an identity, still come."""

from __future__ import annotations

import io
import json
import threading
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh
from fastapi.testclient import TestClient
from modd.ports import free_port
from modd.subbroker.payload import StreamPayload, subscriber_prefix
from modd.zenoh_recovery import values_publisher
from modd_backend import Settings, create_app, hub
from modd_backend.hub import SubscriptionHub
from starlette.testclient import WebSocketTestSession

from .conftest import ADMIN_PASSWORD, login

VECTORS = Path(__file__).resolve().parents[2] / "contracts" / "vectors" / "delivered_value.json"
JSON = zenoh.Encoding.APPLICATION_JSON
EPOCH, OTHER_EPOCH, Q = 1_700_000_000_000_000_000, 1_700_000_060_000_000_000, 250_000_000


def test_the_hub_passes_each_window_once() -> None:
    sequence = json.loads(VECTORS.read_text())["repeats"]["sequence"]
    h = SubscriptionHub()
    every: list[bytes] = []
    h.listen_all(lambda key, payload: every.append(payload))
    for case in sequence:
        doc = json.loads(case["line"])
        h.on_value(
            f"modd/{doc['topic'].split('.')[0]}/sub/{doc['subscriber']}", case["line"].encode()
        )
    assert every == [c["line"].encode() for c in sequence if c["first"]]
    assert h.duplicates == sum(not c["first"] for c in sequence)


def test_what_is_not_a_window_passes() -> None:
    h = SubscriptionHub()
    got: list[bytes] = []
    h.add("usv", "s", lambda name, payload: got.append(payload))
    odd = [b"{", b'{"window":1}', b'{"drone":"usv","subscriber":"s","epoch_ns":1,"window":true}']
    odd.append(b'"window"' + b"[" * 100_000)  # deep: json's recursion, caught
    for payload in odd + odd:
        h.on_value("modd/usv/sub/s", payload)
    assert got == odd + odd and h.duplicates == 0


# --- over zenoh: a router, two stations putting, the backend a client ----------


def _client(router: str) -> zenoh.Session:
    c = zenoh.Config()
    c.insert_json5("mode", '"client"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("connect/endpoints", json.dumps([router]))
    return zenoh.open(c)


@pytest.fixture
def router() -> Iterator[str]:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    c = zenoh.Config()
    c.insert_json5("mode", '"router"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("listen/endpoints", json.dumps([endpoint]))
    session = zenoh.open(c)
    try:
        yield endpoint
    finally:
        session.close()  # type: ignore[no-untyped-call]


def _line(window: int, epoch: int = EPOCH, identity: bool = True, value: float = 1.5) -> bytes:
    """A window of sub_1 as the SubBroker's fast path writes it (payload.StreamPayload)."""
    head = StreamPayload(
        "usv.ctd.temp", "MIN", "0.25", "CELSIUS", 3, ("usv", epoch, Q) if identity else None
    )
    start = epoch + window * Q
    return subscriber_prefix("sub_1") + head.tail(window, start, start + Q, value, None, start + Q)


#: Values of the probes each station puts until the hub hears both (not counted).
PROBES = {-1.0, -2.0}


def _until_both_heard(ws: WebSocketTestSession, a: Any, b: Any) -> None:
    """Each station puts a probe (a payload without identity: always relayed) until
    the browser got one of each, so no counted put precedes the hub's subscriber
    reaching the router (slower on a loaded machine than any fixed wait)."""
    stop = threading.Event()

    def probe() -> None:
        while not stop.is_set():
            a.put(_line(0, identity=False, value=-1.0))
            b.put(_line(0, identity=False, value=-2.0))
            stop.wait(0.1)

    thread = threading.Thread(target=probe, daemon=True)
    thread.start()
    try:
        _values_until(ws, set(PROBES))
    finally:
        stop.set()
        thread.join()


def _values_until(ws: WebSocketTestSession, ends: set[float]) -> list[dict[str, Any]]:
    """The values relayed until each value of ``ends`` came (each station's last put),
    probes left out."""
    got: list[dict[str, Any]] = []
    while ends:
        msg = ws.receive_json()
        if msg["type"] == "value":
            ends.discard(msg["data"]["value"])
            if msg["data"]["value"] not in PROBES:
                got.append(msg["data"])
    return got


def _relayed(router: str, tmp_path: Path) -> list[dict[str, Any]]:
    """Stations a and b both put windows 0-2 of epoch 1 (b after a: a partition
    healed while both served), a puts window 0 of another epoch, both put an older
    payload (no identity); each ends with a window of its own, the marks awaited."""
    settings = Settings(
        data_dir=tmp_path,
        zenoh_connect=(router,),
        initial_admin_password=ADMIN_PASSWORD,
    )
    key = "modd/usv/sub/sub_1"
    sa, sb = _client(router), _client(router)
    # each station's values through the SubBroker's own (advanced) publisher
    a, b = (values_publisher(s, key, JSON, zenoh.CongestionControl.BLOCK) for s in (sa, sb))
    try:
        with TestClient(create_app(settings, out=io.StringIO())) as client:
            token = login(client, "admin", ADMIN_PASSWORD)["Authorization"].split()[1]
            with client.websocket_connect("ws://127.0.0.1/api/drones/usv/stream") as ws:
                ws.send_json({"op": "auth", "token": token})
                assert ws.receive_json()["type"] == "authenticated"
                ws.send_json({"op": "subscribe", "subscriber": "sub_1"})
                assert ws.receive_json()["type"] == "subscribed"
                _until_both_heard(ws, a, b)
                for station in (a, b):
                    for k in range(3):
                        station.put(_line(k))
                    station.put(_line(0, identity=False, value=7.0))
                a.put(_line(0, epoch=OTHER_EPOCH, value=2.5))
                a.put(_line(10, value=100.0))
                b.put(_line(11, value=111.0))
                return _values_until(ws, {100.0, 111.0})
    finally:
        for pub in (a, b):
            pub.undeclare()
        sa.close()  # type: ignore[no-untyped-call]
        sb.close()  # type: ignore[no-untyped-call]


def _windows(values: list[dict[str, Any]]) -> Counter[tuple[int | None, int | None]]:
    return Counter((v.get("epoch_ns"), v.get("window")) for v in values)


def test_two_stations_windows_reach_the_browser_once(router: str, tmp_path: Path) -> None:
    got = _windows(_relayed(router, tmp_path))
    assert got == Counter(
        {(EPOCH, 0): 1, (EPOCH, 1): 1, (EPOCH, 2): 1, (OTHER_EPOCH, 0): 1, (None, None): 2}
        | {(EPOCH, 10): 1, (EPOCH, 11): 1}
    )


def test_without_the_hubs_memory_the_browser_gets_them_twice(
    router: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The control: the same puts with every window taken as new reach the browser
    twice, so the test above sees what the hub drops."""
    monkeypatch.setattr(hub, "first_window", lambda seen, payload: True)
    got = _windows(_relayed(router, tmp_path))
    assert got[(EPOCH, 0)] == got[(EPOCH, 2)] == 2 and got[(OTHER_EPOCH, 0)] == 1
