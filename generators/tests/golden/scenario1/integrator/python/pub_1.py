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
    'usv.accelerometer.accel_x': 'float32',  # METER_PER_SECOND_SQUARED
    'usv.accelerometer.accel_y': 'float32',  # METER_PER_SECOND_SQUARED
    'usv.accelerometer.accel_z': 'float32',  # METER_PER_SECOND_SQUARED
}


# ---- Sensor reads: replace each body with the read of your sensor. ----------
def read_accel_x(t: float) -> float:
    return math.sin(t + 0)


def read_accel_y(t: float) -> float:
    return math.sin(t + 1)


def read_accel_z(t: float) -> float:
    return math.sin(t + 2)


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
            pub.publish('usv.accelerometer.accel_x', ts, read_accel_x(t))
            pub.publish('usv.accelerometer.accel_y', ts, read_accel_y(t))
            pub.publish('usv.accelerometer.accel_z', ts, read_accel_z(t))
            n += 1
            time.sleep(max(0.0, start + n * PERIOD_S - time.monotonic()))
        delivered = pub.flush(5.0)
    print(f"{PUBLISHER}: {n} readings published", file=sys.stderr)
    return 0 if delivered else 1


if __name__ == "__main__":
    sys.exit(main())
