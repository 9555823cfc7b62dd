"""An ingest load as fast as the broker reads it, as its own process (pinned to a core by
the caller): pre-encoded batches written over one loopback TCP connection.

    python blaster.py modd --port P --topics a,b,... --count N
    python blaster.py mqtt --port P --topics a/b,... --count N

``modd``: SAMPLES frames of 4096 float32 records (13 B each: id, timestamp, value; the
project's ingress protocol, docs/ingress.md), timestamps rising, then a half-close and a
wait for the broker to close its side (it has read every byte). ``mqtt``: QoS 0 PUBLISH
packets with a 16-byte payload, 4096 per write, then a QoS 1 PUBLISH whose PUBACK proves
that the broker has read every packet before it. Connects, prints ``ready``, waits for a
line on stdin, sends, prints ``{"sent": N}`` and exits (for mqtt, once the end marker is
acknowledged).
"""

from __future__ import annotations

import argparse
import json
import socket
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from modd.link.codec import varint  # noqa: E402
from modd.link.frames import ValueType  # noqa: E402
from modd.publisher import encode_hello, encode_register  # noqa: E402

from benchkit.mqtt import (  # noqa: E402
    PAYLOAD,
    open_client,
    publish_packet,
    publish_qos1_packet,
    wait_puback,
)

BATCH = 4096
RECORD = np.dtype([("id", "u1"), ("ts", "<i8"), ("v", "<f4")])


def blast_modd(port: int, topics: list[str], count: int) -> int:
    s = socket.create_connection(("127.0.0.1", port))
    s.sendall(
        encode_hello("blaster")
        + b"".join(encode_register(i, ValueType.FLOAT32, t) for i, t in enumerate(topics))
    )
    arr = np.zeros(BATCH, dtype=RECORD)
    arr["id"] = np.arange(BATCH) % len(topics)
    head = bytes([0x03]) + varint(BATCH)
    frame_len = varint(len(head) + BATCH * RECORD.itemsize)
    k = np.arange(BATCH)
    print("ready", flush=True)
    sys.stdin.readline()
    ts0, sent = time.time_ns(), 0
    while sent < count:
        arr["ts"] = ts0 + (sent + k) // len(topics)
        arr["v"] = np.sin((sent + k) * 0.01)
        s.sendall(frame_len + head + arr.tobytes())
        sent += BATCH
    s.shutdown(socket.SHUT_WR)  # the broker closes its side once it has read everything
    s.settimeout(300)
    while s.recv(4096):
        pass
    s.close()
    return sent


def blast_mqtt(port: int, topics: list[str], count: int) -> int:
    s = open_client(port, f"blaster-{topics[0]}")
    chunk = b"".join(
        publish_packet(topics[i % len(topics)], PAYLOAD.pack(i, 0.5, i)) for i in range(BATCH)
    )
    print("ready", flush=True)
    sys.stdin.readline()
    sent = 0
    while sent < count:
        s.sendall(chunk)
        sent += BATCH
    s.sendall(publish_qos1_packet("bench/end", b"end"))
    wait_puback(s)
    s.close()
    return sent


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("protocol", choices=("modd", "mqtt"))
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--topics", required=True)
    ap.add_argument("--count", type=int, required=True)
    args = ap.parse_args()
    blast = blast_modd if args.protocol == "modd" else blast_mqtt
    sent = blast(args.port, args.topics.split(","), args.count)
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
