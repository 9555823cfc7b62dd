"""``modd-plotjuggler``: MoDD's delivered values to PlotJuggler's "UDP Server"
(JSON protocol), one datagram per delivered window; a separate process, off
unless started (one per base station, configured by its options).

Each datagram is a JSON object PlotJuggler flattens into series
``/<drone>/<subscriber>/value`` (and ``/count``, ``/backfilled``), stamped
with the window's end in seconds (tick "use field as timestamp if
available" with field ``timestamp`` in PlotJuggler):

    {"timestamp": 1795000000.25, "usv": {"sub_3": {"value": -0.0966, "count": 6, "backfilled": 0}}}

``backfilled`` is the historical mark of every window: 1 for a window filled
from the drone's archive after an outage (it arrives late and PlotJuggler
places it at its own timestamp, among the live points), 0 for a live one.

Empty windows (no sample) send no value. An ``ALL`` window sends one datagram
per sample, each at its own time (the delivered-value contract spreads the
samples over the window, the last at its end), so the samples form the one
series ``/<drone>/<subscriber>/value``; the window's ``count`` rides with its
last sample.

    modd-plotjuggler --udp 127.0.0.1:9870 --drone usv
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import socket
import sys
import threading
from typing import Any

from modd_contracts import keys
from modd_contracts.delivered import load_delivered
from modd_contracts.types_gen import DeliveredValue

from .shutdown import stop_on_signals
from .zenoh_session import add_viewer_args, client_settings, open_session

log = logging.getLogger("modd.plotjuggler")
#: PlotJuggler's default UDP server port.
DEFAULT_UDP = "127.0.0.1:9870"
#: Above this a datagram is not sent (a subscriber name of megabytes).
MAX_DATAGRAM = 65_000


def datagrams(drone: str, subscriber: str, delivered: DeliveredValue) -> list[bytes]:
    """The datagrams of one delivered value (none when it has nothing to plot).

    >>> datagrams("usv", "sub_3", {"end_ns": 2_500_000_000, "value": 1.5, "count": 6})
    [b'{"timestamp":2.5,"usv":{"sub_3":{"value":1.5,"count":6,"backfilled":0}}}']
    >>> [d[:16] for d in datagrams("usv", "a", {"start_ns": 0, "end_ns": 10**9,
    ...                                          "value": [1.0, 2.0], "count": 2})]
    [b'{"timestamp":0.5', b'{"timestamp":1.0']
    """
    value, end = delivered.get("value"), delivered.get("end_ns")
    if not isinstance(end, int) or value is None:
        return []
    start = delivered.get("start_ns")
    points: list[tuple[float, Any]]
    if isinstance(value, list):
        if not value or not isinstance(start, int):
            return []
        step = (end - start) / len(value)
        points = [((start + (i + 1) * step) / 1e9, v) for i, v in enumerate(value)]
    else:
        points = [(end / 1e9, value)]
    out: list[bytes] = []
    for i, (t, v) in enumerate(points):
        if v is None or (isinstance(v, float) and not math.isfinite(v)):
            continue
        fields: dict[str, Any] = {"value": v}
        if i == len(points) - 1:
            if isinstance(delivered.get("count"), int):
                fields["count"] = delivered["count"]
            fields["backfilled"] = 1 if delivered.get("backfilled") is True else 0
        doc = {"timestamp": t, drone: {subscriber: fields}}
        data = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode()
        if len(data) <= MAX_DATAGRAM:
            out.append(data)
    return out


def parse_udp(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--udp {text!r}: expected HOST:PORT, e.g. {DEFAULT_UDP}")
    return host.strip("[]"), int(port)


class PlotJugglerOut:
    """Subscribes to ``modd/<drone>/sub/*`` and sends a datagram per value."""

    def __init__(self, session: Any, target: tuple[str, int], drone: str = "*") -> None:
        self.target = target
        family = socket.AF_INET6 if ":" in target[0] else socket.AF_INET
        self.sock = socket.socket(family, socket.SOCK_DGRAM)
        self.sent = 0
        self.sub = session.declare_subscriber(
            keys.values_of(None if drone == "*" else drone), self._on
        )

    def _on(self, sample: Any) -> None:
        found = keys.match_sub_key(str(sample.key_expr))
        delivered = load_delivered(sample.payload.to_bytes())
        if found is None or delivered is None:
            return
        for data in datagrams(*found, delivered):
            try:
                self.sock.sendto(data, self.target)
                self.sent += 1
            except OSError as exc:  # nobody listening is fine for UDP
                log.debug("datagram not sent: %s", exc)
                return

    def close(self) -> None:
        self.sub.undeclare()
        self.sock.close()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="modd-plotjuggler", description=__doc__.splitlines()[0])
    p.add_argument(
        "--udp",
        default=DEFAULT_UDP,
        metavar="HOST:PORT",
        help=f"PlotJuggler's UDP server (default {DEFAULT_UDP})",
    )
    p.add_argument("--drone", default="*", help="drone name (default: every drone)")
    add_viewer_args(p)
    a = p.parse_args(argv)
    try:
        target = parse_udp(a.udp)
        session = open_session(client_settings(a.modd_connect, a.credentials))
    except ValueError as exc:
        print(f"modd-plotjuggler: {exc}", file=sys.stderr)
        return 2
    out = PlotJugglerOut(session, target, a.drone)
    values = keys.values_of(None if a.drone == "*" else a.drone)
    print(
        f"modd-plotjuggler: {values} -> udp {target[0]}:{target[1]} "
        "(PlotJuggler: UDP Server, JSON, timestamp field 'timestamp')",
        flush=True,
    )
    stop = threading.Event()
    stop_on_signals(stop)
    try:
        stop.wait()
    except KeyboardInterrupt:
        pass
    finally:
        out.close()
        session.close()  # type: ignore[no-untyped-call]
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
