"""Backfill over a datagram link, end to end: the PubBroker's resend ring is
made tiny (256 B: two datagrams), so a 6 s radio outage leaves windows the
NACKs cannot recover; `modd backfill --gaps` then fills them from the
on-board archive, its BACKFILL_REQUEST and BACKFILL_DATA in CONTROL
datagrams through the emulator. Oracle: the archive."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import wait_connected
from radio_harness import (
    radio_counts,
    start_pubbroker_dgram,
    start_radio_udp,
    subbroker_dgram_config,
)
from subbroker_harness import (
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_subbroker,
    wait_port,
)
from test_backfill import check_complete, run_cli, wait_live

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

PERIOD_NS = 250_000_000


def missing_windows(values: list[Any], period_ns: int, until_ns: int) -> int:
    """How many windows of one period are absent between the first delivered one
    and ``until_ns``: what live delivery missed."""
    ends = sorted({v.end_ns for v in values if v.end_ns <= until_ns})
    return sum((b - a) // period_ns - 1 for a, b in zip(ends, ends[1:], strict=False))


def test_backfill_over_udp_fills_what_the_ring_lost(tmp_path: Path, zenoh_client: Any) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    zport, ingress, port, relay = free_port(), free_port(), free_port("udp"), free_port("udp")
    pb = start_pubbroker_dgram(
        tmp_path, model, {"transport": "udp", "port": port, "ring_bytes": 256}, ingress
    )
    sb = start_subbroker(
        tmp_path, subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{relay}", zport, "udp")
    )
    radio: Proc | None = None
    load: Proc | None = None
    try:
        wait_port(zport, 40)
        session = zenoh_client(zport)
        assert wait_connected(session, 5)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)  # values and status
        radio = start_radio_udp(tmp_path, port, "latency_ms=20,outage=5+6,seed=3", relay=relay)[0]
        assert sb.wait_log("running", 30), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, 40.0)
        time.sleep(max(0.0, radio.started + 11.0 - time.monotonic()))  # the outage's end
        wait_live(got, "sub_5", time.time_ns())
        time.sleep(8.0)  # the NACKs of the outage's slots, answered "too old", given up
        asked = time.time_ns() - 1_000_000_000
        holes = missing_windows(got.snapshot().get("sub_5", []), PERIOD_NS, asked)
        code, out, err = run_cli(
            zport, "--subscriber", "sub_5", "--gaps", "--json", "--timeout", "40"
        )
        assert code == 0, (out, err, sb.log()[-3000:], pb.log()[-2000:])
        figures = json.loads(out.strip().splitlines()[-1])
        time.sleep(0.5)
        values = got.snapshot()
        archive = read_archive(tmp_path / "archive", model)
        counts = radio_counts(radio)
        status = got.status[-1]["radio"]
    finally:
        with processes(*(p for p in (radio, pb, sb, load) if p is not None)):
            pass
    assert "outage" in counts, counts
    assert status["slots_lost"] > 0, status  # the ring could not answer
    # the outage's 6 s of sub_5 are 24 windows: most must have been lost for the
    # ring (256 B) to be what failed, and every window live missed is backfilled
    assert holes >= 8, (holes, status)
    assert figures["windows"] >= holes and figures["duplicates"] == 0, (figures, holes, status)
    back = [v for v in values["sub_5"] if v.backfilled]
    assert len(back) == figures["windows"]
    assert check_against_archive({"sub_5": values["sub_5"]}, archive) > 40  # the oracle
    check_complete(values["sub_5"], PERIOD_NS, asked)
