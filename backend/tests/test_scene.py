"""The 3D scene's pure part: which subscribers give a position or an
attitude, how delivered values become track points, colours and a pose."""

from __future__ import annotations

import math

import pytest
from modd_backend.scene import Track, position_roles
from modd_contracts.types_gen import DeliveredValue


def _v(value: float | None) -> DeliveredValue:
    """A whole delivered value (the contract's type: mypy checks its fields)."""
    return DeliveredValue(
        subscriber="s",
        topic="usv.a.b",
        aggregation="LAST",
        period_s="1",
        unit="NONE",
        config_id=1,
        slot=0,
        start_ns=0,
        end_ns=1,
        value=value,
        count=None,
        delivered_ns=1,
        v=1,
    )


def test_roles_from_the_model() -> None:
    model = {
        "subscribers": [
            {"name": "a", "topic": "usv.autopilot.latitude"},
            {"name": "b", "topic": "usv.autopilot.longitude"},
            {"name": "c", "topic": "usv.autopilot.altitude"},
            {"name": "d", "topic": "usv.autopilot.yaw"},
            {"name": "e", "topic": "usv.ctd.conductivity"},
        ]
    }
    assert position_roles(model) == {"a": "lat", "b": "lon", "c": "alt", "d": "yaw"}


def test_points_in_local_metres_and_colours() -> None:
    t = Track({"la": "lat", "lo": "lon", "al": "alt"}, colour_by="temp")
    assert not t.ingest("temp", _v(10.0))
    assert not t.ingest("la", _v(43.0))
    assert t.ingest("lo", _v(5.0))  # a full fix: the origin
    t.ingest("temp", _v(20.0))
    t.ingest("al", _v(3.0))
    t.ingest("la", _v(43.001))
    t.ingest("lo", _v(5.0))
    assert t.points[0] == (0.0, 0.0, 0.0)
    east, north, up = t.points[1]
    assert east == pytest.approx(0.0, abs=1e-6)
    assert north == pytest.approx(111.19, rel=1e-3)  # 0.001 degree of latitude
    assert up == 3.0
    assert t.colours() == [(0, 0, 255), (255, 0, 0)]  # low blue, high red
    assert not t.ingest("la", _v(None)) and not t.ingest("unknown", _v(1.0))


def test_a_backfilled_value_never_moves_the_live_pose_nor_the_track() -> None:
    t = Track({"la": "lat", "lo": "lon", "y": "yaw"}, colour_by="la")
    t.ingest("y", _v(1.0))
    t.ingest("la", _v(43.0))
    t.ingest("lo", _v(5.0))
    old = _v(0.0)
    old["backfilled"] = True  # an older window, delivered late
    assert not t.ingest("y", old)
    assert not t.ingest("la", old) and not t.ingest("lo", old)
    assert t.attitude == {"yaw": 1.0} and t.points == [(0.0, 0.0, 0.0)]


def test_attitude_quaternion() -> None:
    t = Track({"r": "roll", "y": "yaw"})
    assert t.quaternion() == (1.0, 0.0, 0.0, 0.0)
    t.ingest("y", _v(math.pi / 2))
    w, x, y, z = t.quaternion()
    assert [w, z] == pytest.approx([math.sqrt(0.5), math.sqrt(0.5)])
    assert [x, y] == pytest.approx([0.0, 0.0])
