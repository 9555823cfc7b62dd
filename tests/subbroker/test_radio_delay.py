"""A deploy that changes the link's accepted delay takes effect on a datagram
link (issue 14, item 2; docs/protocol.md, "CONFIG"): scenario 1 over udp
through the radio emulator, the configured model (1 s, the default), then a
deployed copy whose ``Link.delay`` is 0.25 s. The CONFIG carries the new delay,
the PubBroker packs with it from its ack on, and the SubBroker expects it.
Measured on the wire, on the SubBroker's side (slots per DATA datagram, from
its received-datagram counters) and on the emulator's (datagrams passed per
second); delivery complete, with the on-board archive as the oracle."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from radio_harness import start_pubbroker_dgram, start_radio_udp, subbroker_dgram_config
from subbroker_harness import (
    Proc,
    check_against_archive,
    free_port,
    load_counts,
    model_copy,
    processes,
    read_archive,
    signed,
    start_load,
    start_subbroker,
)
from test_radio_link import _delivered_share, _watch

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")


def _radio(got: Collector) -> dict[str, Any]:
    for status in reversed(list(got.status)):
        if status.get("radio"):
            return dict(status["radio"])
    raise AssertionError("no status with radio figures")


def _passed(radio: Proc) -> tuple[float, int]:
    """When, and how many datagrams the emulator has passed drone -> base (its
    report, every second)."""
    lines = [ln for ln in radio.log().splitlines() if ln.startswith("radio:")]
    m = re.search(r"drone->base passed (\d+)", lines[-1]) if lines else None
    assert m is not None, radio.log()[-2000:]
    return time.monotonic(), int(m.group(1))


def test_a_deploy_changes_the_packing_delay(tmp_path: Path, zenoh_client: Any) -> None:
    model = model_copy(tmp_path, "scenario1.modd")  # no Link block: 1 s accepted delay
    fast = tmp_path / "scenario1-fast.json"
    doc = json.loads(model.read_text())
    doc["link"] = {**doc.get("link", {}), "acceptedDelayS": "0.25"}
    fast.write_text(json.dumps(doc))
    zport, ingress, port = free_port(), free_port(), free_port("udp")
    pb = start_pubbroker_dgram(tmp_path, model, {"transport": "udp", "port": port}, ingress)
    radio, endpoint = start_radio_udp(tmp_path, port, "latency_ms=5,seed=2")
    cfg = subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{endpoint}", zport, "udp")
    sb = start_subbroker(tmp_path, cfg)
    seconds = 12.0
    with processes(radio, pb, sb):
        got = _watch(zenoh_client, zport)
        assert sb.wait_log("running", 20), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, seconds)
        time.sleep(1.5)  # the first slots, the sync
        a, wa = _radio(got), _passed(radio)
        time.sleep(4.0)
        b, wb = _radio(got), _passed(radio)
        assert b["accepted_delay_s"] == 1.0
        body = signed(
            {
                "text": fast.read_text(),
                "format": "json",
                "project_id": 7,
                "revision": 2,
                "deployed_by": "operator",
            }
        )
        reply = request(zenoh_client(zport), "modd/usv/deploy", body, timeout_s=15)
        assert reply["status"] == "ACKED", reply
        time.sleep(1.5)  # the switch date, the last datagram packed the old way
        c, wc = _radio(got), _passed(radio)
        assert c["accepted_delay_s"] == 0.25, c
        time.sleep(4.0)
        d, wd = _radio(got), _passed(radio)
        load.p.wait(seconds + 20)
        time.sleep(2.0)
        with processes(load):
            pass
        values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)

    def per_datagram(x: dict[str, Any], y: dict[str, Any]) -> float:
        return float(
            (y["slots_received"] - x["slots_received"]) / (y["datagrams_in"] - x["datagrams_in"])
        )

    before, after = per_datagram(a, b), per_datagram(c, d)
    # 4 slots/s (0.25 s windows): up to 1 s, 4 or 5 slots a datagram; up to 0.25 s, 1 or 2
    assert before >= 3.5, (before, a, b)
    assert after <= 2.2, (after, c, d)
    assert b["nacks"] == d["nacks"] == 0 and d["forged"] == 0, d
    # the emulator's count (drone -> base datagrams a second): 0.8/s -> 2/s; its report
    # comes every second, so each figure may be a second stale (hence 1.4, not 2.5)
    rate_before = (wb[1] - wa[1]) / (wb[0] - wa[0])
    rate_after = (wd[1] - wc[1]) / (wd[0] - wc[0])
    print(
        f"slots a datagram {before:.2f} -> {after:.2f}; "
        f"emulator drone->base datagrams/s {rate_before:.2f} -> {rate_after:.2f}"
    )
    assert rate_after >= 1.4 * rate_before, (rate_before, rate_after)
    # delivery complete across the switch: the archive is the oracle
    assert {t: len(s) for t, s in archive.items()} == load_counts(load)
    assert check_against_archive(values, archive) > 100
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, sorted(missing)
