"""``modd-radio``: put an emulated radio between the two ends of the MoDD link.

UDP: ``modd-radio --udp 127.0.0.1:7181 --to 127.0.0.1:7171 --radio "rate=3600,loss=0.05"``
(the SubBroker sends to 7181 instead of the PubBroker's 7171).
A shared channel (several stations hearing one drone: docs/fleet.md): ``--udp`` once
per station, ``modd-radio --udp 127.0.0.1:7181 --udp 127.0.0.1:7182 --to 127.0.0.1:7171``;
the drone's datagrams reach every station, each losing its own share; ``--radio``
once for all the stations' channels, or once per ``--udp`` in its order.
Serial: ``modd-radio --serial --radio "rate=3600,packet=252"`` creates two
pseudo-terminals, prints their paths (``base=/dev/pts/N drone=/dev/pts/M``) and
relays between them. Prints what it passed and dropped every ``--report`` seconds
and when it stops (SIGTERM, SIGINT, or ``--duration``)."""

from __future__ import annotations

import argparse
import signal
import socket
import sys
import time

from modd_model.io import load_file
from modd_plan.radio import RadioProfile

from .channel import Channel, RadioSpec
from .relay import open_pty_pair, run_serial, run_udp
from .shared import Modem, run_shared_udp, summary


def _hostport(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise argparse.ArgumentTypeError(f"{text!r}: expected HOST:PORT")
    return host, int(port)


def _spec(text: str) -> RadioSpec:
    try:
        return RadioSpec.parse(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _same_endpoint(a: tuple[str, int], b: tuple[str, int]) -> bool:
    """Whether datagrams sent to ``b`` would come back to a socket bound to ``a``
    (same port, and the same address, or ``a`` bound to every address)."""
    if a[1] != b[1]:
        return False
    if a[0] in ("0.0.0.0", "", "::") or a[0] == b[0]:
        return True
    try:
        return socket.gethostbyname(a[0]) == socket.gethostbyname(b[0])
    except OSError:
        return False


def _profile(path: str) -> RadioProfile:
    """The radio profile of a model file (its errors, located, refuse it)."""
    result = load_file(path)
    if result.model is None or result.errors:
        raise argparse.ArgumentTypeError("; ".join(str(d) for d in result.errors) or path)
    radio = result.model.get("link", {}).get("radio")
    if radio is None:
        raise argparse.ArgumentTypeError(f"{path}: the model's link names no radio")
    return RadioProfile.of(radio)


def _print(up: Channel, down: Channel) -> None:
    print(f"radio: base->drone {up.summary()}; drone->base {down.summary()}", flush=True)


def _print_shared(stations: list[Modem]) -> None:
    print(f"radio: {summary(stations)}", flush=True)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="modd-radio", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    mode = p.add_mutually_exclusive_group(required=True)
    mode.add_argument(
        "--udp",
        type=_hostport,
        action="append",
        metavar="HOST:PORT",
        help="listen here for the base station's datagrams (once per station: a shared "
        "channel that every station hears)",
    )
    mode.add_argument(
        "--serial", action="store_true", help="relay between two new pseudo-terminals"
    )
    p.add_argument(
        "--to",
        type=_hostport,
        metavar="HOST:PORT",
        help="the PubBroker's UDP endpoint (with --udp)",
    )
    p.add_argument(
        "--radio",
        type=_spec,
        action="append",
        metavar="SPEC",
        help='e.g. "rate=3600,packet=252,loss=0.05,latency_ms=80,jitter_ms=20,outage=10+30,seed=7"'
        " (a shared channel: once for every station, or once per --udp, in its order)",
    )
    p.add_argument(
        "--profile",
        type=_profile,
        metavar="MODEL",
        help="emulate the air time and duty cycle of this model's link.radio",
    )
    p.add_argument("--report", type=float, default=10.0, metavar="S")
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    args = p.parse_args(argv)
    if args.udp and not args.to:
        p.error("--udp needs --to HOST:PORT (the PubBroker's endpoint)")
    for listen in args.udp or ():
        if _same_endpoint(listen, args.to):
            p.error(
                f"--to {args.to[0]}:{args.to[1]} is where the radio listens (--udp): it would "
                "relay every datagram to itself; give the PubBroker's endpoint"
            )
    if args.udp and len(set(args.udp)) < len(args.udp):
        p.error("--udp: each station needs its own HOST:PORT (one given twice)")
    if args.udp and len(args.udp) > 1 and args.profile is not None:
        p.error("--profile emulates one station's radio: give one --udp with it")
    radios: list[RadioSpec] = args.radio or [RadioSpec()]
    if len(radios) > 1 and len(radios) != len(args.udp or ()):
        p.error(
            f"--radio given {len(radios)} times: give it once, or once per --udp "
            f"({len(args.udp or ())} here)"
        )
    if args.report <= 0 or (args.duration is not None and args.duration <= 0):
        p.error("--report and --duration take seconds > 0")
    stopping: list[bool] = []
    signal.signal(signal.SIGTERM, lambda *_: stopping.append(True))
    signal.signal(signal.SIGINT, lambda *_: stopping.append(True))
    end = time.monotonic() + args.duration if args.duration else None

    def stop() -> bool:
        return bool(stopping) or (end is not None and time.monotonic() >= end)

    if args.udp and len(args.udp) > 1:
        stations = run_shared_udp(radios, args.udp, args.to, stop, _print_shared, args.report)
        _print_shared(stations)
        return 0
    if args.udp:
        up, down = run_udp(
            radios[0], args.udp[0], args.to, stop, _print, args.report, profile=args.profile
        )
    else:
        base, base_path = open_pty_pair()
        drone, drone_path = open_pty_pair()
        print(f"base={base_path} drone={drone_path}", flush=True)
        up, down = run_serial(
            radios[0], base, drone, stop, _print, args.report, profile=args.profile
        )
    _print(up, down)
    return 0


if __name__ == "__main__":
    sys.exit(main())
