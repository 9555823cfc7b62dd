"""Backfill over a datagram link (udp; serial shares the SubBroker's datagram code), real
processes through the radio emulator: after an outage, `modd backfill --gaps` for a
subscriber ends DONE (exit 0) with every missed window delivered once, each equal to the
aggregate recomputed from the on-board archive (the official `mcap` reader: the oracle).
Over datagrams a backfill's END shares a control datagram with its PROGRESS; a SubBroker
that read only the first frame left the job RUNNING for ever.

The datagram link repairs a short outage by itself (NACKs, the PubBroker's resend ring,
which also gets through the catch-up of a slow radio: 600 B/s with a 0.3 s queue here);
the ring is made tiny (`link.ring_bytes`), so that the outage's windows stay missing
and only the backfill can fill them."""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import wait_connected
from radio_harness import (
    start_pubbroker_dgram,
    start_radio_serial,
    start_radio_udp,
    subbroker_dgram_config,
)
from subbroker_harness import (
    PYTHON,
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    shared_credentials,
    start_load,
    start_subbroker,
    wait_port,
)

from conftest import Collector

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

OUTAGE_AT_S, OUTAGE_S = 25.0, 10.0  # from the radio's start: the config runs by then
PERIOD_NS = 250_000_000  # sub_5: accel_z MIN every 0.25 s


def _backfill(zport: int, subscriber: str) -> tuple[int, str, str]:
    env = {**os.environ, "MODD_ZENOH_CREDENTIALS": str(shared_credentials().cred_file("backend"))}
    p = subprocess.run(
        [
            str(PYTHON),
            "-m",
            "modd_model.cli",
            "backfill",
            "--drone",
            "usv",
            "--connect",
            f"tcp/127.0.0.1:{zport}",
            "--subscriber",
            subscriber,
            "--gaps",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=90,
        env=env,
    )
    return p.returncode, p.stdout, p.stderr


@pytest.mark.parametrize("transport", ["udp"])
def test_backfill_after_an_outage_ends_done(
    transport: str, tmp_path: Path, zenoh_client: Any
) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    zport, ingress = free_port(), free_port()
    spec = f"rate=600,queue_s=0.3,outage={OUTAGE_AT_S}+{OUTAGE_S},seed=1"
    began = time.monotonic()
    if transport == "udp":
        port = free_port("udp")
        pb = start_pubbroker_dgram(
            tmp_path, model, {"transport": "udp", "port": port, "ring_bytes": 256}, ingress
        )
        radio, relay = start_radio_udp(tmp_path, port, spec)
        cfg = subbroker_dgram_config(tmp_path, model, f"127.0.0.1:{relay}", zport, "udp")
    else:
        radio, base, drone = start_radio_serial(tmp_path, spec)
        pb = start_pubbroker_dgram(
            tmp_path,
            model,
            {"transport": "serial", "device": drone, "port": 1, "ring_bytes": 256},
            ingress,
        )
        cfg = subbroker_dgram_config(tmp_path, model, "127.0.0.1:1", zport, "serial", device=base)
    sb = start_subbroker(tmp_path, cfg)
    load = None
    with processes(radio, pb, sb):
        wait_port(zport, 40)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/sub/*", got.on_sample)
        assert sb.wait_log("running", 40), sb.log()[-2000:]
        load = start_load(tmp_path, model, ingress, OUTAGE_AT_S + OUTAGE_S + 60)
        with processes(load):
            if time.monotonic() - began > OUTAGE_AT_S - 3:
                pytest.fail("the SubBroker ran too late to see the outage (a loaded machine)")
            time.sleep(max(0.0, OUTAGE_AT_S + OUTAGE_S + 4 - (time.monotonic() - began)))
            deadline = time.monotonic() + 30  # live values again after the outage
            outage_end_ns = time.time_ns() - 4 * 10**9
            while not any(
                v.end_ns > outage_end_ns and not v.backfilled
                for v in got.snapshot().get("sub_5", [])
            ):
                assert time.monotonic() < deadline, "no live value after the outage"
                time.sleep(0.2)
            code, out, err = _backfill(zport, "sub_5")
            assert code == 0, (out, err, sb.log()[-3000:])
            fig = json.loads(out.strip().splitlines()[-1])
            time.sleep(0.5)  # the last values reach the subscriber
    assert fig["duplicates"] == 0, fig
    assert fig["windows"] >= 1, fig  # what the radio's overflow lost
    values = got.snapshot()
    filled = [v for v in values["sub_5"] if v.backfilled]
    assert len(filled) == fig["windows"]
    assert (
        check_against_archive({"sub_5": values["sub_5"]}, read_archive(tmp_path / "archive", model))
        > 40
    )
    ends = sorted(v.end_ns for v in values["sub_5"])
    assert len(ends) == len(set(ends)), "a window delivered twice"
    lo, hi = min(v.end_ns for v in filled), max(v.end_ns for v in filled)
    assert [e for e in ends if lo <= e <= hi] == list(range(lo, hi + 1, PERIOD_NS))
