"""A publisher load for the end-to-end tests and the benchmark: every
publisher of a model publishes all its topics at its period, through the
PubBroker's ingress protocol (docs/ingress.md), with seeded random values.

    python tests/subbroker/loadgen.py --model M --ingress 127.0.0.1:PORT --seconds 30

It is a separate process, as a sensor driver would be; it stops on SIGTERM
or after ``--seconds``. It uses the project's Python publisher client when
that is importable, else writes the ingress frames itself.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import signal
import socket
import struct
import sys
import time
from fractions import Fraction
from types import FrameType

from modd_model import load_model

TYPES = {"float32": (0, "<f"), "float64": (1, "<d"), "int": (2, "<q"), "bool": (3, "<B")}


def varint(v: int) -> bytes:
    out = bytearray()
    while True:
        b = v & 0x7F
        v >>= 7
        if v:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def string(s: str) -> bytes:
    data = s.encode()
    return varint(len(data)) + data


def frame(mtype: int, body: bytes) -> bytes:
    return varint(len(body) + 1) + bytes([mtype]) + body


def value_for(rng: random.Random, vtype: str) -> float | int:
    if vtype == "bool":
        return rng.randint(0, 1)
    if vtype == "int":
        return rng.randint(-1000, 1000)
    return rng.uniform(-10.0, 10.0)


def wave(rng: random.Random, topic: int, t: float) -> float:
    """A smooth signal, as an accelerometer on a boat: what a declared resolution
    is for (consecutive windows a few steps apart)."""
    return math.sin(2 * math.pi * t / 8.0 + topic) + rng.gauss(0.0, 0.01)


def _value(
    signal_: str, rng: random.Random, topic: int, vtype: str, start: float, k: int
) -> float | int:
    if signal_ == "wave" and vtype.startswith("float"):
        return wave(rng, topic, time.monotonic() - start)
    if signal_ == "scripted" and vtype.startswith("float"):
        return scripted(rng, topic, k)
    return value_for(rng, vtype)


def scripted(rng: random.Random, topic: int, k: int) -> float:
    """The event subscriptions' script (tests/subbroker/test_events_e2e.py), 10 s
    at 25 Hz repeated, a phase of 2 s per topic: steps (4, then 6), a ramp down
    from 6 to 3, noise around 5 (sigma 0.3), a signal flapping between 4 and 6."""
    part, i = divmod((k + 50 * topic) % 250, 50)
    if part == 0:
        return 4.0
    if part == 1:
        return 6.0
    if part == 2:
        return 6.0 - 3.0 * i / 49
    if part == 3:
        return 5.0 + rng.gauss(0.0, 0.3)
    return 4.0 if i % 2 else 6.0


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--model", required=True)
    p.add_argument("--ingress", required=True, help="host:port of the PubBroker's TCP ingress")
    p.add_argument("--seconds", type=float, default=30.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--record", help="append every sample sent to this file (JSON lines)")
    p.add_argument(
        "--signal",
        choices=("uniform", "wave", "scripted"),
        default="uniform",
        help="float values: uniform in [-10, 10] (default), a sea wave "
        "(1 m/s2, 8 s period, a phase per topic) plus 0.01 of noise, or the event "
        "tests' script (steps, a ramp, noise around 5, flapping)",
    )
    args = p.parse_args(argv)
    model = load_model(args.model)
    types = {
        f"{model['drone']['name']}.{s['name']}.{v['name']}": v.get("type", "float32")
        for s in model["drone"]["sensors"]
        for v in s["variables"]
    }
    host, port = args.ingress.rsplit(":", 1)
    stop = False

    def on_term(signum: int, frame_: FrameType | None) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, on_term)
    rng = random.Random(args.seed)
    record = open(args.record, "a") if args.record else None  # noqa: SIM115
    sock = socket.create_connection((host, int(port)))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.sendall(frame(0x01, bytes([1]) + string("loadgen")))
    ids: dict[str, int] = {}
    for pub in model.get("publishers", []):
        for topic in pub["topics"]:
            if topic not in ids:
                ids[topic] = len(ids)
                sock.sendall(
                    frame(
                        0x02, varint(ids[topic]) + bytes([TYPES[types[topic]][0]]) + string(topic)
                    )
                )
    pubs = [(Fraction(pub["periodS"]), pub["topics"]) for pub in model.get("publishers", [])]
    sent = dict.fromkeys(ids, 0)
    start = time.monotonic()
    due = [start + float(period) for period, _ in pubs]
    while not stop and time.monotonic() - start < args.seconds:
        i = min(range(len(pubs)), key=lambda k: due[k])
        delay = due[i] - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        now = time.time_ns()
        records = b""
        values = [
            _value(args.signal, rng, ids[topic], types[topic], start, sent[topic])
            for topic in pubs[i][1]
        ]
        for topic, value in zip(pubs[i][1], values, strict=True):
            code, fmt = TYPES[types[topic]]
            records += varint(ids[topic]) + struct.pack("<q", now) + struct.pack(fmt, value)
        try:
            sock.sendall(frame(0x03, varint(len(pubs[i][1])) + records))
        except OSError:  # the PubBroker is gone: report what it accepted to take
            break
        for topic in pubs[i][1]:
            sent[topic] += 1
        if record is not None:
            record.write(json.dumps([now, dict(zip(pubs[i][1], values, strict=True))]) + "\n")
            record.flush()
        due[i] += float(pubs[i][0])
    sock.close()
    if record is not None:
        record.close()
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
