"""Backfill on the base station (docs/subbroker.md, "Backfill"): which windows
each subscriber got, the gaps an outage left, and requests to the PubBroker
(docs/protocol.md, "Backfill") that fill them from the drone's archive.

The record of what arrived is kept per sent stream as merged time intervals
(a few per outage, not one per window), so it stays small over a whole
mission. A subscriber's window is delivered if its source stream covers it;
backfilled windows are recorded per subscriber and stream, so no window is
delivered twice. One link request runs at a time; its resume point is the
first window not yet received, so after a link drop or a PubBroker restart
it is asked again from there (nothing sent twice, nothing skipped).

A datagram link (udp, serial) loses frames, and control datagrams are not
resent: a lost BACKFILL_DATA shows as a frame that starts past the resume
point, a lost END as a run whose windows all arrived, a lost request or END
as silence. Each is answered by asking again from the resume point (the
PubBroker replaces a request of the same id), so a lossy radio slows a
backfill down but never leaves it running for ever.
"""

from __future__ import annotations

import bisect
import itertools
import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from modd_plan.streams import StreamKey
from modd_plan.windows import split_window, window_of

from modd.link import backfill as bf
from modd.link.codec import RawFrame
from modd.link.frames import Aggregation, ProtocolError, ValueType
from modd.link.receiver import Window

from .fanout import period_us
from .payload import DeliveredValue

if TYPE_CHECKING:
    from .delivery import Sink
    from .running import Running

log = logging.getLogger("modd.subbroker.backfill")

#: A resume answered by frames already in flight is not asked again within this time.
RESUME_GRACE_S = 2.0
#: Silence of the running request after which it is asked again (at least; slower paces
#: wait for four of the largest data frames at their rate).
STALL_S = 10.0
LARGEST_FRAME_B = 250


class Intervals:
    """Disjoint, merged ``[start, end)`` intervals of nanoseconds.

    >>> iv = Intervals(); iv.add(0, 10); iv.add(10, 20); iv.add(30, 40)
    >>> iv.spans, iv.covers(5, 20), iv.covers(15, 35)
    ([(0, 20), (30, 40)], True, False)
    """

    def __init__(self) -> None:
        self.spans: list[tuple[int, int]] = []

    def add(self, start: int, end: int) -> None:
        i = bisect.bisect_left(self.spans, (start, start))
        if i > 0 and self.spans[i - 1][1] >= start:
            i -= 1
        j = i
        while j < len(self.spans) and self.spans[j][0] <= end:
            start, end = min(start, self.spans[j][0]), max(end, self.spans[j][1])
            j += 1
        self.spans[i:j] = [(start, end)]

    def covers(self, start: int, end: int) -> bool:
        i = bisect.bisect_right(self.spans, (start, 1 << 63)) - 1
        return i >= 0 and self.spans[i][0] <= start and self.spans[i][1] >= end


@dataclass
class Run:
    """Consecutive windows of one subscriber's stream, one link request."""

    subscriber: str
    stream: StreamKey
    source: StreamKey  # the sent stream the live path derives it from (the record's key)
    value_type: str
    unit: str
    config_id: int
    from_ns: int
    windows: int


