"""Model → field mappings and message intervals; the rate-request state machine
on its own (no sockets, time passed in)."""

from __future__ import annotations

import math
from typing import Any

import pytest
from mavlink_harness import REPO, Autopilot, load_model
from modd.mavlink.autopilot import Autopilot as AutopilotState
from modd.mavlink.decode import Decoder
from modd.mavlink.dialect import MAV
from modd.mavlink.mapping import FieldMapping, MappingError, plan_bridge


def demo() -> dict[str, Any]:
    return load_model(REPO / "metamodel" / "examples" / "demo.modd", 7171)


def test_the_demo_needs_position_and_attitude_every_publisher_period() -> None:
    plan = plan_bridge(demo())
    assert plan.intervals_us == {"GLOBAL_POSITION_INT": 200_000, "ATTITUDE": 200_000}
    assert [(p.name, len(p.mappings)) for p in plan.publishers] == [("mavlink", 6)]
    lat = next(m for _, m in plan.by_message["GLOBAL_POSITION_INT"] if m.field == "lat")
    assert (lat.topic, lat.type, lat.scale) == ("usv.autopilot.latitude", "float64", 1e-7)


def test_the_fastest_publisher_sets_the_interval_and_unpublished_topics_are_named() -> None:
    model = demo()
    model["publishers"].append(
        {"name": "fast", "periodS": "0.05", "topics": ["usv.autopilot.roll"]}
    )
    for gone in ("usv.autopilot.roll", "usv.autopilot.altitude"):
        model["publishers"][1]["topics"].remove(gone)
    plan = plan_bridge(model)
    assert plan.intervals_us == {"GLOBAL_POSITION_INT": 200_000, "ATTITUDE": 50_000}
    assert [(p.name, len(p.mappings)) for p in plan.publishers] == [("mavlink", 4), ("fast", 1)]
    assert plan.warnings == [
        "topic usv.autopilot.altitude is read over MAVLink but no "
        "publisher carries it: not published"
    ]


@pytest.mark.parametrize(
    ("source", "problem"),
    [
        (
            {"message": "NO_SUCH_MESSAGE", "field": "lat"},
            "/drone/sensors/1/variables/0/source/message: unknown MAVLink message NO_SUCH_MESSAGE",
        ),
        (
            {"message": "GLOBAL_POSITION_INT", "field": "latitude"},
            "/drone/sensors/1/variables/0/source/field: GLOBAL_POSITION_INT has no field latitude",
        ),
        (
            {"message": "STATUSTEXT", "field": "text"},
            "/drone/sensors/1/variables/0/source/field: STATUSTEXT.text is not a single number",
        ),
    ],
)
def test_a_source_the_dialect_cannot_read_is_named_by_its_pointer(
    source: dict[str, str], problem: str
) -> None:
    model = demo()
    model["drone"]["sensors"][1]["variables"][0]["source"] = source
    with pytest.raises(MappingError) as err:
        plan_bridge(model)
    assert err.value.problems[0].startswith(problem)


def test_values_are_scaled_offset_and_typed_per_topic() -> None:
    def m(vtype: str, scale: float = 1.0, offset: float = 0.0) -> FieldMapping:
        return FieldMapping("d.s.v", vtype, "SYS_STATUS", "voltage_battery", scale, offset)

    assert m("float64", 1e-7).convert(477_123_456) == pytest.approx(47.7123456)
    assert m("float32", 0.001, 10.0).convert(-250) == pytest.approx(9.75)
    assert m("int", 0.1).convert(127) == 13 and isinstance(m("int").convert(3.6), int)
    assert m("bool").convert(0) is False and m("bool").convert(2) is True
    assert math.isnan(m("float32").convert(float("nan")) or 0.0)
    assert m("int").convert(float("nan")) is None
    assert m("int", 1e300).convert(1e300) is None and m("int").convert("x") is None


def test_requests_are_retried_then_given_up_and_reasked_after_a_reboot() -> None:
    logs: list[str] = []
    ap = AutopilotState(
        {"ATTITUDE": 100_000, "SYS_STATUS": 500_000}, logs.append, heartbeat_timeout_s=100
    )
    decoder = Decoder()
    fake = Autopilot()

    def feed(data: bytes, now: float) -> None:
        for f in decoder.feed(data, datagram=True):
            ap.on_message(f.message, now)

    assert ap.poll(0.0) == []  # no autopilot yet
    feed(fake.heartbeat(), 0.0)
    sent = [ap.poll(t) for t in (0.0, 0.5, 1.01, 2.02, 3.03)]
    # ATTITUDE asked at 0, again at 1.01 and 2.02 (confirmation 1, 2), then given up
    assert [[(int(c.param1), c.confirmation) for c in s] for s in sent] == [
        [(30, 0)],
        [],
        [(30, 1)],
        [(30, 2)],
        [(1, 0)],
    ]
    assert ap.refused == {"ATTITUDE": "NO_ANSWER"}
    feed(fake.ack(MAV.MAV_CMD_SET_MESSAGE_INTERVAL, MAV.MAV_RESULT_ACCEPTED), 3.1)
    assert ap.accepted == {"SYS_STATUS": 500_000} and ap.poll(3.2) == []
    feed(fake.attitude(0.0, boot_ms=900_000), 4.0)
    feed(fake.attitude(0.0, boot_ms=1_000), 4.1)
    assert [int(c.param1) for c in ap.poll(4.2)] == [30]
    assert any("rebooted" in line for line in logs)
