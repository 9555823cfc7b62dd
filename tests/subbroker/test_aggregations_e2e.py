"""MEDIAN, STDDEV, RANGE and PERCENTILE(p) end to end on loopback, real processes (the C++
PubBroker, the publisher load, the SubBroker CLI, a zenoh client here): every
delivered window equals numpy's over the archive's samples of that window,
read with the official ``mcap`` reader. One MEDIAN is sent as such, another
is derived at the SubBroker from an ALL stream (the planner drops it), so both
the PubBroker's accumulator and the SubBroker's derivation are checked; so
are a PERCENTILE(95) sent (its p in CONFIG) and a PERCENTILE(90) derived."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from modd_plan.plan import make_plan
from subbroker_harness import (
    f32,
    free_port,
    model_copy,
    processes,
    read_archive,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

from conftest import Collector

pytestmark = [pytest.mark.usefixtures("needs_pubbroker"), pytest.mark.e2e]

RUN_S = 8.0
X, Y, Z = (f"usv.accelerometer.accel_{a}" for a in "xyz")
#: (name, topic, period, aggregation): scenario 1's subscriptions replaced
SUBS = [
    ("med_x", X, "1.0", "MEDIAN"),
    ("sd_x", X, "0.5", "STDDEV"),
    ("range_z", Z, "0.25", "RANGE"),
    ("all_y", Y, "0.25", "ALL"),
    ("med_y", Y, "1.0", "MEDIAN"),  # derived from all_y's ALL stream
    ("sd_y", Y, "0.5", "STDDEV"),  # derived from it too
    ("p95_x", X, "1.0", "PERCENTILE(95)"),
    ("p90_y", Y, "1.0", "PERCENTILE(90)"),  # derived from all_y's ALL stream
]
NUMPY: dict[str, Callable[[Any], Any]] = {
    "MEDIAN": np.median,
    "STDDEV": np.std,
    "RANGE": np.ptp,
    "PERCENTILE(95)": lambda x: np.percentile(x, 95),
    "PERCENTILE(90)": lambda x: np.percentile(x, 90),
}


def _sub(name: str, topic: str, period: str, label: str) -> dict[str, Any]:
    """A model's subscriber: PERCENTILE(p)'s p apart, as the model writes it."""
    aggregation, _, p = label.partition("(")
    sub = {"name": name, "topic": topic, "periodS": period, "aggregation": aggregation}
    return sub | ({"percentile": float(p.rstrip(")"))} if p else {})


def _model(tmp_path: Path) -> Path:
    path = model_copy(tmp_path, "scenario1.modd")
    model = json.loads(path.read_text())
    model["subscribers"] = [_sub(*s) for s in SUBS]
    path.write_text(json.dumps(model))
    plan = make_plan(model)
    sent = {(s.stream.topic, s.stream.aggregation) for s in plan.sent_streams}
    assert (X, "MEDIAN") in sent and (Y, "MEDIAN") not in sent, sent  # the premise
    assert (X, "PERCENTILE(95)") in sent and (Y, "PERCENTILE(90)") not in sent, sent
    return path


#: computed at the SubBroker from ALL's samples, in double (not sent as a float32)
DERIVED = {"med_y", "sd_y", "p90_y"}


def _check(name: str, aggregation: str, vals: list[Any], samples: list[tuple[int, Any]]) -> int:
    """numpy's value of every window: as the float32 the PubBroker sends, or in
    double when the SubBroker derived it (STDDEV: within float rounding)."""
    checked = 0
    for v in vals:
        window = np.array([x for t, x in samples if v.start_ns <= t < v.end_ns], np.float64)
        if window.size == 0:
            assert v.value is None, (name, v)
            continue
        want = float(NUMPY[aggregation](window))
        if name not in DERIVED:
            want = f32(want)  # float32 topics: a float32 value on the link
        tol = (
            (2e-7 if name not in DERIVED else 1e-12) * abs(want) if aggregation == "STDDEV" else 0.0
        )
        assert abs(v.value - want) <= tol, (name, v, want, window.size)
        checked += 1
    return checked


def test_median_stddev_range_percentile_equal_numpy_over_the_archive(
    tmp_path: Path, zenoh_client: Any
) -> None:
    model = _model(tmp_path)
    link, ingress, zport = free_port(), free_port(), free_port()
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    load = None
    try:
        wait_port(zport)
        session = zenoh_client(zport)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 10), sb.log()
        load = start_load(tmp_path, model, ingress, RUN_S, signal="uniform")
        load.p.wait(RUN_S + 15)
        time.sleep(1.5)
    finally:
        with processes(pb, sb, *([load] if load else [])):
            pass
    values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    assert set(values) == {n for n, *_ in SUBS}
    checked = {n: _check(n, a, values[n], archive[t]) for n, t, _, a in SUBS if a != "ALL"}
    minimum = {"1.0": RUN_S - 3, "0.5": 2 * RUN_S - 4, "0.25": 4 * RUN_S - 6}
    for n, _, p, a in SUBS:
        if a != "ALL":
            assert checked[n] >= minimum[p], (n, checked[n])


def test_a_percentile_outage_is_backfilled_with_numpys_values(
    tmp_path: Path, zenoh_client: Any
) -> None:
    """The link cut for 4 s: ``modd backfill --gaps`` asks the PubBroker for the
    PERCENTILE(95) windows it missed (the p in BACKFILL_REQUEST); every window,
    live or backfilled, equals numpy's over the archive, each once."""
    from subbroker_harness import Blackhole
    from test_backfill import check_complete, listen, run_cli, wait_live

    path = model_copy(tmp_path, "scenario1.modd")
    model = json.loads(path.read_text())
    model["subscribers"] = [_sub("p95_x", X, "1.0", "PERCENTILE(95)")]
    path.write_text(json.dumps(model))
    link, ingress, zport = free_port(), free_port(), free_port()
    pb = start_pubbroker(tmp_path, path, link, ingress)
    proxy = Blackhole(link)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, path, proxy.port, zport))
    load = None
    try:
        wait_port(zport, 60)
        got = listen(zenoh_client, zport)
        assert sb.wait_log("running", 60), sb.log()
        load = start_load(tmp_path, path, ingress, 60.0, signal="uniform")
        wait_live(got, "p95_x", 0)
        proxy.drop()
        time.sleep(4)
        proxy.restore()
        assert sb.wait_log("resuming config 1", 30), sb.log()
        wait_live(got, "p95_x", time.time_ns())
        asked = time.time_ns() - 1_000_000_000
        code, out, err = run_cli(zport, "--subscriber", "p95_x", "--gaps", "--json")
        assert code == 0, (out, err, sb.log()[-3000:], pb.log()[-2000:])
        figures = json.loads(out.strip().splitlines()[-1])
    finally:
        with processes(*(x for x in (pb, sb, load) if x is not None)):
            proxy.close()
    assert figures["windows"] >= 2 and figures["duplicates"] == 0, figures
    values = got.snapshot()["p95_x"]
    assert sum(v.backfilled for v in values) == figures["windows"]
    check_complete(values, 1_000_000_000, asked)
    archive = read_archive(tmp_path / "archive", path)
    backfilled = [v for v in values if v.backfilled]
    assert _check("p95_x", "PERCENTILE(95)", backfilled, archive[X]) == figures["windows"]
    assert _check("p95_x", "PERCENTILE(95)", values, archive[X]) > figures["windows"]  # live too
