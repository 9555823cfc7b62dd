"""A test flight's archive for the radio journey (radio.mjs): PATH.mcap
written with the official ``mcap`` writer, channels as the archive-record
contract says (contracts/vectors/archive_record.json), a smooth signal near 0
(a few hundredths of m/s²) at 25 Hz for SECONDS on each of usv's three
accelerometer topics.

Usage: python flight_archive.py PATH [SECONDS]"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from mcap.writer import CompressionType, Writer

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
START_NS = 1_700_000_000 * 1_000_000_000
STEP_NS = 40_000_000  # 25 Hz, as the model's publisher


def write(path: Path, seconds: int) -> None:
    channel = next(
        c
        for c in json.loads((VECTORS / "archive_record.json").read_text())["channels"]
        if c["type"] == "float32"
    )
    with path.open("wb") as f:
        w = Writer(f, compression=CompressionType.ZSTD)
        w.start(profile="", library="modd e2e flight_archive.py")
        sid = w.register_schema(
            channel["schema_name"], channel["schema_encoding"], channel["schema_data"].encode()
        )
        for i, topic in enumerate(TOPICS):
            cid = w.register_channel(topic, channel["message_encoding"], sid, channel["metadata"])
            for k in range(seconds * 25):
                t = START_NS + k * STEP_NS
                x = 0.03 * math.sin(k / 100 + i)
                w.add_message(cid, log_time=t, publish_time=t, data=b'{"value":%r}' % x)
        w.finish()  # type: ignore[no-untyped-call]


if __name__ == "__main__":
    write(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 60)
