# ruff: noqa: E501  (the vector table reads best one vector per line)
"""Writes the shared ingress-protocol (version 2) test vectors with the Python codec.

Run: .venv/bin/python contracts/vectors/generate.py (the one writer)
The C++ codec (runtime/cpp/tests/test_ingress.cpp) and the Python codec
(runtime/python/tests/test_ingress_vectors.py) both decode every vector's hex to the listed
message and encode the message back to the same hex.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from modd.ingress import (
    Ack,
    Catalogue,
    Reject,
    encode_ack,
    encode_catalogue,
    encode_hello,
    encode_reject,
)
from modd.link.frames import ValueType

HERE = Path(__file__).parent


def vectors() -> list[dict[str, Any]]:
    cat = Catalogue(
        "usv",
        10_000,
        3_600_000,
        False,
        {"usv.accelerometer.accel_z": ValueType.FLOAT32, "usv.gps.fix": ValueType.BOOL},
    )
    rej = Reject(
        0,
        3,
        1,
        "topic 'usv.accelerometer.accel_z': timestamp 4354000000000000000 ns is "
        "2.59e+09 s ahead of the broker clock (bounds: 10000 ms ahead, 3600000 ms behind)",
    )
    return [
        {
            "name": "hello_v2",
            "meaning": "HELLO, version 2, publisher pub_1",
            "hex": encode_hello("pub_1").hex(),
            "message": {"type": "HELLO", "version": 2, "publisher": "pub_1"},
        },
        {
            "name": "catalogue",
            "meaning": "CATALOGUE of drone usv: bounds 10 s ahead, 1 h behind, two topics",
            "hex": encode_catalogue(cat).hex(),
            "message": {
                "type": "CATALOGUE",
                "drone": cat.drone,
                "max_future_ms": cat.max_future_ms,
                "max_past_ms": cat.max_past_ms,
                "accept_unknown": cat.accept_unknown,
                "topics": [[n, t.label] for n, t in cat.topics.items()],
            },
        },
        {
            "name": "ack",
            "meaning": "ACK: 300 records received, 256 settled, 250 of them on disk",
            "hex": encode_ack(Ack(300, 256, 250)).hex(),
            "message": {"type": "ACK", "received": 300, "settled": 256, "archived": 250},
        },
        {
            "name": "reject",
            "meaning": "REJECT: one record of local id 0 refused, timestamp out of bounds",
            "hex": encode_reject(rej).hex(),
            "message": {
                "type": "REJECT",
                "local_id": rej.local_id,
                "reason": rej.reason,
                "count": rej.count,
                "detail": rej.detail,
            },
        },
    ]


def write(here: Path) -> None:
    (here / "replies.json").write_text(json.dumps(vectors(), indent=1) + "\n")


if __name__ == "__main__":  # contracts/vectors/generate.py writes every vector
    write(HERE)
    print(f"wrote {HERE / 'replies.json'}")
