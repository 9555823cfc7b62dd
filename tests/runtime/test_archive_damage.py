"""Start-up recovery of crashed archive files with damaged bytes (issue 28, docs/pubbroker.md):
a real PubBroker is killed (kill -9), single-byte flips are made at 25 offsets of its file (each
flip in a copy of its own, and all 25 in one more, and one flip its decoder reads past in one
more), and the broker restarted on that directory recovers every copy. Oracle:
tests/support/mcap_oracle.py, chunk by chunk over the chunk boundaries of the undamaged file,
against the official `mcap` reader on the recovered files."""

from __future__ import annotations

import signal
import sys
import time
from pathlib import Path
from typing import Any

from mcap.reader import make_reader
from pubbroker_harness import run_load

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from support import mcap_oracle as oracle  # noqa: E402

TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]


def official_count(path: Path) -> int:
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None, path.name
        n = sum(1 for _ in reader.iter_messages())
    assert summary.statistics.message_count == n
    return n


def test_a_crashed_file_with_25_flipped_bytes_keeps_every_chunk_whose_data_checks(
    broker_factory: Any,
) -> None:
    b = broker_factory(archive={"chunk_bytes": 2048})
    run_load(f"unix:{b.unix_path}", TOPICS, 400.0, 1.5)
    time.sleep(0.5)  # flushed (every 200 ms)
    b.stop(signal.SIGKILL)
    [crashed] = sorted(b.archive_dir.glob("*.mcap"))
    data = crashed.read_bytes()
    assert not data.endswith(oracle.MAGIC)
    layout = oracle.records(data)
    assert sum(1 for op, _, _ in layout if op == oracle.CHUNK) >= 30
    everything = oracle.count_valid(data, layout)
    want: dict[str, int] = {}
    all_flips = data
    for i, (at, mask) in enumerate(oracle.flips(data, layout)):
        damaged = oracle.flipped(data, at, mask)
        all_flips = oracle.flipped(all_flips, at, mask)
        name = f"usv-flip{i:02d}.mcap"
        (b.archive_dir / name).write_bytes(damaged)
        want[name] = oracle.count_valid(damaged, layout)
    # a flip the broker's libzstd reads past and python-zstandard's refuses: the chunk is
    # kept, written anew, or the official reader below throws on the whole file
    past = oracle.read_past_flip(data, layout)
    assert past is not None
    (b.archive_dir / "usv-readpast.mcap").write_bytes(oracle.flipped(data, *past))
    want["usv-readpast.mcap"] = oracle.count_valid(oracle.flipped(data, *past), layout)
    assert want["usv-readpast.mcap"] == everything
    (b.archive_dir / "usv-flipall.mcap").write_bytes(all_flips)
    want["usv-flipall.mcap"] = oracle.count_valid(all_flips, layout)
    want[crashed.name] = everything
    # the test's power: most flips cost a chunk (the rest land in message indexes; how
    # many depends on how the load's timing cut the file: 14 to 19 seen)
    damaged_files = sum(1 for n in want.values() if n < everything)
    assert damaged_files >= 12

    b2 = broker_factory(archive={"dir": str(b.archive_dir), "chunk_bytes": 2048})
    assert b2.stop() == 0
    log = b2.log()
    assert "Traceback" not in log and "cannot recover" not in log
    got = {name: official_count(b.archive_dir / name) for name in want}
    assert got == want
    assert not list(b.archive_dir.glob("*.recovering"))
    assert log.count("skipped ") >= damaged_files  # each skipped region logged with its offset
    assert "1 chunks written anew from their data" in log
