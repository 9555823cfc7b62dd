"""The backfill queue as the base station sees it (docs/subbroker.md, "Backfill": "The
queue's view and the time left"), without I/O.

A fill goes by bursts: jobs are served one run (one link request) at a time, each run
costs a round trip before its first frame, and the drone answers a window only once its
archive holds it. A pace in windows per second foresees none of this, so the time left is
computed from what the queue knows instead: each job's windows left times its measured
bytes per window at the link's measured backfill pace, plus the measured round trip of
each run still to ask. Where it cannot be computed (nothing measured yet, the request in
flight waiting for the drone's archive or for the link), no number is given, and the
job's ``state`` says what it waits for.

>>> m = PaceMeter()
>>> m.data(1, ("MIN", "float64"), 0.0, 100, 10, None)
>>> m.data(1, ("MIN", "float64"), 0.5, 100, 10, None)
>>> m.data(1, ("MIN", "float64"), 1.0, 100, 10, None)
>>> m.pace_bps(), m.window_bytes(("MIN", "float64"))
(200.0, 10.0)
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

#: Jobs listed in the queue's view (the rest are counted in ``more``).
MAX_VIEW = 32
#: Sizes kept, one per (aggregation, value type).
MAX_SIZES = 256

#: What a job waits for, in the order the view names them.
STATES = ("sending", "asking", "unanswered", "waiting_archive", "waiting_link", "busy", "queued")

Size = tuple[str, str]  # (aggregation label, value type) of a run


@dataclass
class PaceMeter:
    """The link's backfill pace (bytes/s between DATA frames, a pause longer than
    ``pause_s`` not counted: the drone waited for its archive; a shorter one, such as the
    round trip between two runs, is part of the pace), the round trip of a run (its last
    sending to its first frame: counted apart when longer than ``pause_s``) and the bytes
    of a window per kind."""

    pause_s: float = 1.5
    frames: deque[tuple[float, int]] = field(default_factory=lambda: deque(maxlen=64))
    trips: deque[float] = field(default_factory=lambda: deque(maxlen=16))
    sizes: dict[Size, tuple[int, int]] = field(default_factory=dict)  # -> (bytes, windows)
    _last: tuple[int, float] | None = None  # (request id, time) of the last DATA frame

    def data(
        self,
        request_id: int,
        size: Size,
        now: float,
        nbytes: int,
        windows: int,
        asked: float | None,
    ) -> None:
        """A DATA frame of ``windows`` windows in ``nbytes``; ``asked``: when its request
        was last sent if this is the run's first frame (its round trip), else None."""
        last = self._last
        if asked is not None:
            self.trips.append(max(0.0, now - asked))
        if last is not None and now - last[1] <= self.pause_s:
            self.frames.append((now - last[1], nbytes))
        self._last = (request_id, now)
        b, w = self.sizes.get(size, (0, 0))
        if size in self.sizes or len(self.sizes) < MAX_SIZES:
            self.sizes[size] = (b + nbytes, w + windows)

    def pace_bps(self) -> float | None:
        """Bytes/s over the last frames; None until they span half a second."""
        span = sum(dt for dt, _ in self.frames)
        return sum(n for _, n in self.frames) / span if span >= 0.5 else None

    def trip_s(self) -> float | None:
        return sum(self.trips) / len(self.trips) if self.trips else None

    def window_bytes(self, size: Size) -> float | None:
        b, w = self.sizes.get(size, (0, 0))
        return b / w if w else None


@dataclass(frozen=True)
class Ahead:
    """One job as the view counts it: its state and the seconds its rest takes alone."""

    job_id: int
    state: str
    windows_done: int
    windows_total: int
    runs_left: int
    send_s: float | None

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.job_id,
            "state": self.state,
            "windows_done": self.windows_done,
            "windows_total": self.windows_total,
            "runs_left": self.runs_left,
            "send_s": None if self.send_s is None else round(self.send_s, 1),
        }


def send_s(meter: PaceMeter, sizes: list[tuple[Size, int]], runs_to_ask: int) -> float | None:
    """Seconds to send ``sizes`` ([(kind, windows left)]) and ask ``runs_to_ask`` more
    runs at the measured pace and round trip; None until the pace and each kind's bytes
    per window are measured."""
    pace, trip = meter.pace_bps(), meter.trip_s()
    if pace is None or pace <= 0:
        return None
    # a round trip within pause_s is in the pace already
    trip = trip if trip is not None and trip > meter.pause_s else 0.0
    total = 0.0
    for size, windows in sizes:
        per = meter.window_bytes(size)
        if per is None:
            return None
        total += windows * per
    return total / pace + runs_to_ask * trip


def time_left(jobs: list[Ahead], ours: set[int]) -> tuple[float | None, str]:
    """The seconds until ``ours`` are all done, or None and what it waits for: each of
    ours in full and, of every other job, as much as ours (the queue serves its owners
    and their jobs in turn, so another job takes at most a turn for each of ours)."""
    mine = [j for j in jobs if j.job_id in ours]
    if not mine:
        return None, "not in the queue"
    for state, why in (
        ("waiting_link", "waiting for the link"),
        ("waiting_archive", "waiting for the drone's archive"),
        ("unanswered", "waiting for the drone's answer"),
        ("busy", "the drone is busy"),
    ):
        if any(j.state == state for j in jobs):
            return None, why
    if any(j.send_s is None for j in jobs):
        return None, "measuring the pace"
    own = sum(j.send_s or 0.0 for j in mine)
    others = sum(min(j.send_s or 0.0, own) for j in jobs if j.job_id not in ours)
    return own + others, ""
