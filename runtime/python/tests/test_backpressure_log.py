"""The SubBroker's backpressure log over a radio (issue 28): a NACKed slot that
arrives late is a short episode of falling behind; one log line per change was
~15 MB a day. The first episode of a quiet minute is logged as it happens, the
next ones summed up in one line a minute; the status counts every one."""

from __future__ import annotations

import logging
import re

import pytest
from modd.subbroker.backpressure import Backpressure

SLOT_NS = 250_000_000


def _radio_day(bp: Backpressure, minutes: int) -> int:
    """Slots every 0.25 s, one in 20 delivered 1.5 s late (its resend); the number of
    late slots, each one episode (the next slot is on time again)."""
    late = 0
    for k in range(minutes * 240):
        end = k * SLOT_NS
        delay = 1_500_000_000 if k % 20 == 19 else 2_000_000
        late += k % 20 == 19
        bp.observe(end, 0, end + delay)
    return late


def test_short_episodes_over_a_radio_log_one_line_a_minute(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger="modd.subbroker.backpressure")
    bp = Backpressure(behind_lag_s=1.0)
    late = _radio_day(bp, minutes=10)
    assert bp.episodes == late == 120  # the status still counts every episode
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) <= 2 + 10, lines  # was 2 a late slot: 240 lines
    assert lines[0].startswith("falling behind") and lines[1].startswith("caught up")
    counted = [
        re.match(
            r"over the last (\d+) s: fell behind the link (\d+) times, "
            r"caught up (\d+) times",
            line,
        )
        for line in lines[2:]
    ]
    assert all(counted), lines
    fell = sum(int(m.group(2)) for m in counted if m)
    caught = sum(int(m.group(3)) for m in counted if m)
    assert all(60 <= int(m.group(1)) <= 61 for m in counted if m)
    # every episode but the ones of the last, unfinished minute is in a line
    assert late - 1 - 12 <= fell <= late - 1 and caught == fell  # 12 late slots a minute


def test_a_lone_episode_is_logged_as_it_happens(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="modd.subbroker.backpressure")
    bp = Backpressure(behind_lag_s=1.0, log_every_s=60.0)
    bp.observe(0, 0, 2_000_000)
    for n, at_s in enumerate((10, 200, 400)):  # minutes apart: each one logged whole
        end = at_s * 10**9
        bp.observe(end, 0, end + 3 * 10**9)
        bp.observe(end + SLOT_NS, 0, end + SLOT_NS + 2_000_000)
        assert len(caplog.records) == 2 * (n + 1)
    assert [r.getMessage().split(" ")[0] for r in caplog.records] == ["falling", "caught"] * 3
