"""``modd-sim --model FILE``: the simulated drone of a model (see the package docstring)."""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from typing import Any

from modd_model import load_or_report
from modd_model.numbers import to_fraction
from modd_model.query import topics

from ..shutdown import stop_on_signals
from .faults import FaultFile
from .sensors import run_publisher

DEFAULT_MAVLINK = "udpout:127.0.0.1:14550"


def default_ingress(model: dict[str, Any]) -> str:
    from modd_model.ingress import ingress_of

    return ingress_of(model).address


def mavlink_topics(model: dict[str, Any]) -> set[str]:
    """The topics of the model's ``kind mavlink`` sensors."""
    drone = model["drone"]["name"]
    return {
        f"{drone}.{s['name']}.{v['name']}"
        for s in model["drone"]["sensors"]
        if s.get("kind", "generic") == "mavlink"
        for v in s["variables"]
    }


def instrument_topics(model: dict[str, Any]) -> set[str]:
    """The topics of the model's ``kind nmea``, ``ascii`` and ``modbus`` sensors."""
    from modd_model.instruments import INSTRUMENT_KINDS

    drone = model["drone"]["name"]
    return {
        f"{drone}.{s['name']}.{v['name']}"
        for s in model["drone"]["sensors"]
        if s.get("kind", "generic") in INSTRUMENT_KINDS
        for v in s["variables"]
    }


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="modd-sim",
        description="The simulated drone of a model: "
        "a MAVLink autopilot and the scientific sensors.",
    )
    p.add_argument("--model", required=True, help=".modd or .json model")
    p.add_argument("--ingress", help="unix:/path or tcp:host:port (default: the model's)")
    p.add_argument(
        "--mavlink",
        default=DEFAULT_MAVLINK,
        metavar="URL",
        help=f"where the simulated autopilot sends (default {DEFAULT_MAVLINK})",
    )
    p.add_argument(
        "--no-mavlink",
        action="store_true",
        help="no simulated autopilot: publish the mavlink sensors' topics directly",
    )
    p.add_argument(
        "--no-instruments",
        action="store_true",
        help="no simulated instruments on pseudo-terminals: publish the nmea, ascii "
        "and modbus sensors' topics directly",
    )
    p.add_argument(
        "--system-id",
        type=int,
        default=1,
        metavar="ID",
        help="the simulated autopilot's MAVLink system id (default 1)",
    )
    p.add_argument(
        "--start-time",
        type=float,
        metavar="UNIX_S",
        help="when the survey track starts (default: now)",
    )
    p.add_argument("--duration", type=float, help="stop after this many seconds")
    p.add_argument(
        "--faults",
        default=os.environ.get("MODD_SIM_FAULTS"),
        metavar="FILE",
        help="a JSON file of spikes and flat lines to inject into the simulated sensors, "
        "read again when it changes (default $MODD_SIM_FAULTS; sim/faults.py)",
    )
    return p.parse_args(argv)


def log(line: str) -> None:
    print(f"modd-sim: {line}", flush=True)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    model = load_or_report(args.model)
    if model is None:
        return 1
    start = time.time() if args.start_time is None else args.start_time
    ingress = args.ingress or default_ingress(model)
    autopilot_topics = set() if args.no_mavlink else mavlink_topics(model)
    wired = set() if args.no_instruments else instrument_topics(model)
    tops = topics(model)
    stop = threading.Event()
    faults = FaultFile(args.faults)
    stop_on_signals(stop)
    threads = []
    for i, p in enumerate(model["publishers"]):
        mine = [tops[t] for t in p["topics"] if t not in autopilot_topics | wired]
        if mine:
            threads.append(
                threading.Thread(
                    target=run_publisher,
                    name=p["name"],
                    daemon=True,
                    args=(
                        p["name"],
                        float(to_fraction(p["periodS"])),
                        mine,
                        ingress,
                        stop,
                        i,
                        start,
                        faults,
                    ),
                )
            )
    publishers = len(threads)
    if autopilot_topics:
        from .autopilot import SimAutopilot

        try:
            autopilot = SimAutopilot(args.mavlink, start, system=args.system_id, log=log)
        except (OSError, RuntimeError, ValueError) as exc:
            print(f"modd-sim: cannot open {args.mavlink}: {exc}", file=sys.stderr)
            return 1
        threads.append(
            threading.Thread(target=autopilot.run, args=(stop,), name="autopilot", daemon=True)
        )
    for th in threads:
        th.start()
    if wired:
        from .instruments import start_instruments

        try:
            threads += start_instruments(model, start, stop, log, faults)
        except OSError as exc:
            print(f"modd-sim: cannot simulate the instruments: {exc}", file=sys.stderr)
            stop.set()
            return 1
    log(
        f"drone {model['drone']['name']}: {publishers} publishers -> {ingress}"
        + (f"; autopilot -> {args.mavlink}" if autopilot_topics else "")
        + f"; track started at {start:.3f}"
    )
    stop.wait(args.duration)
    stop.set()
    for th in threads:
        th.join(timeout=5)
    return 0


if __name__ == "__main__":
    sys.exit(main())
