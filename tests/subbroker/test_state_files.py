"""State files never stop the base station, end to end: the real SubBroker is started
on a state directory whose window record (`windows.json`) is damaged or hostile in each
way issue 38 found (``"received": []``, a ``1e400``, nesting 100,000 deep, 10^6
recorded configs, garbage bytes) and with a kept deployment and dynamic subscriptions
that are not JSON; each time it starts, sets the file aside with a message naming it,
and delivers live values within 5 s of its start (was: a crash at start, five restarts
under `modd up` and a stopped run; 38 s and 1.17 GB for 10^6 configs). The
structure-aware fuzz of the readers is runtime/python/tests/test_state_files.py."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest
from modd.zenoh_session import wait_connected
from subbroker_harness import (
    free_port,
    model_copy,
    processes,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

pytestmark = [pytest.mark.e2e, pytest.mark.usefixtures("needs_pubbroker")]

T0 = 1_796_000_000 * 10**9
EPOCH = '{"mission":"m","config_id":1,"due":[["sub_1","usv.a.x/MIN/2","usv.a.x/MIN/0.25","m","float32"]],"epoch_ns":%d}'  # noqa: E501
CASES: dict[str, bytes] = {
    "received is a list": b'{"epochs": [], "received": [], "filled": []}',
    "1e400": b'{"epochs": [{"mission": "m", "config_id": 1, "epoch_ns": 1e400, "due": []}],'
    b' "received": {}, "filled": []}',
    "nested 100,000 deep": b"[" * 100_000 + b"]" * 100_000,
    "10^6 configs": (
        '{"epochs":[' + ",".join(EPOCH % (T0 + i) for i in range(1_000_000)) + "],"
        '"received":{},"filled":[]}'
    ).encode(),
    "garbage bytes": bytes(range(256)) * 256,
}
START_S = 5.0


def first_value_after(zport: int, zenoh_client: Any, began: float, timeout_s: float) -> float:
    """Seconds from ``began`` to the first value delivered on zenoh."""
    wait_port(zport, timeout_s)
    session = zenoh_client(zport)
    assert wait_connected(session, timeout_s)
    got = Collector()
    session.declare_subscriber("modd/usv/sub/*", got.on_sample)
    while not any(got.snapshot().values()):
        assert time.monotonic() - began < timeout_s, "no value delivered"
        time.sleep(0.02)
    return time.monotonic() - began


def test_the_subbroker_starts_and_delivers_whatever_its_state_files_hold(
    tmp_path: Path, zenoh_client: Any
) -> None:
    model = model_copy(tmp_path, "scenario1.modd")
    link, ingress = free_port(), free_port()
    pb = start_pubbroker(tmp_path, model, link, ingress)
    load = start_load(tmp_path, model, ingress, 20.0 * len(CASES) + 30)
    state = tmp_path / "state"
    took: dict[str, float] = {}
    with processes(pb, load):
        for n, (what, raw) in enumerate(CASES.items()):
            state.mkdir(exist_ok=True)
            (state / "windows.json").write_bytes(raw)
            if n == 0:  # and the other state files, damaged too, once
                (state / "deployed.json").write_bytes(b'{"model": {"na')
                (state / "dynamic.json").write_bytes(b"\xff" * 100)
            zport = free_port()
            cfg = subbroker_config(tmp_path, model, link, zport, state_dir=state, tag=f"sb{n}")
            began = time.monotonic()
            sb = start_subbroker(tmp_path, cfg, tag=f"sb{n}")
            with processes(sb):
                took[what] = first_value_after(zport, zenoh_client, began, 30.0)
                log = sb.log()
            assert f"state file {state / 'windows.json'} cannot be used" in log, (what, log)
            assert "set aside as windows.json.bad-" in log, (what, log)
            assert "Traceback" not in log, (what, log)
            if n == 0:
                for name in ("deployed.json", "dynamic.json"):
                    assert f"state file {state / name} cannot be used" in log, log
            assert not (state / "windows.json").exists() or json.loads(
                (state / "windows.json").read_text()
            ), what  # set aside; the new record is written afresh
    print("start to first value:", {k: round(v, 2) for k, v in took.items()})
    slow = {k: v for k, v in took.items() if v > START_S}
    assert not slow, slow
