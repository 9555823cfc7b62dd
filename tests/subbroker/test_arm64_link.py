"""The aarch64 PubBroker (build/cpp-arm64, runtime/cpp/scripts/test-arm64.sh) run under
qemu-user against the amd64 SubBroker over TCP, and over serial through the radio
emulator (modd-radio between two pseudo-terminals, a SiK-like radio), as a companion
computer and its base station would: a publisher load at scenario 1's rate, every
delivered window recomputed from the archive the arm64 broker wrote (read back here, on
amd64, with the official `mcap` reader), then a deploy of scenario 2 acknowledged by
the arm64 broker. A byte order, alignment or size assumption in the link codec or the
archive shows here."""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path
from typing import Any

import pytest
from modd.subbroker.client import request
from modd.zenoh_session import wait_connected
from radio_harness import start_pubbroker_dgram, start_radio_serial, subbroker_dgram_config
from subbroker_harness import (
    REPO,
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    processes,
    read_archive,
    signed,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

ARM64_PUBBROKER = REPO / "build" / "cpp-arm64" / "bin" / "modd-pubbroker"
QEMU = shutil.which("qemu-aarch64-static") or shutil.which("qemu-aarch64")
RUN_S = 6.0
#: A SiK radio at 64 kbps air rate with ECC off, lossless (the loss cases: test_radio_link.py).
SERIAL_RADIO = "rate=7200,packet=252,seed=3"


@pytest.fixture
def arm64_pubbroker() -> list[str]:
    # make test (CI) builds and installs both before this runs: missing there is a broken
    # set-up, a failure; a developer running this file alone is told what to run.
    missing = pytest.fail if os.environ.get("CI") else pytest.skip
    if not ARM64_PUBBROKER.exists():
        missing(
            f"{ARM64_PUBBROKER} is not built: runtime/cpp/scripts/test-arm64.sh builds it "
            "(make test runs it)"
        )
    if QEMU is None:
        missing("qemu-user is not installed: scripts/setup.sh arm64 installs it")
    assert QEMU is not None
    return [QEMU, str(ARM64_PUBBROKER)]


def start_pair(tmp: Path, transport: str, command: list[str]) -> tuple[Path, int, int, list[Proc]]:
    """(model, ingress port, zenoh port, [radio,] PubBroker, SubBroker) over ``transport``."""
    link, ingress, zport = free_port(), free_port(), free_port()
    model = model_copy(tmp, "scenario1.modd")
    if transport == "tcp":
        pb = start_pubbroker(tmp, model, link, ingress, command=command)
        return (
            model,
            ingress,
            zport,
            [pb, start_subbroker(tmp, subbroker_config(tmp, model, link, zport))],
        )
    radio, base, drone = start_radio_serial(tmp, SERIAL_RADIO)
    serial = {"transport": "serial", "device": drone, "port": 1}
    pb = start_pubbroker_dgram(tmp, model, serial, ingress, command=command)
    cfg = subbroker_dgram_config(tmp, model, "127.0.0.1:1", zport, "serial", device=base)
    return model, ingress, zport, [radio, pb, start_subbroker(tmp, cfg)]


@pytest.mark.parametrize("transport", ["tcp", "serial"])
def test_arm64_pubbroker_with_the_amd64_subbroker(
    transport: str, tmp_path: Path, zenoh_client: Any, arm64_pubbroker: list[str]
) -> None:
    model, ingress, zport, procs = start_pair(tmp_path, transport, arm64_pubbroker)
    pb, sb = procs[-2:]
    s2 = model_copy(tmp_path, "scenario2.modd")
    load = None
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        assert wait_connected(session)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("config 1 running", 30), sb.log() + pb.log()
        load = start_load(tmp_path, model, ingress, RUN_S)
        load.p.wait(RUN_S + 20)
        time.sleep(1.5 if transport == "tcp" else 3.0)  # the last windows close and travel
        values = got.snapshot()
        reply = request(
            session, "modd/usv/deploy", signed({"text": s2.read_text(), "format": "json"})
        )
    finally:
        with processes(*procs, *([load] if load else [])):
            pass
    assert reply["status"] == "ACKED" and reply["config_id"] == 2, reply
    if transport == "serial":  # through the radio's pseudo-terminals, not another path
        assert "authenticated over serial" in sb.log(), sb.log()
    assert "config 2 accepted" in pb.log()
    archive = read_archive(tmp_path / "archive", model)
    sent = json.loads(load.log().strip().splitlines()[-1])["sent"]
    assert {t: len(s) for t, s in archive.items()} == sent  # lossless archive, read on amd64
    n = check_against_archive(values, archive)
    assert n >= 40, (transport, n, {k: len(v) for k, v in values.items()})
