"""``modd archive info FILE``: what an MCAP archive holds, per topic: message
count, first and last log time, and the gaps (silences much longer than the
topic's usual interval), for closed and crashed files alike.

>>> summary = archive_info("usv.mcap")                      # doctest: +SKIP
>>> summary.topics["usv.gps.latitude"].count                # doctest: +SKIP
1200
"""

from __future__ import annotations

import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .scan import scan_file

#: A silence is a gap when longer than this many times the median interval.
GAP_FACTOR = 5.0


@dataclass
class TopicInfo:
    topic: str
    count: int = 0
    first_ns: int | None = None
    last_ns: int | None = None
    median_interval_ns: int | None = None
    gaps: list[tuple[int, int]] = field(default_factory=list)


@dataclass
class ArchiveInfo:
    path: Path
    complete: bool
    stopped_at: str | None
    messages: int
    topics: dict[str, TopicInfo]

    @property
    def start_ns(self) -> int | None:
        firsts = [t.first_ns for t in self.topics.values() if t.first_ns is not None]
        return min(firsts) if firsts else None

    @property
    def end_ns(self) -> int | None:
        lasts = [t.last_ns for t in self.topics.values() if t.last_ns is not None]
        return max(lasts) if lasts else None

    def to_json(self) -> dict[str, Any]:
        return {
            "file": str(self.path),
            "complete": self.complete,
            "stopped_at": self.stopped_at,
            "messages": self.messages,
            "start_ns": self.start_ns,
            "end_ns": self.end_ns,
            "topics": [
                {
                    "topic": t.topic,
                    "count": t.count,
                    "first_ns": t.first_ns,
                    "last_ns": t.last_ns,
                    "median_interval_ns": t.median_interval_ns,
                    "gaps": [{"from_ns": a, "to_ns": b} for a, b in t.gaps],
                }
                for t in sorted(self.topics.values(), key=lambda t: t.topic)
            ],
        }


def find_gaps(
    times: list[int], factor: float = GAP_FACTOR, min_gap_ns: int | None = None
) -> tuple[int | None, list[tuple[int, int]]]:
    """Median interval of sorted ``times`` and the silences longer than
    ``factor`` times it (or than ``min_gap_ns`` when given).

    >>> find_gaps([0, 10, 20, 30, 200, 210])
    (10, [(30, 200)])
    """
    if len(times) < 2:
        return None, []
    intervals = [b - a for a, b in zip(times, times[1:], strict=False)]
    median = int(statistics.median(intervals))
    limit = min_gap_ns if min_gap_ns is not None else max(1, int(median * factor))
    gaps = [(a, b) for a, b in zip(times, times[1:], strict=False) if b - a > limit]
    return median, gaps


def archive_info(path: str | Path, min_gap_ns: int | None = None) -> ArchiveInfo:
    scan = scan_file(path)
    by_topic: dict[str, list[int]] = {}
    for m in scan.messages:
        ch = scan.channels.get(m.channel_id)
        topic = ch.topic if ch is not None else f"<channel {m.channel_id}>"
        by_topic.setdefault(topic, []).append(m.log_time)
    for ch in scan.channels.values():
        by_topic.setdefault(ch.topic, [])
    topics: dict[str, TopicInfo] = {}
    for topic, times in by_topic.items():
        times.sort()
        median, gaps = find_gaps(times, min_gap_ns=min_gap_ns)
        topics[topic] = TopicInfo(
            topic,
            len(times),
            times[0] if times else None,
            times[-1] if times else None,
            median,
            gaps,
        )
    return ArchiveInfo(Path(path), scan.complete, scan.error, len(scan.messages), topics)


def _iso(ns: int | None) -> str:
    if ns is None:
        return "-"
    import datetime as dt

    t = dt.datetime.fromtimestamp(ns / 1e9, tz=dt.UTC)
    return t.strftime("%Y-%m-%dT%H:%M:%S.%f")[:-3] + "Z"


def format_info(info: ArchiveInfo) -> str:
    """The human-readable report of ``modd archive info``."""
    state = "closed" if info.complete else "NOT CLOSED (crash?): run `modd archive recover`"
    lines = [
        f"{info.path}: {info.messages} messages, {len(info.topics)} topics, {state}",
        f"time range: {_iso(info.start_ns)} .. {_iso(info.end_ns)}",
    ]
    if info.stopped_at:
        lines.append(f"skipped: {info.stopped_at}")
    width = max((len(t) for t in info.topics), default=5)
    for t in sorted(info.topics.values(), key=lambda t: t.topic):
        period = f"{t.median_interval_ns / 1e6:.1f} ms" if t.median_interval_ns else "-"
        lines.append(
            f"  {t.topic:<{width}}  {t.count:>9}  {_iso(t.first_ns)} .. "
            f"{_iso(t.last_ns)}  every {period}  gaps {len(t.gaps)}"
        )
        for a, b in t.gaps[:10]:
            lines.append(f"  {'':<{width}}    gap {(b - a) / 1e9:.3f} s from {_iso(a)}")
        if len(t.gaps) > 10:
            lines.append(f"  {'':<{width}}    ... {len(t.gaps) - 10} more gaps")
    return "\n".join(lines)
