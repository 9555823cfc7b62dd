"""Deploy records that tell the truth, on the SubBroker's side (issue 23,
items 5, 6 and 8), against the real PubBroker:

- the status names the deployment that runs (project, revision, nonce, who,
  when) and is put at once when a CONFIG is acknowledged;
- a deploy request sent again (same signed nonce) applies nothing, and the
  refusal of the replay says it is the deployment running;
- a deploy sent right after another (the PubBroker answers BUSY while the
  first waits for its switch date) is retried, not refused;
- a model the SubBroker cannot plan within its budget is refused with a
  located error, and the running config keeps running;
- after a restart, the kept deployment and the dynamic subscriptions (with
  their owners) come back, said on the first lines and in the status;
  ``--no-resume`` runs the configured model.
"""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from modd_model.query import topics
from subbroker_harness import (
    SUBBROKER,
    Proc,
    free_port,
    model_copy,
    processes,
    signed,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")


def _deploy(session: Any, model: Path, revision: int, **more: Any) -> dict[str, Any]:
    body = signed(
        {
            "text": model.read_text(),
            "format": "json",
            "project_id": 7,
            "revision": revision,
            "deployed_by": "operator",
            **more,
        }
    )
    reply: dict[str, Any] = request(session, "modd/usv/deploy", body, timeout_s=15)
    return reply


def _status_where(got: Collector, pred: Any, timeout_s: float = 5.0) -> dict[str, Any]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        for status in reversed(list(got.status)):
            if pred(status):
                return dict(status)
        time.sleep(0.05)
    raise AssertionError(f"no such status; last: {got.status[-1] if got.status else None}")


def test_the_status_names_what_runs_and_a_restart_resumes_it_loudly(
    tmp_path: Path, zenoh_client: Any
) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    s1 = model_copy(tmp_path, "scenario1.modd")
    s2 = model_copy(tmp_path, "scenario2.modd")
    pb = start_pubbroker(tmp_path, s1, link, ingress)
    cfg = subbroker_config(tmp_path, s1, link, zport, state_dir=tmp_path / "state")
    sb = start_subbroker(tmp_path, cfg)
    procs: list[Proc] = [pb, sb]
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("config 1 running", 10), sb.log()
        first = _status_where(got, lambda s: s.get("config_id") == 1)
        assert first["deployment"]["source"] == "configured"
        assert first["deployment"]["differs_from_configured"] is False

        # a deploy, then one right after it: the PubBroker says BUSY until the
        # first one's switch date; the SubBroker sends it again, never refuses
        replies: list[dict[str, Any]] = []
        second = threading.Thread(target=lambda: replies.append(_deploy(session, s1, 3)))
        reply = _deploy(session, s2, 2)
        second.start()
        second.join(20)
        assert reply["status"] == "ACKED", reply
        assert replies and replies[0]["status"] == "ACKED", replies
        acked_at = time.monotonic()
        running = _status_where(got, lambda s: (s.get("deployment") or {}).get("revision") == 3)
        assert time.monotonic() - acked_at < 0.5  # put at once, not a status period later
        meta = running["deployment"]
        assert meta["source"] == "deploy" and meta["project_id"] == 7
        assert meta["deployed_by"] == "operator" and meta["nonce"]
        assert abs(meta["deployed_at_ns"] - time.time_ns()) < 60e9
        assert running["config_id"] == replies[0]["config_id"]

        # the same signed request again: a replay, refused, but told it is what runs
        accepted = pb.log().count("accepted")
        again = signed(
            {
                "text": s2.read_text(),
                "format": "json",
                "project_id": 7,
                "revision": 4,
                "deployed_by": "operator",
            }
        )
        assert request(session, "modd/usv/deploy", again, timeout_s=15)["status"] == "ACKED"
        dup = request(session, "modd/usv/deploy", again, timeout_s=15)
        assert dup["status"] == "UNAUTHORISED" and dup.get("already_running") is True, dup
        assert dup["deployment"]["revision"] == 4 and "replayed" in dup["reason"]
        time.sleep(0.3)
        assert pb.log().count("accepted") == accepted + 1

        # a dynamic subscription of one owner, kept across the restart
        dyn = request(
            session,
            "modd/usv/subscribe",
            {
                "topic": "usv.ins.accel_x",
                "period_s": "2.0",
                "aggregation": "MIN",
                "owner": "alice",
                "subscriber": "dyn_alice",
            },
        )
        assert dyn["status"] == "ACCEPTED", dyn
        kept = json.loads((tmp_path / "state" / "dynamic.json").read_text())
        assert kept["subscriptions"][0]["owner"] == "alice"

        sb.stop()
        sb2 = start_subbroker(tmp_path, cfg, tag="sb2")
        procs.append(sb2)
        assert sb2.wait_log("running", 15), sb2.log()
        head = "\n".join(sb2.log().splitlines()[:3])
        assert "RESUMING the deployment kept in" in head and "revision 4 of project 7" in head
        assert "by operator" in head and "DIFFERS from the configured model" in head
        time.sleep(1.2)  # the client session reconnects by itself
        resumed = _status_where(
            got, lambda s: (s.get("deployment") or {}).get("source") == "kept", 10
        )
        assert resumed["deployment"]["revision"] == 4
        assert resumed["deployment"]["differs_from_configured"] is True
        assert resumed["deployment"]["resumed_at_ns"] > meta["deployed_at_ns"]
        assert resumed["dynamic"] == ["dyn_alice"]
        mine = request(session, "modd/usv/subscribe", {"action": "list", "owner": "alice"})
        assert [d["name"] for d in mine["subscriptions"]] == ["dyn_alice"]
        others = request(session, "modd/usv/subscribe", {"action": "list", "owner": "bob"})
        assert others["subscriptions"] == []

        # told not to resume: the configured model runs, and the status says so
        sb2.stop()
        sb3 = Proc("sb3", [*SUBBROKER, "--config", str(cfg), "--no-resume"], tmp_path / "sb3.log")
        procs.append(sb3)
        assert sb3.wait_log("running", 15), sb3.log()
        assert "NOT resuming the deployment kept in" in sb3.log()
        time.sleep(1.2)
        fresh = _status_where(
            got,
            lambda s: (
                (s.get("deployment") or {}).get("source") == "configured" and s.get("dynamic") == []
            ),
            10,
        )
        assert fresh["deployment"]["revision"] is None
    finally:
        with processes(*procs):
            pass


def _slow_model(tmp: Path, base: Path, extra: int) -> Path:
    """``base`` with ``extra`` subscriptions at as many non-dividing periods: past
    65 of them the slot bound refuses the model with a located error."""
    model = json.loads(base.read_text())
    for i in range(extra):
        model["subscribers"].append(
            {
                "name": f"big_{i}",
                "topic": "usv.accelerometer.accel_y",
                "periodS": str(round(0.04 * (i + 2), 2)),
                "aggregation": ("MIN", "MAX", "AVERAGE")[i % 3],
            }
        )
    path = tmp / "slow.json"
    path.write_text(json.dumps(model))
    return path


def _large_model(tmp: Path, base: Path, extra: int) -> Path:
    """``base`` with ``extra`` subscriptions at four dividing periods: a plannable
    model whose plan takes time in proportion (20,000: about 0.5 s on this machine,
    ten times the test's budget, where the exponential cases of ``_slow_model`` now
    plan in milliseconds)."""
    model = json.loads(base.read_text())
    names = list(topics(model))
    for i in range(extra):
        model["subscribers"].append(
            {
                "name": f"many_{i}",
                "topic": names[i % len(names)],
                "periodS": ("0.5", "1.0", "2.0", "5.0")[(i // len(names)) % 4],
                "aggregation": ("MIN", "MAX", "AVERAGE")[i % 3],
            }
        )
    path = tmp / "large.json"
    path.write_text(json.dumps(model))
    return path


def test_a_deploy_over_the_planning_budget_is_refused_and_the_config_keeps_running(
    tmp_path: Path, zenoh_client: Any
) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    s1 = model_copy(tmp_path, "scenario1.modd")
    pb = start_pubbroker(tmp_path, s1, link, ingress)
    cfg = subbroker_config(
        tmp_path, s1, link, zport, state_dir=tmp_path / "state", plan_budget_s=0.05
    )
    sb = start_subbroker(tmp_path, cfg)
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("config 1 running", 10), sb.log()
        t0 = time.monotonic()
        reply = _deploy(session, _large_model(tmp_path, s1, 20_000), 2)
        took = time.monotonic() - t0
        assert reply["status"] == "REJECTED", reply
        assert "budget of 0.05 s" in reply["reason"] and took < 3
        assert reply["diagnostics"][0]["pointer"] == ""
        # a model that cannot be planned at all: the planner's located error
        bad = _deploy(session, _slow_model(tmp_path, s1, 80), 3)
        assert bad["status"] == "REJECTED", bad
        assert (
            any(d["pointer"].startswith("/subscribers/") for d in bad["diagnostics"])
            or "still being planned" in bad["reason"]
        ), bad
        time.sleep(1.0)
        status = got.status[-1]
        assert status["config_id"] == 1 and status["link"] == "up"
        assert status["deployment"]["source"] == "configured"
        assert not (tmp_path / "state" / "deployed.json").exists()
        assert "config 2" not in pb.log()
    finally:
        with processes(pb, sb):
            pass
