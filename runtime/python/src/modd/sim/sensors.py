"""Simulated sensors that publish through the Python publisher client: one
thread per model publisher, each of its topics at the publisher's period.

What a topic carries is chosen from its variable's name (accelerometer axes see
the waves, water temperature and conductivity see the plume, position and
attitude follow the track); a topic the simulator does not recognise gets a
slow sine of its type.

Example::

    run_publisher("ctd", 0.5, [tops["usv.ctd.water_temperature"]], "unix:/tmp/i.sock",
                  stop_event, seed=0, start=time.time())
"""

from __future__ import annotations

import math
import random
import threading
import time
from collections.abc import Callable

from modd_model.query import Topic

from ..publisher import Publisher
from .faults import FaultFile
from .track import LEG_M, Pose, altitude, plume, survey_pose, waves

Signal = Callable[[float, Pose], float | int | bool]


def topic_signal(topic: Topic, rng: random.Random) -> Signal:
    """The value of a topic at t seconds into the track, where the drone is at pose."""
    v = topic.variable.lower()
    for axis, phase in {"x": 0.0, "y": 1.3, "z": 2.1}.items():
        if v in (f"accel_{axis}", f"acc_{axis}", axis + "acc"):
            base = 9.81 if axis == "z" else 0.0
            return lambda t, p: (
                base + 0.8 * math.sin(2 * math.pi * 0.3 * t + phase) + rng.gauss(0, 0.05)
            )
    named: dict[str, Signal] = {
        "latitude": lambda t, p: p.lat,
        "lat": lambda t, p: p.lat,
        "longitude": lambda t, p: p.lon,
        "lon": lambda t, p: p.lon,
        "altitude": lambda t, p: altitude(t),
        "yaw": lambda t, p: p.yaw,
        "heading": lambda t, p: math.degrees(p.yaw),
        "roll": lambda t, p: waves(t)[0],
        "pitch": lambda t, p: waves(t)[1],
        "water_temperature": lambda t, p: 12.0 + 4.0 * plume(p) + rng.gauss(0, 0.02),
        "temperature": lambda t, p: 12.0 + 4.0 * plume(p) + rng.gauss(0, 0.02),
        "conductivity": lambda t, p: 52.0 - 20.0 * plume(p) + rng.gauss(0, 0.05),
        "depth": lambda t, p: 3.0 + 6.0 * p.y / LEG_M + 0.05 * math.sin(t),  # a sloping bottom
    }
    if v in named:
        return named[v]
    if topic.type == "bool":
        return lambda t, p: int(t) % 2 == 0
    if topic.type == "int":
        return lambda t, p: int(t * 10)
    phase = rng.uniform(0, 2 * math.pi)
    return lambda t, p: math.sin(0.2 * t + phase)


def run_publisher(
    name: str,
    period_s: float,
    tops: list[Topic],
    ingress: str,
    stop: threading.Event,
    seed: int,
    start: float,
    faults: FaultFile | None = None,
) -> None:
    """Publishes every topic of ``tops`` each ``period_s`` until ``stop`` is set;
    ``start`` is the track's start (Unix seconds); ``faults``: spikes and flat
    lines injected (faults.py)."""
    faults = faults or FaultFile(None)
    rng = random.Random(seed)
    signals = {t.name: topic_signal(t, rng) for t in tops}
    with Publisher(name, ingress) as pub:
        for t in tops:
            pub.declare(t.name, t.type)
        first = time.monotonic()
        tick = 0
        while not stop.is_set():
            now = time.time_ns()
            elapsed = now / 1e9 - start
            pose = survey_pose(elapsed)
            for t in tops:
                value = faults.apply(t.name, now / 1e9, signals[t.name](elapsed, pose))
                pub.publish(t.name, now, value)
            tick += 1
            stop.wait(max(0.0, first + tick * period_s - time.monotonic()))
