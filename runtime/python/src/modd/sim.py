"""``modd-sim --model FILE``: simulated sensors for a model. Every publisher of
the model publishes each of its topics at its period, through the Python
publisher client, to the PubBroker's ingress.

The drone follows a survey pattern (back-and-forth legs over a stretch of
water), so the values mean something: position and attitude follow the track,
the accelerometer sees the waves, and water temperature and conductivity vary
in space (a warm, fresh plume near one corner), so a track coloured by them
shows a pattern. Topics the simulator does not recognise get a slow sine of
their type. The autopilot's topics are published directly here; reading them
from a simulated MAVLink autopilot through the MAVLink bridge is not built yet.
"""

from __future__ import annotations

import argparse
import math
import random
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from modd_model import load_file
from modd_model.numbers import to_fraction
from modd_model.query import Topic, topics

from .publisher import Publisher

ORIGIN_LAT, ORIGIN_LON = 47.70, -3.35  # a sheltered bay
LEG_M, SPACING_M, LEGS, SPEED_MS = 400.0, 40.0, 8, 2.0
METERS_PER_DEG_LAT = 111_320.0


@dataclass(frozen=True)
class Pose:
    lat: float
    lon: float
    yaw: float  # radians, 0 = north
    x: float  # metres east of the origin
    y: float  # metres north of the origin


def survey_pose(t: float) -> Pose:
    """Where the drone is t seconds into a lawnmower survey (it loops)."""
    leg_time = LEG_M / SPEED_MS
    turn_time = SPACING_M / SPEED_MS
    period = LEGS * (leg_time + turn_time)
    t %= period
    leg, rest = divmod(t, leg_time + turn_time)
    leg = int(leg)
    north = leg % 2 == 0
    if rest < leg_time:
        y = rest * SPEED_MS if north else LEG_M - rest * SPEED_MS
        x, yaw = leg * SPACING_M, 0.0 if north else math.pi
    else:
        y = LEG_M if north else 0.0
        x, yaw = leg * SPACING_M + (rest - leg_time) * SPEED_MS, math.pi / 2
    lat = ORIGIN_LAT + y / METERS_PER_DEG_LAT
    lon = ORIGIN_LON + x / (METERS_PER_DEG_LAT * math.cos(math.radians(ORIGIN_LAT)))
    return Pose(lat, lon, yaw, x, y)


def plume(p: Pose) -> float:
    """0..1: how deep in the warm, fresh plume the drone is."""
    return math.exp(-((p.x - 250) ** 2 + (p.y - 300) ** 2) / (2 * 90.0**2))


def _signal(topic: Topic, rng: random.Random) -> Callable[[float, Pose], float | int | bool]:
    v = topic.variable.lower()
    waves = {"x": 0.0, "y": 1.3, "z": 2.1}
    for axis, phase in waves.items():
        if v in (f"accel_{axis}", f"acc_{axis}", axis + "acc"):
            base = 9.81 if axis == "z" else 0.0
            return lambda t, p: base + 0.8 * math.sin(2 * math.pi * 0.3 * t + phase) \
                + rng.gauss(0, 0.05)
    named: dict[str, Callable[[float, Pose], float]] = {
        "latitude": lambda t, p: p.lat, "lat": lambda t, p: p.lat,
        "longitude": lambda t, p: p.lon, "lon": lambda t, p: p.lon,
        "altitude": lambda t, p: 0.2 * math.sin(0.5 * t), "yaw": lambda t, p: p.yaw,
        "heading": lambda t, p: math.degrees(p.yaw),
        "roll": lambda t, p: 0.05 * math.sin(2 * math.pi * 0.3 * t),
        "pitch": lambda t, p: 0.03 * math.sin(2 * math.pi * 0.25 * t + 1.0),
        "water_temperature": lambda t, p: 12.0 + 4.0 * plume(p) + rng.gauss(0, 0.02),
        "temperature": lambda t, p: 12.0 + 4.0 * plume(p) + rng.gauss(0, 0.02),
        "conductivity": lambda t, p: 52.0 - 20.0 * plume(p) + rng.gauss(0, 0.05),
    }
    if v in named:
        return named[v]
    if topic.type == "bool":
        return lambda t, p: int(t) % 2 == 0
    if topic.type == "int":
        return lambda t, p: int(t * 10)
    phase = rng.uniform(0, 2 * math.pi)
    return lambda t, p: math.sin(0.2 * t + phase)


def run_publisher(name: str, period_s: float, tops: list[Topic], ingress: str,
                  stop: threading.Event, seed: int) -> None:
    rng = random.Random(seed)
    signals = {t.name: _signal(t, rng) for t in tops}
    with Publisher(name, ingress) as pub:
        for t in tops:
            pub.declare(t.name, t.type)
        start = time.monotonic()
        tick = 0
        while not stop.is_set():
            elapsed = time.monotonic() - start
            pose = survey_pose(elapsed)
            now = time.time_ns()
            for t in tops:
                pub.publish(t.name, now, signals[t.name](elapsed, pose))
            tick += 1
            stop.wait(max(0.0, start + tick * period_s - time.monotonic()))


def default_ingress(model: dict[str, Any]) -> str:
    from modd_gen.ingress import ingress_of

    return ingress_of(model).address


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="modd-sim", description="Simulated sensors: publish "
                                     "every topic of a model at its publisher's period.")
    parser.add_argument("--model", required=True, help=".modd or .json model")
    parser.add_argument("--ingress", help="unix:/path or tcp:host:port (default: the model's)")
    parser.add_argument("--duration", type=float, help="stop after this many seconds")
    args = parser.parse_args(argv)
    result = load_file(args.model)
    for d in result.diagnostics:
        print(d, file=sys.stderr)
    if not result.ok or result.model is None:
        return 1
    model = result.model
    ingress = args.ingress or default_ingress(model)
    tops = topics(model)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    threads = [threading.Thread(target=run_publisher, name=p["name"], daemon=True,
                                args=(p["name"], float(to_fraction(p["periodS"])),
                                      [tops[t] for t in p["topics"]], ingress, stop, i))
               for i, p in enumerate(model["publishers"])]
    for th in threads:
        th.start()
    print(f"modd-sim: {len(threads)} publishers of drone {model['drone']['name']} -> {ingress}",
          flush=True)
    stop.wait(args.duration)
    stop.set()
    for th in threads:
        th.join(timeout=5)
    return 0


if __name__ == "__main__":
    sys.exit(main())
