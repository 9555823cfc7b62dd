"""``modd-sensors --model FILE``: reads the model's ``nmea``, ``ascii`` and
``modbus`` sensors and publishes their variables to the PubBroker's ingress,
one publisher client per model publisher (docs/sensors.md). Stops cleanly
(publishers flushed) on SIGTERM or Ctrl-C.

Example::

    modd-sensors --model demo.modd --status-file /run/modd/sensors.json
"""

from __future__ import annotations

import argparse
import sys
import threading
import time
from pathlib import Path
from typing import Any

from ..onboard import ModelWatch, follow, validated, write_result
from ..publisher import Publisher
from ..shutdown import stop_on_signals
from .check import checked_model, model_or_why
from .plan import plan_sensors
from .reload import apply_plans, linked_device
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
        "--watch",
        action="store_true",
        help="follow the model file: apply a deployed model's instruments as it changes, "
        "each result in <model dir>/applied/sensors.json (docs/sensors.md)",
    )
    p.add_argument(
        "--device-dir",
        type=Path,
        metavar="DIR",
        help="with --watch: a deployed sensor that has a link DIR/<name> reads it, not the "
        "model's device (modd up --simulate: the simulator's pseudo-terminals)",
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
    plans = [linked_device(p, args.device_dir) for p in plan_sensors(model)]
    if not plans and not args.watch:
        print(
            f"modd-sensors: {args.model}: no published topic of an nmea, ascii or modbus sensor",
            file=sys.stderr,
        )
        return 1
    from modd_model.ingress import ingress_of  # the model's ingress, as the generators write it

    ingress = args.ingress or ingress_of(model).address
    names = sorted({m.publisher for p in plans for m in p.mappings})
    sinks = {n: Publisher(n, ingress) for n in names}
    runner = Runner(plans, sinks, log, args.status_file, args.status_period)
    runner.report_health = lambda health: _report_health(runner, health)
    stop = threading.Event()
    stop_on_signals(stop)
    for p in plans:
        log(
            f"{p.name} ({p.kind}): {len(p.mappings)} topics from {p.device.path} at "
            f"{p.device.baud} baud"
        )
    log(f"drone {model['drone']['name']}: {len(plans)} sensors -> {ingress}")
    if args.watch:
        _follow(Path(args.model), runner, ingress, stop, args.device_dir)
    runner.run(stop)
    log("stopped")
    return 0


def _report_health(runner: Runner, health: list[Any]) -> None:
    """The health rides on one publisher's connection (the broker forwards it in
    STATUS): the first one the readers have now (none while idle, under --watch with
    no instrument yet: a deploy may add the first)."""
    sinks = [s for _, s in sorted(runner.sinks.items())]
    if sinks and isinstance(sinks[0], Publisher):
        sinks[0].report_health(health)


def _applied(
    model: dict[str, Any], runner: Runner, ingress: str, devices: Path | None
) -> dict[str, Any]:
    try:
        plans = [linked_device(p, devices) for p in plan_sensors(model)]
    except (KeyError, TypeError, ValueError) as exc:  # a model file no validator read
        return {"ok": False, "problem": f"cannot read the model's instruments: {exc!r}"}
    return apply_plans(runner, plans, lambda n: Publisher(n, ingress))


def _follow(
    path: Path, runner: Runner, ingress: str, stop: threading.Event, devices: Path | None
) -> None:
    """Applies the model file each time it changes (a deploy), in a thread of its own."""
    watch = ModelWatch(path)
    write_result(path, "sensors", watch.digest, {"ok": True, "started": True})

    def apply(applied: str) -> None:
        # a deploy's hand-over was validated by the SubBroker; a file edited by hand is checked
        model = validated(path, applied)
        why = ""
        if model is None:
            model, why = model_or_why(str(path))
        if model is None:
            log(f"deploy: {path} refused, the readers go on: {why}")
            result: dict[str, Any] = {"ok": False, "problem": f"invalid model: {why}"}
        else:
            result = _applied(model, runner, ingress, devices)
        write_result(path, "sensors", applied, result)

    threading.Thread(target=follow, args=(watch, apply, stop), name="watch", daemon=True).start()


if __name__ == "__main__":
    sys.exit(main())
