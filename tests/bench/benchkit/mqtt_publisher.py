"""A drone-side MQTT publisher, as its own process: every publisher of the load publishes
each sample of each of its topics as one QoS 0 PUBLISH (16-byte payload: publish time ns,
float32 value, sequence) at its period, over one raw MQTT connection.

    python mqtt_publisher.py --port PORT --load JSON --seconds S

``--load`` is ``[[period_s, [topic, ...]], ...]`` (MQTT topic names). Prints
``{"sent": {topic: n}}`` on exit (SIGTERM or after ``--seconds``).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
from pathlib import Path
from types import FrameType

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchkit.mqtt import PAYLOAD, open_client, publish_packet  # noqa: E402
from benchkit.ticks import publisher_ticks  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--load", required=True)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args(argv)
    publishers = [(float(p), [str(t) for t in ts]) for p, ts in json.loads(args.load)]
    stop = False

    def on_term(signum: int, frame: FrameType | None) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, on_term)
    sock = open_client(args.port, "drone-publisher")
    sent = {t: 0 for _, ts in publishers for t in ts}
    ticks = publisher_ticks([p for p, _ in publishers], args.seconds, lambda: stop)
    for seq, (i, now) in enumerate(ticks):
        for j, topic in enumerate(publishers[i][1]):
            sock.sendall(publish_packet(topic, PAYLOAD.pack(now, math.sin(0.37 * seq + j), seq)))
            sent[topic] += 1
    sock.close()
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
