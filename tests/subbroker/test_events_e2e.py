"""ON_CHANGE and THRESHOLD end to end on loopback, real processes (the C++
PubBroker, the publisher load with a scripted signal: steps, a ramp, noise
around the threshold, a flapping signal; the SubBroker CLI; a zenoh client
here). The oracle is the reference definition (modd_contracts.events) run over
the archive's samples, read with the official ``mcap`` reader: every event it
implies is delivered in its window (the first N - 1, then the newest, the
rest counted as coalesced), none other; THRESHOLD's events alternate and leave
the hysteresis band; an alert's stream carries both crossings (its way back);
each window's value, as the link codec writes it, is within the plan's worst
case, and so are the link's bytes a second."""

from __future__ import annotations

import json
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.frames import Aggregation, Value, ValueType, value_kind
from modd_contracts.events import EventSpec, implied, parse_label
from modd_contracts.labels import of_subscriber
from modd_plan.linkcost import event_window_bytes
from modd_plan.plan import make_plan
from subbroker_harness import (
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

RUN_S = 14.0
X, Y, Z = (f"usv.accelerometer.accel_{a}" for a in "xyz")
SUBS: list[dict[str, Any]] = [
    {
        "name": "on_x",
        "topic": X,
        "periodS": "1.0",
        "aggregation": "ON_CHANGE",
        "deadband": 0.5,
        "maxEvents": 4,
    },
    {
        "name": "onp_y",
        "topic": Y,
        "periodS": "1.0",
        "aggregation": "ON_CHANGE",
        "deadbandPercent": 10,
    },
    {
        "name": "th_x",
        "topic": X,
        "periodS": "1.0",
        "aggregation": "THRESHOLD",
        "level": 5.0,
        "hysteresis": 0.2,
        "maxEvents": 3,
    },
    {
        "name": "thd_z",
        "topic": Z,
        "periodS": "0.5",
        "aggregation": "THRESHOLD",
        "level": 5.0,
        "hysteresis": 0.5,
        "crossing": "down",
    },
    {  # an alert (issue 45, item 3): its stream reports both crossings, so its way back is seen
        "name": "alert_z",
        "topic": Z,
        "periodS": "0.5",
        "aggregation": "THRESHOLD",
        "level": 5.0,
        "hysteresis": 0.5,
        "crossing": "down",
        "alert": ["scientist", "operator"],
    },
]


def _model(tmp_path: Path) -> Path:
    path = model_copy(tmp_path, "scenario1.modd")
    model = json.loads(path.read_text())
    model["subscribers"] = SUBS
    path.write_text(json.dumps(model))
    return path


def _spec(sub: dict[str, Any]) -> EventSpec:
    return parse_label(of_subscriber(sub)).spec


def check_event_windows(
    sub: dict[str, Any], values: list[Any], samples: list[tuple[int, Any]]
) -> int:
    """Every delivered window holds what the definition implies in it (bounded
    by N, coalesced beyond), and every implied event is in a delivered window."""
    spec = _spec(sub)
    every = implied(spec, samples)
    seen = 0
    for v in values:
        mine = [(t, x) for t, x in every if v.start_ns <= t < v.end_ns]
        assert mine, (sub["name"], "a window no event implies", v)
        kept = mine if len(mine) <= spec.max_events else [*mine[: spec.max_events - 1], mine[-1]]
        want_ns = [v.start_ns + (t - v.start_ns) // 1000 * 1000 for t, _ in kept]
        assert v.value == [x for _, x in kept], (sub["name"], v, mine)
        assert v.event_ns == want_ns, (sub["name"], v.event_ns, want_ns)
        assert v.coalesced == len(mine) - len(kept) and v.count == len(mine), (sub["name"], v)
        seen += len(mine)
    first, last = min(v.start_ns for v in values), max(v.end_ns for v in values)
    inside = [e for e in every if first <= e[0] < last]
    assert seen == len(inside), (sub["name"], seen, len(inside))  # none missed in the run
    return seen


def _check_hysteresis(sub: dict[str, Any], values: list[Any]) -> None:
    level, h = sub["level"], sub.get("hysteresis", 0.0)
    events = [x for v in sorted(values, key=lambda v: v.start_ns) for x in v.value]
    assert all(x > level + h or x < level - h for x in events), sub["name"]
    if sub.get("crossing", "both") == "both" and not any(v.coalesced for v in values):
        sides = [x > level for x in events]
        assert all(a != b for a, b in zip(sides, sides[1:], strict=False)), sub["name"]


def _event_values(values: list[Any]) -> list[float]:
    """The events of a subscription's windows, in time order."""
    out: list[float] = []
    for v in sorted(values, key=lambda v: v.start_ns):
        assert isinstance(v.value, list), v
        out += [float(x) for x in v.value]
    return out


def _window_bytes(values: list[Any]) -> list[int]:
    """Each window's value as the link codec writes it (float32 topics)."""
    kind = value_kind(ValueType.FLOAT32, Aggregation.ON_CHANGE)
    out = []
    for v in values:
        times = [(t - v.start_ns) // 1000 for t in v.event_ns]
        b = bytearray()
        codec._put_value(
            b, kind, Value(True, samples=v.value, times_us=times, coalesced=v.coalesced)
        )
        out.append(len(b))
    return out


def test_on_change_and_threshold_deliver_every_implied_event_within_the_plan(
    tmp_path: Path, zenoh_client: Any
) -> None:
    model = _model(tmp_path)
    plan = make_plan(json.loads(model.read_text()))
    link, ingress, zport = free_port(), free_port(), free_port()
    pb = start_pubbroker(tmp_path, model, link, ingress)
    sb = start_subbroker(tmp_path, subbroker_config(tmp_path, model, link, zport))
    load = None
    try:
        wait_port(zport, 60)
        session = zenoh_client(zport)
        got = Collector()
        session.declare_subscriber("modd/usv/**", got.on_sample)
        assert sb.wait_log("running", 60), sb.log()
        load = start_load(tmp_path, model, ingress, RUN_S, signal="scripted")
        load.p.wait(RUN_S + 15)
        time.sleep(1.5)
    finally:
        with processes(pb, sb, *([load] if load else [])):
            pass
    values = got.snapshot()
    archive = read_archive(tmp_path / "archive", model)
    assert set(values) == {s["name"] for s in SUBS}, (set(values), sb.log()[-2000:])
    for sub in SUBS:
        seen = check_event_windows(sub, values[sub["name"]], archive[sub["topic"]])
        assert seen >= 5, (sub["name"], seen)
        if sub["aggregation"] == "THRESHOLD":
            _check_hysteresis(sub, values[sub["name"]])
    assert any(v.coalesced for v in values["th_x"])  # the flapping part went beyond N = 3
    # the alert's windows hold both crossings, alternating (the DOWN ones are thd_z's)
    downs = _event_values(values["thd_z"])
    alert = _event_values(values["alert_z"])
    alert_downs = [x for x in alert if x < 5.0]
    n = min(len(downs), len(alert_downs))
    assert n >= 5 and alert_downs[:n] == downs[:n], (alert_downs, downs)
    assert any(x > 5.5 for x in alert) and all(
        (a > 5.0) != (b > 5.0) for a, b in zip(alert, alert[1:], strict=False)
    ), alert
    for sub in SUBS:
        period_us = int(float(sub["periodS"]) * 1_000_000)
        samples = 25 * float(sub["periodS"])  # 25 Hz

        bound = event_window_bytes(of_subscriber(sub), "float32", Fraction(samples), period_us)
        measured = _window_bytes(values[sub["name"]])
        assert max(measured) <= bound, (sub["name"], max(measured), bound)
        print(f"events: {sub['name']} window value at most {max(measured)} B, plan {bound} B")
    # the plan sizes the link for every window at its worst: the link bytes the
    # SubBroker read (every frame, handshake and STATUS included) stay under the
    # plan's drone-to-base bytes a second over the load's run
    read = max(status["bytes_in"] for status in got.status)
    print(f"events: link {read / RUN_S:.1f} B/s read, plan at most {plan.link.drone_to_base} B/s")
    assert 0 < read / RUN_S <= plan.link.drone_to_base, (read, plan.link)
