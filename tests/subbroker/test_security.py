"""The SubBroker's zenoh control plane as an attacker on the same machine
meets it (docs/security.md, "Zenoh"): against the real PubBroker and the
SubBroker CLI on loopback, with the credentials the SubBroker uses.

- anonymous and wrong-password clients are refused;
- a viewer cannot deploy, subscribe dynamically, or put values or status, and
  its forged value never reaches a subscriber;
- a deploy not signed by the workbench, or replayed (also after a restart
  of the SubBroker), is refused;
- dynamic subscriptions: quota per owner, owner-scoped list and cancel,
  bounded names."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import NoReply, request
from modd.subbroker.dynamic import PER_OWNER
from modd.zenoh_auth import Credentials
from modd.zenoh_session import client_settings, open_session, wait_connected
from modd_model.signing import sign_request
from subbroker_harness import (
    Scenario1,
    scenario1_running,
    shared_credentials,
    signed,
    start_subbroker,
    wait_port,
)

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

DYN = {"topic": "usv.accelerometer.accel_x", "period_s": "4.0", "aggregation": "AVERAGE"}


@pytest.fixture(scope="module")
def station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Scenario1]:
    tmp = tmp_path_factory.mktemp("security")
    with scenario1_running(tmp, 60) as running:
        yield running


def _anonymous(port: int, who: Credentials | None) -> None:
    open_session(client_settings(f"tcp/127.0.0.1:{port}", who))


def test_anonymous_and_wrong_password_refused(station: Scenario1) -> None:
    port = station.port
    with pytest.raises(ValueError, match="cannot open"):
        _anonymous(port, None)
    for who in (
        Credentials("viewer", "not-the-password"),
        Credentials("admin", "admin"),
        Credentials("backend", shared_credentials().credentials("viewer").password),
    ):
        with pytest.raises(ValueError, match="cannot open"):
            _anonymous(port, who)


def test_viewer_reads_but_cannot_deploy_subscribe_or_forge(
    station: Scenario1, zenoh_client: Any
) -> None:
    port = station.port
    reader = zenoh_client(port, "backend")
    viewer = zenoh_client(port, "viewer")
    assert wait_connected(reader) and wait_connected(viewer)
    seen: list[tuple[str, bytes]] = []
    mine: list[str] = []
    reader.declare_subscriber(
        "modd/usv/**", lambda s: seen.append((str(s.key_expr), s.payload.to_bytes()))
    )
    viewer.declare_subscriber("modd/usv/**", lambda s: mine.append(str(s.key_expr)))
    forged = {"subscriber": "sub_3", "topic": "usv.ins.accel_x", "value": 1e9, "slot": 999999}
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline:
        viewer.put("modd/usv/sub/sub_3", json.dumps(forged))
        viewer.put("modd/usv/status", json.dumps({"drone": "usv", "forged": True}))
        time.sleep(0.1)
    assert any("/sub/" in k for k, _ in seen) and any(k.endswith("/status") for k, _ in seen)
    assert not [p for _, p in seen if b"999999" in p or b"forged" in p]
    assert any("/sub/" in k for k in mine), "the viewer reads values"
    s1 = station.model.read_text()
    with pytest.raises(NoReply):
        request(viewer, "modd/usv/deploy", signed({"text": s1, "format": "json"}), timeout_s=1)
    with pytest.raises(NoReply):
        request(viewer, "modd/usv/subscribe", DYN, timeout_s=1)
    assert "deploy" not in station.sb.log().split("config 1 running", 1)[1]


def test_unsigned_forged_or_replayed_deploy_refused(station: Scenario1, zenoh_client: Any) -> None:
    backend = zenoh_client(station.port, "backend")
    assert wait_connected(backend)
    body = {"text": station.model.read_text(), "format": "json", "timeout_s": 5}
    unsigned = request(backend, "modd/usv/deploy", body)
    assert unsigned["status"] == "UNAUTHORISED", unsigned
    forged = sign_request(b"a key the attacker made up", body)
    assert request(backend, "modd/usv/deploy", forged)["status"] == "UNAUTHORISED"
    good = signed(body)
    tampered = {**good, "timeout_s": 6}
    assert request(backend, "modd/usv/deploy", tampered)["status"] == "UNAUTHORISED"
    acked = request(backend, "modd/usv/deploy", good)
    assert acked["status"] == "ACKED", acked
    replay = request(backend, "modd/usv/deploy", good)
    assert replay["status"] == "UNAUTHORISED" and "replayed" in replay["reason"]


def test_dynamic_quota_owner_scope_and_names(station: Scenario1, zenoh_client: Any) -> None:
    backend = zenoh_client(station.port, "backend")
    assert wait_connected(backend)

    def ask(**more: Any) -> dict[str, Any]:
        return request(backend, "modd/usv/subscribe", {**DYN, **more})

    names = []
    for _ in range(PER_OWNER):
        reply = ask(owner="alice")
        assert reply["status"] == "ACCEPTED", reply
        names.append(reply["subscriber"])
    over = ask(owner="alice")
    assert over["status"] == "QUOTA", over
    assert ask(owner="bob")["status"] == "ACCEPTED"  # the quota is per owner
    listed = request(backend, "modd/usv/subscribe", {"action": "list", "owner": "bob"})
    assert len(listed["subscriptions"]) == 1 and listed["subscriptions"][0]["owner"] == "bob"
    theft = request(
        backend, "modd/usv/subscribe", {"action": "cancel", "subscriber": names[0], "owner": "bob"}
    )
    assert theft["status"] == "ERROR"
    mine = request(
        backend,
        "modd/usv/subscribe",
        {"action": "cancel", "subscriber": names[0], "owner": "alice"},
    )
    assert mine["status"] == "CANCELLED"
    for bad in ("x" * 10_000, "sub_ok\n", "a/b", "*"):
        reply = ask(owner="carol", subscriber=bad)
        assert reply["status"] == "ERROR", (bad[:20], reply)
    for name in names[1:]:
        request(
            backend,
            "modd/usv/subscribe",
            {"action": "cancel", "subscriber": name, "owner": "alice"},
        )


def test_replayed_deploy_refused_after_a_subbroker_restart(
    station: Scenario1, zenoh_client: Any, tmp_path: Path
) -> None:
    backend = zenoh_client(station.port, "backend")
    assert wait_connected(backend)
    body = {"text": station.model.read_text(), "format": "json", "timeout_s": 5}
    good = signed(body)
    applied = request(backend, "modd/usv/deploy", good)  # the signature and nonce passed
    assert applied["status"] != "UNAUTHORISED", applied
    old = station.sb
    old.stop()
    station.sb = sb = start_subbroker(tmp_path, station.config, "sb-restarted")
    wait_port(station.port)
    assert sb.wait_log("running", 30), sb.log()
    deadline = time.monotonic() + 10
    while True:  # the client reconnects to the restarted router by itself
        try:
            replay = request(backend, "modd/usv/deploy", good, timeout_s=2)
            break
        except NoReply:
            assert time.monotonic() < deadline, sb.log()
            time.sleep(0.2)
    assert replay["status"] == "UNAUTHORISED" and "replayed" in replay["reason"], replay
    fresh = request(backend, "modd/usv/deploy", signed(body))  # a new signature still works
    assert fresh["status"] != "UNAUTHORISED", fresh


def _replies(session: Any, key: str, body: dict[str, Any]) -> list[dict[str, Any]]:
    """Every reply to one query (a forged queryable would add one)."""
    out = []
    for reply in session.get(key, payload=json.dumps(body).encode(), timeout=3):
        if reply.ok is not None:
            out.append(json.loads(reply.ok.payload.to_bytes()))
    return out


def test_no_identity_but_the_subbroker_answers_or_forges(
    station: Scenario1, zenoh_client: Any
) -> None:
    """Held-out: a viewer, or a stolen backend credential, declares queryables
    on the control keys to answer in the SubBroker's place, and the backend
    puts forged values and status: none of it reaches anyone."""
    port = station.port
    backend = zenoh_client(port, "backend")
    viewer = zenoh_client(port, "viewer")
    other = zenoh_client(port, "backend")
    assert wait_connected(backend) and wait_connected(viewer) and wait_connected(other)
    forged_reply = json.dumps({"status": "ACKED", "forged": True, "subscriptions": []})

    def answer(query: Any) -> None:
        query.reply(query.key_expr, forged_reply.encode())

    fakes = [
        s.declare_queryable(k, answer)
        for s in (viewer, other)
        for k in ("modd/usv/deploy", "modd/usv/subscribe", "modd/**")
    ]
    seen: list[bytes] = []
    viewer.declare_subscriber("modd/**", lambda s: seen.append(s.payload.to_bytes()))
    time.sleep(0.5)
    listed = _replies(backend, "modd/usv/subscribe", {"action": "list", "owner": "x"})
    assert listed and not [r for r in listed if r.get("forged")], listed
    deploys = _replies(backend, "modd/usv/deploy", {"text": "{}", "format": "json"})
    assert deploys and all(r["status"] == "UNAUTHORISED" for r in deploys), deploys
    deadline = time.monotonic() + 2
    while time.monotonic() < deadline:
        other.put("modd/usv/sub/sub_1", json.dumps({"value": 1e9, "slot": 999999}))
        other.put("modd/usv/status", json.dumps({"forged": True}))
        other.put("modd/usv/sub/new_name", json.dumps({"value": 1e9, "slot": 999999}))
        time.sleep(0.1)
    assert seen, "the viewer reads the SubBroker's values"
    assert not [p for p in seen if b"999999" in p or b"forged" in p]
    for q in fakes:
        q.undeclare()


def test_oversized_or_deep_queries_are_refused_before_parsing(
    station: Scenario1, zenoh_client: Any
) -> None:
    """Held-out: a stolen ``backend`` credential sends 30,000-deep and
    oversized documents to every queryable. Before, the parser's recursion
    answered "internal error" (a traceback logged per query) and a 20 MB
    query was parsed whole; now each is an ERROR naming the bound, and the
    SubBroker keeps answering."""
    backend = zenoh_client(station.port, "backend")
    assert wait_connected(backend)
    deep = b"[" * 30_000 + b"]" * 30_000  # within the size bound, far past the recursion limit
    big = json.dumps({"action": "list", "owner": "x" * 70_000}).encode()
    for key in ("modd/usv/deploy", "modd/usv/subscribe", "modd/usv/backfill"):
        for payload, words in ((deep, "nested"), (big, "bytes")):
            replies = [
                json.loads(r.ok.payload.to_bytes())
                for r in backend.get(key, payload=payload, timeout=5)
                if r.ok is not None
            ]
            if key.endswith("deploy") and payload is big:  # within a deploy's bound
                assert replies and replies[0]["status"] != "ACKED", replies
                continue
            assert len(replies) == 1, (key, replies)
            assert replies[0]["status"] == "ERROR" and words in replies[0]["reason"], replies
    listed = request(backend, "modd/usv/subscribe", {"action": "list", "owner": "x"})
    assert listed["status"] == "OK"
    assert "RecursionError" not in station.sb.log()
