#!/usr/bin/env python3
"""Driver of publisher pub_1 (drone usv), in Python: reads the sensors
every 0.04 s and hands the readings to the on-board PubBroker through the
MoDD Python publisher client (``import modd``).

This file is yours: `modd generate` wrote it once and will never overwrite it.
Replace the bodies of the read_*() functions with the reads of your sensors
(they return a test signal until then).
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time

from modd.publisher import Publisher

PUBLISHER = 'pub_1'
DEFAULT_INGRESS = 'unix:/tmp/modd/usv/ingress.sock'
PERIOD_S = 0.04
TOPICS = {
    'usv.ins.accel_x': 'float32',  # METER_PER_SECOND_SQUARED
    'usv.ins.accel_y': 'float32',  # METER_PER_SECOND_SQUARED
    'usv.ins.accel_z': 'float32',  # METER_PER_SECOND_SQUARED
    'usv.ins.gyro_x': 'float32',  # RADIAN_PER_SECOND
    'usv.ins.gyro_y': 'float32',  # RADIAN_PER_SECOND
    'usv.ins.gyro_z': 'float32',  # RADIAN_PER_SECOND
    'usv.ins.roll': 'float32',  # RADIAN
    'usv.ins.pitch': 'float32',  # RADIAN
    'usv.ins.yaw': 'float32',  # RADIAN
    'usv.ins.vel_north': 'float32',  # METER_PER_SECOND
    'usv.ins.vel_east': 'float32',  # METER_PER_SECOND
    'usv.ins.vel_down': 'float32',  # METER_PER_SECOND
    'usv.ins.latitude': 'float32',  # RADIAN
    'usv.ins.longitude': 'float32',  # RADIAN
    'usv.ins.altitude': 'float32',  # METER
    'usv.ins.temperature': 'float32',  # DEGREE_CELSIUS
    'usv.ins.pressure': 'float32',  # BAR
    'usv.ins.heave': 'float32',  # METER
    'usv.ins.undulation': 'float32',  # METER
}


# ---- Sensor reads: replace each body with the read of your sensor. ----------
def read_accel_x(t: float) -> float:
    return math.sin(t + 0)


def read_accel_y(t: float) -> float:
    return math.sin(t + 1)


def read_accel_z(t: float) -> float:
    return math.sin(t + 2)


def read_gyro_x(t: float) -> float:
    return math.sin(t + 3)


def read_gyro_y(t: float) -> float:
    return math.sin(t + 4)


def read_gyro_z(t: float) -> float:
    return math.sin(t + 5)


def read_roll(t: float) -> float:
    return math.sin(t + 6)


def read_pitch(t: float) -> float:
    return math.sin(t + 7)


def read_yaw(t: float) -> float:
    return math.sin(t + 8)


def read_vel_north(t: float) -> float:
    return math.sin(t + 9)


def read_vel_east(t: float) -> float:
    return math.sin(t + 10)


def read_vel_down(t: float) -> float:
    return math.sin(t + 11)


def read_latitude(t: float) -> float:
    return math.sin(t + 12)


def read_longitude(t: float) -> float:
    return math.sin(t + 13)


def read_altitude(t: float) -> float:
    return math.sin(t + 14)


def read_temperature(t: float) -> float:
    return math.sin(t + 15)


def read_pressure(t: float) -> float:
    return math.sin(t + 16)


def read_heave(t: float) -> float:
    return math.sin(t + 17)


def read_undulation(t: float) -> float:
    return math.sin(t + 18)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--ingress", default=os.environ.get("MODD_INGRESS", DEFAULT_INGRESS),
                        help="unix:/path or tcp:host:port")
    parser.add_argument("--count", type=int, help="stop after this many readings")
    args = parser.parse_args()
    stopping = False

    def stop(*_: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGINT, stop)
    signal.signal(signal.SIGTERM, stop)
    with Publisher(PUBLISHER, args.ingress) as pub:  # waits up to 1 s for the broker's catalogue
        if not pub.connected:
            # Said at once: the client keeps queueing (bounded) and reconnects by itself.
            print(f"{PUBLISHER}: cannot reach the PubBroker at {args.ingress}: is it running"
                  " (modd up starts one)? Readings are queued and sent when it answers.",
                  file=sys.stderr, flush=True)
        for topic, vtype in TOPICS.items():
            pub.declare(topic, vtype)
        start = time.monotonic()
        n = 0
        while not stopping and (args.count is None or n < args.count):
            ts, t = time.time_ns(), time.monotonic() - start
            # ---- One publish call per topic of pub_1. ----
            pub.publish('usv.ins.accel_x', ts, read_accel_x(t))
            pub.publish('usv.ins.accel_y', ts, read_accel_y(t))
            pub.publish('usv.ins.accel_z', ts, read_accel_z(t))
            pub.publish('usv.ins.gyro_x', ts, read_gyro_x(t))
            pub.publish('usv.ins.gyro_y', ts, read_gyro_y(t))
            pub.publish('usv.ins.gyro_z', ts, read_gyro_z(t))
            pub.publish('usv.ins.roll', ts, read_roll(t))
            pub.publish('usv.ins.pitch', ts, read_pitch(t))
            pub.publish('usv.ins.yaw', ts, read_yaw(t))
            pub.publish('usv.ins.vel_north', ts, read_vel_north(t))
            pub.publish('usv.ins.vel_east', ts, read_vel_east(t))
            pub.publish('usv.ins.vel_down', ts, read_vel_down(t))
            pub.publish('usv.ins.latitude', ts, read_latitude(t))
            pub.publish('usv.ins.longitude', ts, read_longitude(t))
            pub.publish('usv.ins.altitude', ts, read_altitude(t))
            pub.publish('usv.ins.temperature', ts, read_temperature(t))
            pub.publish('usv.ins.pressure', ts, read_pressure(t))
            pub.publish('usv.ins.heave', ts, read_heave(t))
            pub.publish('usv.ins.undulation', ts, read_undulation(t))
            n += 1
            time.sleep(max(0.0, start + n * PERIOD_S - time.monotonic()))
        delivered = pub.flush(5.0)
    print(f"{PUBLISHER}: {n} readings published", file=sys.stderr)
    return 0 if delivered else 1


if __name__ == "__main__":
    sys.exit(main())
