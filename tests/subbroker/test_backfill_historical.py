"""Backfilled windows are historical end to end (issue 45): real PubBroker and
SubBroker, the link cut in a proxy, then the outage's windows backfilled by
the subscription's own policy (``backfill = gaps``) while live windows flow.

A LAST subscription is watched at once at three outputs, each after every
value it gets: the Python subscriber API (``Subscription.latest``), the
backend's latest value (the 3D scene's track, fed by the backend's
subscription hub) and the browser-facing stream (the backend's live relay,
whose messages are then replayed through the frontend's WebSocketSource by
frontend/src/dataSources/historical.test.ts). The oracle is the stream
itself: the newest live window so far; and whether a window was backfilled
is checked against the SubBroker's window record (windows.json)."""

from __future__ import annotations

import json
import os
import subprocess
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.payload import DeliveredValue
from modd.subscriber import subscribe
from modd.zenoh_session import wait_connected
from subbroker_harness import (
    Blackhole,
    free_port,
    model_copy,
    processes,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

CUT_S = float(os.environ.get("MODD_BACKFILL_CUT_S", "4"))
NAME = "sub_7"  # made LAST, 0.25 s, with backfill = gaps
FRONTEND = Path(__file__).resolve().parents[2] / "frontend"


class Watch:
    """After every value an output got: (the value, what that output calls the latest)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.seen: list[tuple[DeliveredValue, DeliveredValue | float | None]] = []

    def add(self, value: DeliveredValue, latest: DeliveredValue | float | None) -> None:
        with self.lock:
            self.seen.append((value, latest))

    def snapshot(self) -> list[tuple[DeliveredValue, DeliveredValue | float | None]]:
        with self.lock:
            return list(self.seen)


def last_model(tmp_path: Path) -> Path:
    model = model_copy(tmp_path, "scenario1.modd")
    doc = json.loads(model.read_text())
    for sub in doc["subscribers"]:
        if sub["name"] == NAME:
            sub["aggregation"], sub["backfill"] = "LAST", "gaps"
    model.write_text(json.dumps(doc))
    return model


def backend_outputs(session: Any, scene: Watch) -> tuple[Any, Any]:
    """The backend's hub, live relay (the browser's stream) and scene track, on ``session``."""
    from modd_backend.hub import SubscriptionHub
    from modd_backend.live import LiveRelay
    from modd_backend.scene import Track
    from modd_backend.zenoh_session import ZenohSession

    hub = SubscriptionHub()
    track = Track({}, colour_by=NAME)  # its colour value: the backend's latest of NAME

    def on_any(key: str, payload: bytes) -> None:
        if key.endswith(f"/sub/{NAME}"):
            track.ingest(NAME, json.loads(payload))
            scene.add(DeliveredValue.from_json(payload), track._last_value)

    hub.listen_all(on_any)
    hub.start(ZenohSession(session))
    relay = LiveRelay(hub, "usv", 1_000_000)
    relay.subscribe(NAME)
    return hub, relay


def run_outage(tmp_path: Path, zenoh_client: Any) -> tuple[Watch, Watch, list[dict[str, Any]]]:
    link, ingress, zport = free_port(), free_port(), free_port()
    model = last_model(tmp_path)
    pb = start_pubbroker(tmp_path, model, link, ingress)
    proxy = Blackhole(link)
    sb = start_subbroker(
        tmp_path, subbroker_config(tmp_path, model, proxy.port, zport, state_dir=tmp_path / "state")
    )
    load, api, scene = None, Watch(), Watch()
    try:
        wait_port(zport, 60)
        session = zenoh_client(zport)
        assert wait_connected(session, 5)
        hub, relay = backend_outputs(session, scene)
        held: list[Any] = []  # the subscription, once subscribe returned
        sub = subscribe(
            "usv", NAME, lambda v: api.add(v, held[0].latest if held else v), session=session
        )
        held.append(sub)
        assert sb.wait_log("running", 60)
        load = start_load(tmp_path, model, ingress, CUT_S + 120)
        wait_for(lambda: any(v.value is not None for v, _ in api.snapshot()), "a live value")
        proxy.drop()
        time.sleep(CUT_S)
        proxy.restore()
        assert sb.wait_log("resuming config 1", 30), sb.log()
        assert sb.wait_log(f"for {NAME}: DONE", 60), sb.log()[-3000:]
        time.sleep(1.0)  # live windows after the backfill too
        sub.close()
        hub.stop()
    finally:
        with processes(*(x for x in (pb, sb, load) if x is not None)):
            proxy.close()
    return api, scene, relay.queue.drain()


def wait_for(ok: Any, what: str, timeout_s: float = 60) -> None:
    deadline = time.monotonic() + timeout_s
    while not ok():
        assert time.monotonic() < deadline, f"no {what}"
        time.sleep(0.1)


def check_latest(seen: list[tuple[DeliveredValue, Any]], of: Any, empty: bool = True) -> int:
    """After every value, the output's latest is the newest live window so far
    (``of`` reads its end, or its value; ``empty``: whether a window without a
    sample counts); returns how many backfilled windows came after a newer live
    one (each the case under test)."""
    newest: DeliveredValue | None = None
    behind = 0
    for value, latest in seen:
        if value.backfilled:
            behind += newest is not None and value.end_ns < newest.end_ns
        elif (empty or value.value is not None) and (
            newest is None or value.end_ns > newest.end_ns
        ):
            newest = value
        if newest is not None:
            assert latest is not None and of(latest) == of(newest), (value, latest, newest)
    return behind


def test_a_live_last_is_never_replaced_by_an_older_backfilled_one(
    tmp_path: Path, zenoh_client: Any
) -> None:
    api, scene, relayed = run_outage(tmp_path, zenoh_client)
    # the window record says which windows the backfill filled: exactly those are marked
    (path,) = (tmp_path / "state").rglob("windows.json")
    spans = [
        (a, b)
        for subscriber, _stream, filled in json.loads(path.read_text())["filled"]
        if subscriber == NAME
        for a, b in filled
    ]
    values = [v for v, _ in api.snapshot()]
    for v in values:
        assert v.backfilled == any(a <= v.start_ns and v.end_ns <= b for a, b in spans), v
    back = [v for v in values if v.backfilled]
    assert len(back) >= (CUT_S - 1.5) / 0.25, len(back)
    # the subscriber API: Subscription.latest is the newest live window, never a backfilled one
    behind = check_latest(api.snapshot(), lambda v: v.end_ns)
    print(f"historical: {len(back)} backfilled windows, {behind} after a newer live one")
    assert behind > 0
    assert not any(isinstance(x, DeliveredValue) and x.backfilled for _, x in api.snapshot())
    # the backend's latest value (the scene's): the newest live window's value
    of = lambda v: v if isinstance(v, float) else v.value  # noqa: E731
    assert check_latest(scene.snapshot(), of, empty=False) > 0
    # the browser's stream: each window marked exactly when the record says it was filled
    assert sum(m["data"].get("backfilled") is True for m in relayed) == len(back)
    for m in relayed:
        d = m["data"]
        filled = any(a <= d["start_ns"] and d["end_ns"] <= b for a, b in spans)
        assert m["type"] == "value" and m["subscriber"] == NAME
        assert d.get("backfilled", False) is filled, m
    capture = tmp_path / "relay.json"
    capture.write_text(json.dumps({"subscriber": NAME, "messages": relayed}))
    # ... and through the frontend's own logic (Vitest, this run's messages)
    run = subprocess.run(
        ["npx", "vitest", "run", "src/dataSources/historical.test.ts"],
        cwd=FRONTEND,
        env={**os.environ, "MODD_RELAY_CAPTURE": str(capture)},
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert "1 passed" in run.stdout
