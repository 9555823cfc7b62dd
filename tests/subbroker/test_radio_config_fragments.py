"""Scenario 2 deployed over a serial telemetry radio of 252-byte packets (a SiK
radio's): its CONFIG (19 topics with their names) does not fit one packet, so
the SubBroker sends it as control fragments (0x42) that the PubBroker puts
back together; with loss, a CONFIG whose ack does not come is sent again
whole. The emulator drops any frame larger than the packet, so the deploy only
runs if every datagram fits. Oracle: the on-board archive (every delivered
window equals the one recomputed from the archived samples)."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.datagram import BASE_TO_DRONE, encode_control
from modd.subbroker.planning import config_for
from modd.zenoh_session import wait_connected
from modd_plan import make_plan
from modd_plan.linkbudget import datagram_capacity
from radio_harness import (
    radio_counts,
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
)
from subbroker_harness import (
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

PACKET = 252


def _model(tmp: Path) -> Path:
    path = model_copy(tmp, "scenario2.modd")
    model = json.loads(path.read_text())
    model["link"] = {"transport": "serial", "device": "/dev/null", "maxPacket": PACKET}
    path.write_text(json.dumps(model))
    return path


@pytest.mark.parametrize("loss", [0.0, 0.1])
def test_scenario2_deploys_over_a_sik_radio_in_control_fragments(
    loss: float, tmp_path: Path, zenoh_client: Any
) -> None:
    model = _model(tmp_path)
    config = config_for(make_plan(json.loads(model.read_text())), 1)
    one_datagram = len(encode_control(1 << 20, codec.encode(config), bytes(32), BASE_TO_DRONE))
    assert one_datagram > datagram_capacity("serial", PACKET)  # it has to be cut
    spec = f"packet={PACKET},loss={loss},latency_ms=20,seed=5"
    radio, base, drone = start_radio_serial(tmp_path, spec)
    zport, ingress = free_port(), free_port()
    pb = start_pubbroker_dgram(
        tmp_path,
        model,
        {"transport": "serial", "device": drone, "port": 1, "max_packet": PACKET},
        ingress,
    )
    sb = start_subbroker(
        tmp_path,
        subbroker_dgram_config(tmp_path, model, "127.0.0.1:1", zport, "serial", device=base),
    )
    with processes(radio, pb, sb):
        wait_port(zport, 40)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 30), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, 8.0)
        load.p.wait(30)
        time.sleep(3.0)  # the last slots and, under loss, their NACKs
        with processes(load):
            pass
        values = got.snapshot()
        archive = read_archive(tmp_path / "archive", model)
        counts = radio_counts(radio)
    assert "BAD_CONFIG" not in sb.log() and "no CONFIG_ACK" not in sb.log(), sb.log()[-2000:]
    assert "oversize" not in counts, counts  # every datagram within the packet
    # windows of (nearly) every subscription arrive and equal the archive's
    assert check_against_archive(values, archive) > 40, (values.keys(), counts)
    names = {s["name"] for s in json.loads(model.read_text())["subscribers"]}
    assert len(names & set(values)) >= len(names) - 2, (sorted(names - set(values)), counts)
