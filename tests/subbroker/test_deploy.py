"""Deploy over zenoh against the real PubBroker: the reply comes only after
the PubBroker's CONFIG_ACK; errors and a down link get an answer too; the
deployed model survives a SubBroker restart (state_dir)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from subbroker_harness import (
    SCENARIOS,
    free_port,
    model_copy,
    processes,
    signed,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")


def test_deploy_switches_the_running_plan(tmp_path: Path, zenoh_client: Any) -> None:
    link, ingress, zport = free_port(), free_port(), free_port()
    s1 = model_copy(tmp_path, "scenario1.modd")
    s2 = model_copy(tmp_path, "scenario2.modd")
    pb = start_pubbroker(tmp_path, s1, link, ingress)
    cfg = subbroker_config(tmp_path, s1, link, zport, state_dir=tmp_path / "state")
    sb = start_subbroker(tmp_path, cfg)
    sb2 = load = None
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("config 1 running", 10), sb.log()
        dyn = request(
            session,
            "modd/usv/subscribe",
            {"topic": "usv.accelerometer.accel_x", "period_s": "4.0", "aggregation": "AVERAGE"},
        )
        assert dyn["status"] == "ACCEPTED"

        bad = request(
            session, "modd/usv/deploy", signed({"text": "Drone usv {", "filename": "x.modd"})
        )
        assert bad["status"] == "INVALID" and bad["diagnostics"]
        assert "x.modd" in str(bad["diagnostics"][0])
        other = request(
            session,
            "modd/usv/deploy",
            signed({"text": (SCENARIOS / "scenario1.modd").read_text().replace("usv", "uav")}),
        )
        assert other["status"] == "REJECTED" and "'uav'" in other["reason"]

        t0 = time.monotonic()
        reply = request(
            session, "modd/usv/deploy", signed({"text": s2.read_text(), "format": "json"})
        )
        assert reply["status"] == "ACKED", reply
        assert reply["config_id"] == 2 and reply["streams_sent"] == 19
        assert reply["messages_per_hyperperiod"] == 1 and reply["epoch_ns"] > 0
        assert set(reply["buffer_sizes"].values()) == {25}
        assert time.monotonic() - t0 < 5
        assert "config 2 accepted" in pb.log()

        load = start_load(tmp_path, s2, ingress, 3.5)
        load.p.wait(10)
        time.sleep(1.2)
        status = got.status[-1]
        assert status["config_id"] == 2
        assert status["dynamic"] == []  # accel_x is no longer sent: the dynamic sub is dropped
        values = got.snapshot()
        mins = [v for v in values.get("sub_1", []) if v.topic == "usv.ins.accel_x"]
        assert len(mins) >= 2 and all(v.aggregation == "MIN" and v.period_s == "1.0" for v in mins)

        # the deployed model outlives the process
        sb.stop()
        sb2 = start_subbroker(tmp_path, cfg, tag="sb2")
        assert sb2.wait_log("running", 10), sb2.log()
        assert "kept in" in sb2.log()
        assert sb2.wait_log("19 streams sent", 5)
        assert (tmp_path / "state" / "deployed.json").exists()
        time.sleep(1.2)  # the client session reconnects by itself (connect/retry)

        # link down: an answer within the request's timeout, never silence
        pb.stop()
        time.sleep(0.3)
        t0 = time.monotonic()
        down = request(
            session,
            "modd/usv/deploy",
            signed({"text": s2.read_text(), "format": "json", "timeout_s": 1.0}),
        )
        assert down["status"] in ("LINK_DOWN", "TIMEOUT"), down
        assert time.monotonic() - t0 < 3
    finally:
        with processes(pb, sb, *(p for p in (sb2, load) if p)):
            pass
