"""Backfill of event subscriptions (ON_CHANGE, THRESHOLD) end to end, real processes on
loopback: the scripted signal (steps, a ramp, noise around the threshold, flapping)
through the C++ PubBroker, the link cut in a proxy for CUT_S seconds, then `backfill
gaps` for every event subscriber. The PubBroker re-derives the lost windows' events from
its archive, its detector's state rebuilt from the config's epoch (docs/protocol.md,
"Backfill of events"); one subscription (BY_POLICY) has `backfill = gaps` in the
model and is filled by the SubBroker by itself. The oracle is the reference definition
(modd_contracts.events) over the archive read with the official ``mcap`` reader: every
event it implies is delivered exactly once, live or backfilled, in its window (coalesced
beyond N), and the backfilled windows are marked so."""

from __future__ import annotations

import json
import re
import time
from pathlib import Path
from typing import Any

import pytest
from subbroker_harness import (
    Blackhole,
    free_port,
    processes,
    read_archive,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)
from test_backfill import CUT_S, ask, listen, wait_live
from test_events_e2e import SUBS, check_event_windows
from test_events_e2e import _model as events_model

pytestmark = [pytest.mark.usefixtures("needs_pubbroker"), pytest.mark.e2e]


def _backfill(session: Any, name: str, timeout_s: float = 60) -> dict[str, Any]:
    job = ask(session, {"op": "start", "subscriber": name, "gaps": True})
    assert job["status"] in ("RUNNING", "DONE"), job
    deadline = time.monotonic() + timeout_s
    while (p := ask(session, {"op": "progress", "id": job["id"]}))["status"] == "RUNNING":
        assert time.monotonic() < deadline, p
        time.sleep(0.2)
    return p


#: filled by the SubBroker by itself (its model's policy); the others are asked for
BY_POLICY = "thd_z"


def test_a_cut_links_events_are_backfilled_exactly_once(tmp_path: Path, zenoh_client: Any) -> None:
    model = events_model(tmp_path)
    doc = json.loads(model.read_text())
    for sub in doc["subscribers"]:
        if sub["name"] == BY_POLICY:
            sub["backfill"] = "gaps"
    model.write_text(json.dumps(doc))
    link, ingress, zport = free_port(), free_port(), free_port()
    pb = start_pubbroker(tmp_path, model, link, ingress)
    proxy = Blackhole(link)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, proxy.port, zport))
    load = None
    jobs: dict[str, dict[str, Any]] = {}
    try:
        wait_port(zport, 60)
        got = listen(zenoh_client, zport)
        session = zenoh_client(zport)
        assert sb.wait_log("running", 60), sb.log()
        load = start_load(tmp_path, model, ingress, CUT_S + 120, signal="scripted")
        wait_live(got, "on_x", 0)
        time.sleep(2)
        proxy.drop()
        time.sleep(CUT_S)
        proxy.restore()
        assert sb.wait_log("resuming config 1", 30), sb.log()
        wait_live(got, "on_x", time.time_ns())
        time.sleep(1.5)  # windows ending before the request are the backfill's
        for sub in SUBS:
            if sub["name"] != BY_POLICY:
                jobs[sub["name"]] = _backfill(session, sub["name"])
        assert sb.wait_log(f"for {BY_POLICY}: DONE", 30), sb.log()[-3000:]
        found = re.search(rf"backfill (\d+) for {BY_POLICY}: DONE", sb.log())
        assert found, sb.log()[-3000:]
        jobs[BY_POLICY] = ask(session, {"op": "progress", "id": int(found.group(1))})
        time.sleep(1.5)
    finally:
        with processes(*(x for x in (pb, sb, load) if x is not None)):
            proxy.close()
    values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    backfilled = 0
    for sub in SUBS:
        name = sub["name"]
        job = jobs[name]
        assert job["status"] == "DONE" and job["duplicates"] == 0, (name, job, sb.log()[-3000:])
        mine = values[name]
        starts = [v.start_ns for v in mine]
        assert len(starts) == len(set(starts)), (name, "a window delivered twice")
        back = [v for v in mine if v.backfilled]
        assert len(back) == job["windows"], (name, job, len(back))
        # every event the definition implies over the archive, once, live or backfilled
        check_event_windows(sub, mine, archive[sub["topic"]])
        backfilled += sum(v.count or 0 for v in back)
        print(f"events backfill: {name} {len(back)} windows, {job['bytes']} B")
    # the cut lost events of every kind (the script repeats every 10 s)
    assert backfilled >= 4 * CUT_S, backfilled
    assert all(any(v.backfilled for v in values[s["name"]]) for s in SUBS[:3])
