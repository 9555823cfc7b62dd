"""The drone's wall clock stepped under a running PubBroker (docs/pubbroker.md,
"Clock steps"): a companion computer without RTC boots on a stale clock and
GPS/NTP sets it forward (+3 days, +30 days), or NTP sets it back (-2 h). The
step is real for the process: libfaketime (apt package faketime) moves its
CLOCK_REALTIME through a file while CLOCK_MONOTONIC runs on. Oracles: the
windows a base station receives (the plan's cadence, contiguous slots, bytes),
the archive read with the official MCAP reader, the run's counters file.
Was: +30 days walked 10.4 M slots (82 s without ingest), -2 h stopped live
delivery for 2 h."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import pytest
from pubbroker_harness import (
    BaseStation,
    PubBroker,
    hand_config_scenario1,
    read_archive,
    run_load,
)

FAKETIME = Path("/usr/lib/x86_64-linux-gnu/faketime/libfaketimeMT.so.1")
pytestmark = pytest.mark.skipif(
    not FAKETIME.exists(), reason="libfaketime is missing (apt-get install faketime)"
)

TOPICS = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
WINDOW_NS = 250_000_000  # scenario 1: every stream every 0.25 s (the hyperperiod)
BEFORE_S, AFTER_S = 2.5, 3.0


@pytest.mark.parametrize(
    "step_s", [3 * 86400, 30 * 86400, -2 * 3600], ids=["forward-3d", "forward-30d", "back-2h"]
)
def test_a_wall_clock_step_costs_nothing(
    step_s: int, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    offset = tmp_path / "faketime"
    offset.write_text("+0\n")
    with monkeypatch.context() as env:  # the PubBroker only
        env.setenv("LD_PRELOAD", str(FAKETIME))
        env.setenv("FAKETIME_TIMESTAMP_FILE", str(offset))
        env.setenv("FAKETIME_CACHE_DURATION", "0")
        env.setenv("FAKETIME_DONT_FAKE_MONOTONIC", "1")
        pb = PubBroker(
            tmp_path,
            [(t, "float32") for t in TOPICS],
            ingress={"max_future_ms": 0, "max_past_ms": 0},
        ).start()
    try:
        bs = BaseStation(pb.link_port).start()
        bs.configure(hand_config_scenario1())
        stop = threading.Event()
        published: list[int] = []
        seconds = BEFORE_S + AFTER_S + 1
        load = threading.Thread(
            target=lambda: published.append(
                run_load(f"unix:{pb.unix_path}", TOPICS, 100, seconds, stop=stop).published
            )
        )
        load.start()
        time.sleep(BEFORE_S)
        before = bs.snapshot()
        offset.write_text(f"{step_s:+d}\n")
        stepped = time.monotonic()
        time.sleep(AFTER_S)
        after = bs.snapshot()
        load.join()
        time.sleep(0.5)  # the last windows
        bs.close()
    finally:
        pb.stop()
    assert published and not stop.is_set()
    frames_after = after.data_frames - before.data_frames
    bytes_after = after.data_bytes - before.data_bytes
    print(
        f"step {step_s:+d} s: {frames_after} DATA frames, {bytes_after} B in {AFTER_S} s "
        f"after it ({before.data_frames} frames, {before.data_bytes} B in {BEFORE_S} s before); "
        f"{time.monotonic() - stepped:.1f} s"
    )
    # the plan's cadence across the step: 4 windows a second, none walked, none held
    plan = AFTER_S * 1e9 / WINDOW_NS
    assert plan - 3 <= frames_after <= plan + 2, frames_after
    assert bytes_after <= 2 * before.data_bytes / BEFORE_S * AFTER_S
    slots = sorted({w.slot for w in after.windows})
    assert slots == list(range(slots[0], slots[-1] + 1))  # contiguous: no gap at the step
    ends = sorted({w.end_ns for w in after.windows})
    assert all(b - a == WINDOW_NS for a, b in zip(ends, ends[1:], strict=False))
    # everything archived, log times on the broker's timeline (no jump, no hold)
    archive = read_archive(pb.archive_dir)
    assert sum(len(v) for v in archive.values()) == published[0]
    for samples in archive.values():
        gaps = [b.log_time - a.log_time for a, b in zip(samples, samples[1:], strict=False)]
        assert min(gaps) >= 0 and max(gaps) < 1_000_000_000, (min(gaps), max(gaps))
    # the step is said where the run's counters are kept
    record = json.loads(next(pb.archive_dir.glob("*.counters.json")).read_text())
    assert record["clock"]["steps"] == 1, record
    assert abs(record["clock"]["last_step_ns"] - step_s * 1_000_000_000) < 1_000_000_000
    assert "clock: CLOCK_REALTIME stepped" in pb.log()
