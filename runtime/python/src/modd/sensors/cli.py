"""``modd-sensors --model FILE``: reads the model's ``nmea``, ``ascii`` and
``modbus`` sensors and publishes their variables to the PubBroker's ingress,
one publisher client per model publisher (docs/sensors.md). Stops cleanly
(publishers flushed) on SIGTERM or Ctrl-C.

Example::

    modd-sensors --model demo.modd --status-file /run/modd/sensors.json
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from pathlib import Path

from ..publisher import Publisher
from .check import checked_model
from .plan import plan_sensors
from .run import Runner


def log(line: str) -> None:
    print(f"{time.strftime('%H:%M:%S')} modd-sensors: {line}", flush=True)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="modd-sensors",
        description="plug-and-play instruments "
        "(NMEA 0183, ASCII lines, Modbus RTU) → the model's topics → "
        "the PubBroker's ingress",
    )
    p.add_argument("--model", required=True, help=".modd or .json model")
    p.add_argument("--ingress", help="unix:/path or tcp:host:port (default: the model's)")
    p.add_argument(
        "--status-file",
        type=Path,
        metavar="PATH",
        help="keep each sensor's health in this JSON file (rewritten every 0.25 s)",
    )
    p.add_argument(
        "--status-period",
        type=float,
        default=10.0,
        metavar="S",
        help="seconds between status lines (default 10)",
    )
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    model = checked_model(args.model)
    if model is None:
        return 1
    plans = plan_sensors(model)
    if not plans:
        print(
            f"modd-sensors: {args.model}: no published topic of an nmea, ascii or modbus sensor",
            file=sys.stderr,
        )
        return 1
    from modd_model.ingress import ingress_of  # the model's ingress, as the generators write it

    ingress = args.ingress or ingress_of(model).address
    names = sorted({m.publisher for p in plans for m in p.mappings})
    sinks = {n: Publisher(n, ingress) for n in names}
    # the health rides on one publisher's connection (the broker forwards it in STATUS)
    runner = Runner(
        plans, sinks, log, args.status_file, args.status_period, sinks[names[0]].report_health
    )
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    for p in plans:
        log(
            f"{p.name} ({p.kind}): {len(p.mappings)} topics from {p.device.path} at "
            f"{p.device.baud} baud"
        )
    log(f"drone {model['drone']['name']}: {len(plans)} sensors -> {ingress}")
    runner.run(stop)
    log("stopped")
    return 0


if __name__ == "__main__":
    sys.exit(main())
