"""Reading a drone's on-board archives (MCAP files written by the PubBroker,
one channel per topic, JSON messages ``{"value": ...}``) with the official
``mcap`` reader. A closed file is read through its index; a file still being
written (or cut short by a crash) is read as a stream up to its last complete
record, so whatever was flushed is readable.

Paths: only ``<archive_dir>/<drone>/<name>.mcap`` (or ``<archive_dir>/<name>.mcap``
when there is no folder per drone) with plain file names; nothing outside the
archive directory can be reached."""

from __future__ import annotations

import re
import struct
from collections.abc import Iterator
from dataclasses import dataclass
from itertools import islice
from pathlib import Path
from typing import Any

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Message
from mcap.stream_reader import StreamReader
from modd_contracts.archive_record import value_of

from .errors import ApiError

DRONE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
FILE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*\.mcap")
Sample = tuple[int, Any]
#: What the reader raises on a file cut short or not yet closed.
_BROKEN = (McapError, EOFError, ValueError, OSError, struct.error)


def drone_dir(root: Path, drone: str) -> Path:
    """``<root>/<drone>`` when that folder exists (several drones), else the
    archive directory itself (one drone, as ``modd up`` lays it out). Resolved;
    a drone folder that resolves outside the archive directory (a symlink
    out) is a 404."""
    if not DRONE.fullmatch(drone):
        raise ApiError(422, f"drone {drone!r} is not an identifier")
    base = root.resolve()
    own = root / drone
    if own.is_symlink() or own.is_dir():
        real = own.resolve()
        if not real.is_relative_to(base) or real == base:
            raise ApiError(404, f"no archives for drone {drone!r}")
        return real
    return base


def _confined(path: Path, folder: Path) -> bool:
    """A regular file directly in ``folder`` once every link is resolved."""
    real = path.resolve()
    return real.parent == folder and real.is_file()


def archive_path(root: Path, drone: str, name: str) -> Path:
    """The file, checked to be a direct child of the drone's folder; 404 otherwise."""
    if not FILE.fullmatch(name) or ".." in name:
        raise ApiError(404, f"no archive named {name!r}")
    folder = drone_dir(root, drone)
    path = folder / name
    if not _confined(path, folder):
        raise ApiError(404, f"no archive {name!r} for drone {drone!r}")
    return path.resolve()


def list_files(root: Path, drone: str) -> list[Path]:
    if not root.is_dir():
        return []
    folder = drone_dir(root, drone)
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if FILE.fullmatch(p.name) and _confined(p, folder))


def _value(data: bytes) -> Any:
    """The sample of an archive record (contract ``archive_record``), None if it is not one."""
    return value_of(data)


def _stream(path: Path) -> Iterator[tuple[str, Message]]:
    """Every complete message, in file order, stopping quietly at a cut tail."""
    channels: dict[int, str] = {}
    with path.open("rb") as f:
        try:
            for rec in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(rec, Channel):
                    channels[rec.id] = rec.topic
                elif isinstance(rec, Message) and rec.channel_id in channels:
                    yield channels[rec.channel_id], rec
        except _BROKEN:
            return


@dataclass(frozen=True)
class FileInfo:
    name: str
    size: int
    complete: bool  # has a summary (closed cleanly)
    start_ns: int | None
    end_ns: int | None
    topics: dict[str, int]  # topic -> message count

    def to_json(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "size": self.size,
            "complete": self.complete,
            "start_ns": self.start_ns,
            "end_ns": self.end_ns,
            "topics": [{"topic": t, "messages": n} for t, n in sorted(self.topics.items())],
        }


def file_info(path: Path) -> FileInfo:
    try:
        with path.open("rb") as f:
            summary = make_reader(f).get_summary()
    except _BROKEN:
        summary = None
    if summary is not None and summary.statistics is not None:
        st = summary.statistics
        counts = {
            ch.topic: st.channel_message_counts.get(cid, 0) for cid, ch in summary.channels.items()
        }
        return FileInfo(
            path.name,
            path.stat().st_size,
            True,
            st.message_start_time if st.message_count else None,
            st.message_end_time if st.message_count else None,
            counts,
        )
    topics: dict[str, int] = {}
    first = last = None
    for topic, msg in _stream(path):
        topics[topic] = topics.get(topic, 0) + 1
        first = msg.log_time if first is None else min(first, msg.log_time)
        last = msg.log_time if last is None else max(last, msg.log_time)
    return FileInfo(path.name, path.stat().st_size, False, first, last, topics)


def read_topic(
    path: Path, topic: str, start_ns: int | None, end_ns: int | None, limit: int | None = None
) -> list[Sample]:
    """(log time ns, value) of ``topic`` in [start, end), in time order;
    reading stops after ``limit + 1`` samples (the caller refuses the range)."""
    stop = None if limit is None else limit + 1
    try:
        with path.open("rb") as f:
            reader = make_reader(f)
            if reader.get_summary() is not None:
                messages = reader.iter_messages(
                    topics=[topic], starting_at=start_ns, ending_before=end_ns
                )
                return [(m.log_time, _value(m.data)) for _s, _c, m in islice(messages, stop)]
    except _BROKEN:
        pass
    wanted = (
        m
        for t, m in _stream(path)
        if t == topic
        and (start_ns is None or m.log_time >= start_ns)
        and (end_ns is None or m.log_time < end_ns)
    )
    out = [(m.log_time, _value(m.data)) for m in islice(wanted, stop)]
    out.sort(key=lambda s: s[0])
    return out


def reduce_minmax(samples: list[Sample], max_points: int) -> list[Sample]:
    """At most ``max_points`` samples for plotting: per time bucket, its
    minimum and maximum (in time order), so peaks survive the reduction.

    >>> reduce_minmax([(t, v) for t, v in enumerate([0, 5, 1, 9, 2, 3])], 4)
    [(0, 0), (1, 5), (3, 9), (4, 2)]
    """
    numeric = [s for s in samples if isinstance(s[1], int | float)]
    if len(samples) <= max_points or max_points < 2 or len(numeric) != len(samples):
        return samples[:max_points] if len(samples) > max_points else samples
    buckets = max_points // 2
    size = -(-len(samples) // buckets)
    out: list[Sample] = []
    for i in range(0, len(samples), size):
        chunk = samples[i : i + size]
        lo = min(chunk, key=lambda s: s[1])
        hi = max(chunk, key=lambda s: s[1])
        out.extend(sorted({lo, hi}, key=lambda s: s[0]) if lo != hi else [lo])
    return out
