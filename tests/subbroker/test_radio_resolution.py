"""Declared resolution end to end (issue 34, item 1): scenario 1 with 0.01 m/s²
on the accelerometer, the real PubBroker and SubBroker over serial through
modd-radio at 5 % loss. Every delivered window is within half a step of the
window recomputed from the on-board archive (the official mcap reader), every
window arrives (NACKs repair the loss; no datagram corrupts another), and the
drone->base bytes through the emulator are about half of the float32 link's."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

import pytest
from radio_harness import (
    radio_counts,
    start_pubbroker_dgram,
    start_radio_serial,
    subbroker_dgram_config,
)
from subbroker_harness import (
    free_port,
    load_counts,
    model_copy,
    oracle_value,
    processes,
    read_archive,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    window_samples,
)
from test_radio_link import _delivered_share, _watch

pytestmark = pytest.mark.usefixtures("needs_pubbroker")

STEP = 0.01
SECONDS = 10.0
PASSED = re.compile(r"drone->base passed \d+ \((\d+) B\)")


def _with_resolution(tmp: Path) -> Path:
    model = model_copy(tmp, "scenario1.modd")
    doc = json.loads(model.read_text())
    for v in doc["drone"]["sensors"][0]["variables"]:
        v["resolution"] = STEP
    model.write_text(json.dumps(doc))
    return model


def _check_within_half_a_step(values: dict[str, list[Any]], archive: Any) -> int:
    checked = 0
    for name, vals in values.items():
        for v in vals:
            samples = window_samples(archive.get(v.topic, []), v.start_ns, v.end_ns)
            want, count = oracle_value(v.aggregation, samples)
            assert abs(v.value - want) <= STEP / 2 + 1e-9, (name, v, want)
            if v.aggregation == "AVERAGE":
                assert v.count == count, (name, v, count)
            if float(v.period_s) == 0.25:  # as sent: whole steps (the 2 s ones are merged)
                assert abs(v.value / STEP - round(v.value / STEP)) < 1e-6, (name, v)
            checked += 1
    return checked


def test_quantised_scenario1_over_serial_at_5_percent_loss(
    tmp_path: Path, zenoh_client: Any
) -> None:
    model = _with_resolution(tmp_path)
    zport, ingress = free_port(), free_port()
    radio, base, drone = start_radio_serial(tmp_path, "loss=0.05,latency_ms=40,seed=5")
    pb = start_pubbroker_dgram(
        tmp_path, model, {"transport": "serial", "device": drone, "port": 1}, ingress
    )
    cfg = subbroker_dgram_config(tmp_path, model, "127.0.0.1:1", zport, "serial", device=base)
    sb = start_subbroker(tmp_path, cfg)
    with processes(radio, pb, sb):
        got = _watch(zenoh_client, zport)
        assert sb.wait_log("running", 20), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, SECONDS)
        time.sleep(2.0)
        m0 = PASSED.search(radio_counts(radio))
        t0 = time.monotonic()
        load.p.wait(SECONDS + 20)
        m1 = PASSED.search(radio_counts(radio))
        t1 = time.monotonic()
        time.sleep(4.0)  # the last NACKs answered
        with processes(load):
            pass
        values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    assert {t: len(s) for t, s in archive.items()} == load_counts(load)  # the archive is exact
    assert _check_within_half_a_step(values, archive) > 100
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, sorted(missing)
    assert m0 and m1
    rate = (int(m1.group(1)) - int(m0.group(1))) / (t1 - t0)
    print(f"drone->base {rate:.1f} B/s through the emulator (5 % loss, resends included)")
    assert rate < 60, rate  # the float32 link: 81.6 B/s without loss


def test_quantised_scenario1_over_tcp(tmp_path: Path, zenoh_client: Any) -> None:
    """Over tcp every DATA frame is a unit of its own: each value its absolute steps."""
    model = _with_resolution(tmp_path)
    link, ingress, zport = free_port(), free_port(), free_port()
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    with processes(pb, sb):
        got = _watch(zenoh_client, zport)
        assert sb.wait_log("running", 20), sb.log()[-3000:]
        load = start_load(tmp_path, model, ingress, 6.0)
        load.p.wait(30)
        time.sleep(1.5)
        with processes(load):
            pass
        values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    assert _check_within_half_a_step(values, archive) > 60
    share, missing = _delivered_share(values, archive)
    assert share == 1.0, sorted(missing)
