"""``modd-mavlink --model FILE [--connect URL]``: the MAVLink bridge (docs/mavlink.md).

Reads the autopilot over UDP or a serial port, asks it for the message rates the
model needs and publishes the fields the model's ``kind mavlink`` sensors map,
one publisher client per model publisher, to the PubBroker's ingress. Stops
cleanly (publishers flushed) on SIGTERM or Ctrl-C.

Example::

    modd-mavlink --model demo.modd --connect /dev/ttyUSB0,57600
"""

from __future__ import annotations

import argparse
import queue
import sys
import threading
import time
from pathlib import Path
from typing import Any

from modd_model import load_or_report

from ..onboard import ModelWatch, follow, validated, write_result
from ..publisher import Publisher
from ..shutdown import stop_on_signals
from .bridge import Bridge, BridgeSettings
from .guard import signing_key
from .mapping import MappingError, plan_bridge
from .reload import replan
from .transport import open_transport

DEFAULT_CONNECT = "udpin:127.0.0.1:14550"
APPLY_TIMEOUT_S = 1.0


def log(line: str) -> None:
    stamp = time.strftime("%H:%M:%S")
    print(f"{stamp} modd-mavlink: {line}", flush=True)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(
        prog="modd-mavlink",
        description="MAVLink bridge: autopilot "
        "messages → the model's topics → the PubBroker's ingress",
    )
    p.add_argument("--model", required=True, help=".modd or .json model")
    p.add_argument(
        "--connect",
        default=DEFAULT_CONNECT,
        metavar="URL",
        help="udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT or DEVICE[,BAUD] "
        f"(default {DEFAULT_CONNECT})",
    )
    p.add_argument("--ingress", help="unix:/path or tcp:host:port (default: the model's)")
    p.add_argument(
        "--source-system",
        type=int,
        default=255,
        metavar="ID",
        help="the bridge's own MAVLink system id (default 255)",
    )
    p.add_argument(
        "--target-system",
        type=int,
        default=None,
        metavar="ID",
        help="the autopilot's system id (default: the first autopilot heard)",
    )
    p.add_argument(
        "--target-component",
        type=int,
        default=None,
        metavar="ID",
        help="the autopilot's component id (default: the first autopilot's)",
    )
    p.add_argument(
        "--signing-key",
        default=None,
        metavar="file:PATH",
        help="accept only MAVLink 2 signed with this key (SHA-256 of the file's "
        "text, as MAVProxy's signing setup; docs/security.md)",
    )
    p.add_argument(
        "--heartbeat-timeout",
        type=float,
        default=3.0,
        metavar="S",
        help="report the autopilot lost after this long without HEARTBEAT (3)",
    )
    p.add_argument(
        "--watch",
        action="store_true",
        help="follow the model file: apply a deployed model's mavlink variables as it "
        "changes, each result in <model dir>/applied/mavlink.json (docs/mavlink.md)",
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
    model = load_or_report(args.model)
    if model is None:
        return 1
    try:
        plan = plan_bridge(model)
    except MappingError as exc:
        for problem in exc.problems:
            print(f"{args.model}: {problem}", file=sys.stderr)
        return 1
    for warning in plan.warnings:
        log(warning)
    if not plan.publishers and not args.watch:  # under --watch a deploy may add the first
        print(
            f"modd-mavlink: {args.model}: no published topic of a kind mavlink sensor",
            file=sys.stderr,
        )
        return 1
    if args.ingress:
        ingress = args.ingress
    else:
        from modd_model.ingress import ingress_of

        ingress = ingress_of(model).address
    try:
        transport = open_transport(args.connect, args.source_system)
    except (OSError, RuntimeError, ValueError) as exc:
        print(f"modd-mavlink: cannot open {args.connect}: {exc}", file=sys.stderr)
        return 1
    try:
        key = signing_key(args.signing_key) if args.signing_key else None
    except ValueError as exc:
        print(f"modd-mavlink: {exc}", file=sys.stderr)
        return 1
    sinks = {p.name: Publisher(p.name, ingress) for p in plan.publishers}
    settings = BridgeSettings(
        source_system=args.source_system,
        target_system=args.target_system,
        target_component=args.target_component,
        signing_key=key,
        heartbeat_timeout_s=args.heartbeat_timeout,
        status_period_s=args.status_period,
    )
    bridge = Bridge(plan, transport, sinks, settings, log)
    stop = threading.Event()
    stop_on_signals(stop)
    topics = sum(len(p.mappings) for p in plan.publishers)
    log(
        f"drone {model['drone']['name']}: {topics} topics from {args.connect} -> {ingress}, "
        "waiting for the autopilot's HEARTBEAT"
    )
    if args.watch:
        _follow(Path(args.model), bridge, ingress, stop)
    bridge.run(stop)
    log("stopped")
    return 0


def _replanned(path: Path, applied: str, bridge: Bridge, ingress: str) -> dict[str, Any]:
    """The deployed model applied by the bridge's own thread; what it did."""
    model = validated(path, applied) or load_or_report(str(path))
    if model is None:
        return {"ok": False, "problem": f"invalid model (see {path}'s diagnostics in the log)"}
    try:
        plan = plan_bridge(model)
    except MappingError as exc:
        return {"ok": False, "problem": "; ".join(exc.problems)[:500]}
    done: queue.SimpleQueue[dict[str, Any]] = queue.SimpleQueue()
    bridge.pending.put(lambda: done.put(replan(bridge, plan, lambda n: Publisher(n, ingress))))
    try:
        return done.get(timeout=APPLY_TIMEOUT_S)
    except queue.Empty:
        return {"ok": False, "problem": f"the bridge did not apply it in {APPLY_TIMEOUT_S} s"}


def _follow(path: Path, bridge: Bridge, ingress: str, stop: threading.Event) -> None:
    """Applies the model file each time it changes (a deploy), in a thread of its own."""
    watch = ModelWatch(path)
    write_result(path, "mavlink", watch.digest, {"ok": True, "started": True})

    def apply(applied: str) -> None:
        write_result(path, "mavlink", applied, _replanned(path, applied, bridge, ingress))

    threading.Thread(target=follow, args=(watch, apply, stop), name="watch", daemon=True).start()


if __name__ == "__main__":
    sys.exit(main())
