"""The demo's alert has a real signal to cross: the simulated deck's accel_x
(modd.sim.sensors) crosses THRESHOLD(UP 0.5, 0.1) and comes back, judged by the
reference event detector (modd_contracts.events). The alerts browser journey
(frontend/tests/e2e/alerts.mjs) and docs/user-guide/scientist.md, "Alerts",
rely on it: no value is injected."""

from __future__ import annotations

import random

from modd.sim.sensors import topic_signal
from modd.sim.track import survey_pose
from modd_contracts.events import Crossing, Detector, EventKind, EventSpec
from modd_model.query import Topic


def test_the_demo_accel_x_crosses_the_journeys_level_both_ways() -> None:
    topic = Topic(
        "usv.accelerometer.accel_x",
        "accelerometer",
        "accel_x",
        "METER_PER_SECOND_SQUARED",
        "float32",
        "pub_1",
        None,
    )
    signal = topic_signal(topic, random.Random(7))
    spec = EventSpec(EventKind.THRESHOLD, 100, level=0.5, hysteresis=0.1, crossing=Crossing.BOTH)
    detector = Detector(spec)
    events = [detector.feed(float(signal(k / 25, survey_pose(k / 25)))) for k in range(30 * 25)]
    ups = events.count(int(Crossing.UP))
    downs = events.count(int(Crossing.DOWN))
    # 0.8 sin(2π 0.3 t): one crossing each way every 3.3 s, so 9 in 30 s
    assert 8 <= ups <= 10 and 8 <= downs <= 10, (ups, downs)