@dataclass
class Job:
    """One backfill as the queryable and the CLI see it."""

    job_id: int
    subscriber: str
    runs: deque[Run]
    total: int
    rate_bps: int
    started: float = field(default_factory=time.monotonic)
    status: str = "RUNNING"  # DONE, CANCELLED, FAILED
    reason: str = ""
    done_windows: int = 0
    delivered: int = 0
    duplicates: int = 0
    bytes: int = 0
    request: bf.BackfillRequest | None = None
    next: int = 0  # resume point of the running request
    finished: threading.Event = field(default_factory=threading.Event)
    heard: float = 0.0  # monotonic time of the running request's last frame (or its sending)
    asked_at: float = 0.0  # monotonic time the running request was last sent
    asked_next: int = -1  # the resume point it was sent with
    resumes: int = 0  # requests sent again after a loss or a silence

    def stall_s(self) -> float:
        return max(STALL_S, 4 * LARGEST_FRAME_B / max(self.rate_bps, 1))

    def progress(self) -> dict[str, Any]:
        secs = time.monotonic() - self.started
        left = None
        if self.done_windows and self.status == "RUNNING":
            left = secs / self.done_windows * (self.total - self.done_windows)
        return {"status": self.status, "id": self.job_id, "subscriber": self.subscriber,
                "windows": self.delivered, "windows_done": self.done_windows,
                "windows_total": self.total, "duplicates": self.duplicates, "bytes": self.bytes,
                "rate_bps": self.rate_bps, "seconds": round(secs, 3),
                "bytes_per_s": round(self.bytes / secs, 1) if secs > 0 else 0.0,
                "seconds_left": None if left is None else round(left, 1),
                "reason": self.reason}


