"""The drone side of the zenoh comparison, as its own process: a zenoh router whose
downsampling interceptor (egress, ``put``) limits each subscriber's key to its
subscription's rate, and the publisher in the same session putting every sample of a topic
on each subscriber key of that topic at the sensor's rate (16-byte payload: publish time
ns, float32 value, sequence). Zenoh drops samples to reach the rate: it does not aggregate.

    python zenoh_drone.py --listen tcp/127.0.0.1:PORT --plan JSON --seconds S

``--plan`` is ``{"publishers": [[period_s, [topic, ...]], ...],
"keys": [[key, topic, freq_hz], ...]}``. Prints ``{"sent": N}`` on exit (SIGTERM or
after ``--seconds``).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import struct
import sys
from pathlib import Path
from types import FrameType

import zenoh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchkit.ticks import publisher_ticks  # noqa: E402

PAYLOAD = struct.Struct("<qfI")  # 16 bytes: publish time ns, value, sequence


def router_config(listen: str, keys: list[tuple[str, str, float]]) -> zenoh.Config:
    c = zenoh.Config()
    c.insert_json5("mode", '"router"')
    c.insert_json5("scouting/multicast/enabled", "false")
    c.insert_json5("scouting/delay", "0")
    c.insert_json5("listen/endpoints", json.dumps([listen]))
    rules = [{"key_expr": key, "freq": freq} for key, _, freq in keys]
    c.insert_json5(
        "downsampling", json.dumps([{"messages": ["put"], "flows": ["egress"], "rules": rules}])
    )
    return c


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--listen", required=True)
    ap.add_argument("--plan", required=True)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args(argv)
    plan = json.loads(args.plan)
    keys = [(str(k), str(t), float(f)) for k, t, f in plan["keys"]]
    stop = False

    def on_term(signum: int, frame: FrameType | None) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, on_term)
    session = zenoh.open(router_config(args.listen, keys))
    pubs = {key: session.declare_publisher(key) for key, _, _ in keys}
    by_topic: dict[str, list[str]] = {}
    for key, topic, _ in keys:
        by_topic.setdefault(topic, []).append(key)
    publishers = [(float(p), list(ts)) for p, ts in plan["publishers"]]
    print("ready", flush=True)
    sent = 0
    ticks = publisher_ticks([p for p, _ in publishers], args.seconds, lambda: stop)
    for seq, (i, now) in enumerate(ticks):
        for j, topic in enumerate(publishers[i][1]):
            payload = PAYLOAD.pack(now, math.sin(0.37 * seq + j), seq)
            for key in by_topic.get(topic, []):
                pubs[key].put(payload)
                sent += 1
    session.close()  # type: ignore[no-untyped-call]
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
