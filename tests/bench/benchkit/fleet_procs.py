"""Processes of the fleet benchmark that are not the project's own daemons: a zenoh
router (a Python session in router mode) and one publisher load feeding every drone's
PubBroker (its TCP ingress, docs/ingress.md) from a single process.

    python fleet_procs.py router --listen tcp/127.0.0.1:PORT --credentials DIR
    python fleet_procs.py load --targets '[["d0", 7001, MODEL_JSON_PATH], ...]' --seconds S
"""

from __future__ import annotations

import argparse
import json
import random
import signal
import socket
import struct
import sys
import threading
import time
from pathlib import Path
from types import FrameType
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "subbroker"))

from loadgen import TYPES, frame, string, value_for, varint  # noqa: E402


def router(listen: str, credentials: str) -> None:
    """A router with a SubBroker's authentication and access control (every drone)."""
    from modd.zenoh_auth import CredentialStore, acl
    from modd.zenoh_session import ZenohSettings, open_session

    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda s, f: stop.set())
    store = CredentialStore(credentials).ensure()
    session = open_session(
        ZenohSettings(
            mode="router",
            listen=(listen,),
            dictionary_file=str(store.dictionary),
            access_control=acl(None),
            extra={"scouting/gossip/enabled": "false"},
        )
    )
    print("ready", flush=True)
    stop.wait()
    session.close()  # type: ignore[no-untyped-call]


def load(targets: list[tuple[str, int, str]], seconds: float) -> None:
    """Every drone's publishers at their period, one TCP ingress connection per drone."""
    stop = False

    def on_term(signum: int, frame_: FrameType | None) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, on_term)
    rng = random.Random(1)
    jobs: list[list[Any]] = []  # (due, period, sock, records of (id, type) per topic)
    start = time.monotonic()
    for _, port, path in targets:
        model = json.loads(Path(path).read_text())
        types = {
            f"{model['drone']['name']}.{s['name']}.{v['name']}": v.get("type", "float32")
            for s in model["drone"]["sensors"]
            for v in s["variables"]
        }
        sock = socket.create_connection(("127.0.0.1", port))
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.sendall(frame(0x01, bytes([1]) + string("fleet-load")))
        ids: dict[str, int] = {}
        for pub in model["publishers"]:
            topics = []
            for topic in pub["topics"]:
                if topic not in ids:
                    ids[topic] = len(ids)
                    sock.sendall(
                        frame(
                            0x02,
                            varint(ids[topic]) + bytes([TYPES[types[topic]][0]]) + string(topic),
                        )
                    )
                topics.append((ids[topic], types[topic]))
            period = float(pub["periodS"])
            jobs.append([start + period, period, sock, topics])
    print("ready", flush=True)
    sent = 0
    while not stop and time.monotonic() - start < seconds:
        job = min(jobs, key=lambda j: j[0])
        delay = job[0] - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        now = time.time_ns()
        body = b"".join(
            varint(i) + struct.pack("<q", now) + struct.pack(TYPES[t][1], value_for(rng, t))
            for i, t in job[3]
        )
        try:
            job[2].sendall(frame(0x03, varint(len(job[3])) + body))
        except OSError:
            break
        sent += len(job[3])
        job[0] += job[1]
    print(json.dumps({"sent": sent}), flush=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["router", "load"])
    ap.add_argument("--listen")
    ap.add_argument("--credentials", help="credentials directory (made when missing)")
    ap.add_argument("--targets")
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    if args.what == "router":
        router(args.listen, args.credentials)
    else:
        load([tuple(t) for t in json.loads(args.targets)], args.seconds)
    return 0


if __name__ == "__main__":
    sys.exit(main())