class BackfillManager:
    """Delivered-window record, gap detection and the link requests of one SubBroker."""

    def __init__(self, send: Callable[[bytes], None], sinks: Callable[[], Sequence[Sink]]) -> None:
        self._send = send
        self._sinks = sinks
        self._lock = threading.RLock()
        self._received: dict[StreamKey, Intervals] = {}
        self._filled: dict[tuple[str, StreamKey], Intervals] = {}
        self._jobs: dict[int, Job] = {}
        self._queue: deque[Job] = deque()
        self._active: Job | None = None
        self._ids = itertools.count(1)
        self._request_ids = itertools.count(1)

    # -- the record ---------------------------------------------------------------

    def on_windows(self, running: Running, windows: Sequence[Window]) -> None:
        """Live windows that arrived (link thread)."""
        sent = running.fanout.sent
        with self._lock:
            for w in windows:
                iv = self._received.get(sent[w.stream])
                if iv is None:
                    iv = self._received[sent[w.stream]] = Intervals()
                iv.add(w.start_ns, w.end_ns)

    def received_until(self) -> int | None:
        """The end of the latest live window received (the live path covers what follows)."""
        with self._lock:
            ends = [iv.spans[-1][1] for iv in self._received.values() if iv.spans]
        return max(ends) if ends else None

    def delivered(self, subscriber: str, stream: StreamKey, source: StreamKey,
                  start: int, end: int) -> bool:
        with self._lock:
            live = self._received.get(source)
            if live is not None and live.covers(start, end):
                return True
            filled = self._filled.get((subscriber, stream))
            return filled is not None and filled.covers(start, end)

    def gaps(self, running: Running, subscriber: str, from_ns: int, to_ns: int) -> list[Run]:
        """The runs of windows of ``subscriber``'s streams in ``[from_ns, to_ns)`` that
        were not delivered (live or backfilled), on the live window grid."""
        runs: list[Run] = []
        epoch = running.epoch_ns
        for ps in running.plan.streams:
            if subscriber not in ps.subscribers:
                continue
            stream = ps.stream
            source = ps.sources[0].stream if ps.sources else stream
            q = period_us(stream) * 1000
            first = max(0, -(-(from_ns - epoch) // q))
            last = (to_ns - epoch) // q  # windows [epoch + j q, epoch + (j+1) q) for j < last
            unit, vtype = running.topic_info[stream.topic]
            start: int | None = None
            for j in range(first, last):
                s = epoch + j * q
                if self.delivered(subscriber, stream, source, s, s + q):
                    if start is not None:
                        runs.append(Run(subscriber, stream, source, vtype, unit,
                                        running.config.config_id, start, (s - start) // q))
                        start = None
                elif start is None:
                    start = s
            if start is not None:
                end = epoch + last * q
                runs.append(Run(subscriber, stream, source, vtype, unit,
                                running.config.config_id, start, (end - start) // q))
        return runs

    # -- jobs ---------------------------------------------------------------------

    def start(self, subscriber: str, runs: list[Run], rate_bps: int) -> Job:
        job = Job(next(self._ids), subscriber, deque(runs), sum(r.windows for r in runs), rate_bps)
        with self._lock:
            self._jobs[job.job_id] = job
            for old in list(self._jobs)[:-64]:
                if self._jobs[old].finished.is_set():
                    del self._jobs[old]
            self._queue.append(job)
            if self._active is None:
                self._next_request()
        if job.total == 0:
            self._finish(job, "DONE")
        return job

    def job(self, job_id: int) -> Job | None:
        return self._jobs.get(job_id)

    def cancel(self, job_id: int) -> Job | None:
        with self._lock:
            job = self._jobs.get(job_id)
            if job is None or job.finished.is_set():
                return job
            if job is self._active and job.request is not None:
                self._try_send(bf.encode(bf.BackfillCancel(job.request.request_id)))
            self._finish(job, "CANCELLED")
            return job

    def cap(self, job_id: int, rate_bps: int) -> Job | None:
        """Lower (or set) the pace of a job; a running request is asked again at the new
        pace from its resume point (the PubBroker replaces a request with the same id)."""
        with self._lock:
            job = self._jobs.get(job_id)
            if job is None or job.finished.is_set():
                return job
            job.rate_bps = rate_bps
            if job is self._active and job.request is not None:
                self.on_up()
            return job

    def on_up(self) -> None:
        """The link is up again: ask for the running request from its resume point."""
        with self._lock:
            job = self._active
            if job is not None and job.request is not None:
                self._resume(job, "the link is up again")

    def _resume(self, job: Job, why: str) -> None:
        """Ask for the running request again from its resume point (same id: the
        PubBroker replaces the request it has, if any)."""
        q = job.request
        assert q is not None
        job.request = bf.BackfillRequest(q.request_id, q.topic, q.type, q.aggregation,
                                         q.period_us, q.from_ns, q.windows, job.next,
                                         job.rate_bps)
        job.resumes += 1
        log.info("backfill %d: %s, resuming at window %d of %d", job.job_id, why, job.next,
                 q.windows)
        self._ask(job)

    def _resume_unless_asked(self, job: Job, why: str) -> None:
        """Resume, unless the same resume point was asked for a moment ago (frames
        sent before that request reached the PubBroker still arrive)."""
        if job.asked_next == job.next and time.monotonic() - job.asked_at < RESUME_GRACE_S:
            return
        self._resume(job, why)

    def _ask(self, job: Job) -> None:
        """Send the running request, and watch it: silence past its stall time asks again."""
        assert job.request is not None
        now = time.monotonic()
        job.asked_at = job.heard = now
        job.asked_next = job.next
        self._try_send(bf.encode(job.request))
        self._watch(job, job.request.request_id, job.stall_s())

    def _watch(self, job: Job, request_id: int, after_s: float) -> None:
        timer = threading.Timer(after_s, self._check_stall, (job, request_id))
        timer.daemon = True
        timer.start()

    def _check_stall(self, job: Job, request_id: int) -> None:
        with self._lock:
            if (self._active is not job or job.request is None
                    or job.request.request_id != request_id or job.finished.is_set()):
                return  # that request ended; its successor has its own watch
            quiet = time.monotonic() - job.heard
            if quiet >= job.stall_s() - 0.01:
                self._resume(job, f"nothing heard for {quiet:.1f} s")
            else:
                self._watch(job, request_id, job.stall_s() - quiet)

    def _try_send(self, frame: bytes) -> None:
        try:
            self._send(frame)
        except (ConnectionError, OSError) as exc:  # sent again from on_up
            log.info("backfill request waits for the link: %s", exc)

    def _finish(self, job: Job, status: str, reason: str = "") -> None:
        with self._lock:
            if job.finished.is_set():
                return
            job.status, job.reason = status, reason
            job.finished.set()
            if job in self._queue:
                self._queue.remove(job)
            if self._active is job:
                self._active = None
                self._next_request()
        log.info("backfill %d for %s: %s (%d windows, %d duplicates, %d bytes)%s", job.job_id,
                 job.subscriber, status, job.delivered, job.duplicates, job.bytes,
                 f": {reason}" if reason else "")

    def _next_request(self) -> None:
        while self._queue and self._active is None:
            job = self._queue[0]
            if not job.runs:
                self._queue.popleft()
                self._finish(job, "DONE")
                continue
            run = job.runs[0]
            self._active = job
            job.next = 0
            job.request = bf.BackfillRequest(
                next(self._request_ids), run.stream.topic, ValueType.parse(run.value_type),
                Aggregation[run.stream.aggregation], period_us(run.stream), run.from_ns,
                run.windows, 0, job.rate_bps)
            self._ask(job)

    # -- frames from the PubBroker (link thread) --------------------------------------

    def on_frame(self, frame: RawFrame) -> None:
        with self._lock:
            job = self._active
            req = job.request if job is not None else None
            try:
                if frame.type == bf.BackfillType.DATA:
                    if job is None or req is None or bf.data_request_id(frame) != req.request_id:
                        return  # a frame of a request cancelled or replaced
                    self._on_data(job, req, bf.decode_data(frame, req.kind()), len(frame.body) + 2)
                    return
                msg = bf.decode(frame)
            except ProtocolError as exc:
                log.warning("backfill frame refused: %s", exc)
                return
            if job is None or req is None or getattr(msg, "request_id", None) != req.request_id:
                return
            job.heard = time.monotonic()
            if isinstance(msg, bf.BackfillEnd):
                self._on_end(job, req, msg)

    def _on_data(self, job: Job, req: bf.BackfillRequest, d: bf.BackfillData, size: int) -> None:
        job.heard = time.monotonic()
        if d.first > job.next:  # a frame before it was lost on the way
            self._resume_unless_asked(job, f"windows {job.next}..{d.first - 1} lost")
            return
        if d.first != job.next:  # in flight before a resume: asked for again
            return
        run = job.runs[0]
        job.bytes += size
        now = time.time_ns()
        q = req.period_us * 1000
        source = run.source
        for i, value in enumerate(d.values):
            start = req.window_start_ns(d.first + i)
            job.next += 1
            job.done_windows += 1
            if self.delivered(run.subscriber, run.stream, source, start, start + q):
                job.duplicates += 1
                continue
            window = window_of(value, run.stream.aggregation, run.value_type)
            val, count = split_window(run.stream.aggregation, window)
            out = DeliveredValue(run.subscriber, run.stream.topic, run.stream.aggregation,
                                 run.stream.key.rsplit("/", 1)[1], run.unit, run.config_id,
                                 (start + q) // q, start, start + q, val, count, now, True)
            payload = out.to_json()
            for sink in self._sinks():
                sink.put(run.subscriber, payload)
            filled = self._filled.setdefault((run.subscriber, run.stream), Intervals())
            filled.add(start, start + q)
            job.delivered += 1
        if job.next >= req.windows:  # all of the run: its END may be lost, not waited for
            self._run_done(job)

    def _run_done(self, job: Job) -> None:
        job.runs.popleft()
        job.request = None
        self._active = None
        if job.runs:
            self._next_request()  # the job stays first in the queue: its next run
        else:
            self._finish(job, "DONE")

    def _on_end(self, job: Job, req: bf.BackfillRequest, end: bf.BackfillEnd) -> None:
        if end.status == bf.EndStatus.DONE and job.next >= req.windows:
            self._run_done(job)
            return
        if end.status == bf.EndStatus.DONE:
            # the PubBroker sent the whole run but windows from job.next did not arrive
            # (or this END left before a resume reached it: then the resumed one follows)
            self._resume_unless_asked(job, f"the run ended with windows from {job.next} lost")
            return
        self._finish(job, "CANCELLED" if end.status == bf.EndStatus.CANCELLED else "FAILED",
                     f"{end.status.name}: {end.message}")
