"""The backfill queue of one link, without I/O (docs/subbroker.md, "Backfill").

Any number of jobs from any number of users; each job is a list of runs (the
consecutive missed windows of one stream), each run one link request. The
queue serves the runs fairly (one run per turn: the owner served longest ago,
then that owner's job served longest ago) and keeps ONE request in flight on the link.
A request is sent again until the PubBroker acknowledges it (any frame of its
id), at most once per ``min_resend_s`` whatever the link does (a flapping link
included); a BUSY answer means wait and ask again, never fail; silence of an
acknowledged request past its stall time asks again from the resume point
(the first window not received: nothing is delivered twice, nothing skipped).

Fed the time (monotonic seconds) and what happened; answers with the frames
to send. Every job that has not ended has a reason that says what it waits
for ("queued behind 3 jobs", "waiting for the link", "paced at 600 B/s").

>>> q = BackfillQueue()
>>> q.progress(q.submit(Job(1, "sub_1", "", deque(), 0, 600), 0.0)[0], 0.0)["status"]
'DONE'
"""

from __future__ import annotations

import dataclasses
from collections import deque
from dataclasses import dataclass, field
from typing import Any

from modd_contracts import labels
from modd_contracts.events import parse_label
from modd_plan.streams import StreamKey

from modd.link import backfill as bf
from modd.link.frames import Aggregation, ValueType

from .backfill_view import MAX_VIEW, Ahead, PaceMeter, Size, send_s, time_left
from .fanout import period_us


@dataclass(frozen=True)
class Timing:
    """The queue's clocks (seconds); the documented bound of a silent job is ``stall_s``."""

    ack_s: float = 2.0  # an unacknowledged request is sent again after this (doubling)
    ack_max_s: float = 16.0
    busy_s: float = 1.0  # a BUSY request is asked again after this (doubling)
    busy_max_s: float = 10.0
    min_resend_s: float = 1.0  # the same request is never sent twice within this
    resume_grace_s: float = 2.0  # a resume answered by frames in flight is not asked again
    stall_s: float = 10.0  # silence of an acknowledged request after which it is asked again
    largest_frame_b: int = 250  # slow paces wait for four such frames before a resume

    def stall(self, rate_bps: int) -> float:
        """0: paced by the PubBroker (its own budget, not a slow one): ``stall_s``
        (was 4 frames at 1 B/s: a job whose last frames were lost waited 1,000 s)."""
        if rate_bps <= 0:
            return self.stall_s
        return max(self.stall_s, 4 * self.largest_frame_b / rate_bps)


@dataclass
class Run:
    """Consecutive windows of one subscriber's stream, one link request."""

    subscriber: str
    stream: StreamKey
    source: StreamKey  # the sent stream the live path derives it from (the record's key)
    value_type: str
    unit: str
    config_id: int  # the config that was running when these windows were due
    from_ns: int
    windows: int
    epoch_ns: int | None = None  # the config's epoch (the windows' grid); None: unknown


@dataclass
class Job:
    """One backfill as the queryable, the CLI and the workbench see it."""

    job_id: int
    subscriber: str
    owner: str  # whom the queue is fair to (the asking user; "" for the CLI)
    runs: deque[Run]
    total: int
    rate_bps: int
    started: float = 0.0
    ended: float | None = None
    status: str = "RUNNING"  # DONE, CANCELLED, FAILED
    reason: str = ""
    done_windows: int = 0
    delivered: int = 0
    duplicates: int = 0
    bytes: int = 0
    resumes: int = 0  # requests sent again after a loss, a silence or a BUSY
    requests: int = 0  # request frames sent for this job


@dataclass
class InFlight:
    """The request on the link: its job's first run, from the resume point ``next``."""

    job: Job
    request: bf.BackfillRequest
    next: int = 0
    acked: bool = False
    sent_at: float | None = None  # None: not sent yet (or the link went down since)
    last_sent: float | None = None  # the last sending, whatever happened since
    asked_next: int = -1  # the resume point it was last sent with
    sends: int = 0  # sendings not acknowledged yet
    heard: float = 0.0
    retry_at: float | None = None
    busy: int = 0  # BUSY answers in a row
    why: str = ""  # why it is asked again (said once it is sent)
    got_data: bool = False  # a DATA frame of this run arrived (its round trip is measured)


@dataclass
class Filled:
    """Windows of a BACKFILL_DATA frame the manager delivers (in window order)."""

    job: Job
    run: Run
    request: bf.BackfillRequest
    data: bf.BackfillData


@dataclass
class BackfillQueue:
    timing: Timing = field(default_factory=Timing)
    next_request_id: int = 1
    up: bool = True
    jobs: dict[int, Job] = field(default_factory=dict)  # jobs that have not ended
    flight: InFlight | None = None
    _turn: int = 0  # counts the runs put in flight
    _served: dict[str, int] = field(default_factory=dict)  # owner / job id -> its last turn
    notes: list[str] = field(default_factory=list)  # what to log (the manager drains it)
    meter: PaceMeter = field(default_factory=PaceMeter)  # the pace the view's time left uses
    _view: tuple[float, dict[str, Any], list[Ahead]] | None = None  # (when, json, jobs)

    # -- jobs -------------------------------------------------------------------------

    def submit(self, job: Job, now: float) -> tuple[Job, list[bytes]]:
        job.started = now
        if not job.runs:
            self._end(job, "DONE", "", now)
            return job, []
        self.jobs[job.job_id] = job
        return job, self._serve(now)

    def cancel(self, job: Job, now: float) -> list[bytes]:
        out: list[bytes] = []
        f = self.flight
        if f is not None and f.job is job:
            self.flight = None
            if f.sent_at is not None:
                out.append(bf.encode(bf.BackfillCancel(f.request.request_id)))
        self._end(job, "CANCELLED", "cancelled", now)
        return out + self._serve(now)

    def cap(self, job: Job, rate_bps: int, now: float) -> list[bytes]:
        """A new pace: the running request is asked again at it from its resume point."""
        job.rate_bps = rate_bps
        f = self.flight
        if f is None or f.job is not job or f.sent_at is None:
            return []
        f.sent_at, f.sends = None, 0
        return self._again(f, now, f"a new pace of {rate_bps} B/s")

    # -- the link ---------------------------------------------------------------------

    def link_up(self, now: float) -> list[bytes]:
        """The link is (up) again: the request in flight is asked again from its resume
        point (the PubBroker forgot it), a waiting one is sent."""
        self.up = True
        f = self.flight
        if f is not None and f.last_sent is not None:
            f.sent_at, f.acked, f.sends, f.retry_at = None, False, 0, None
            f.job.resumes += 1
            f.why = "the link is up again"
        return self._serve(now)

    def link_down(self) -> None:
        """Sending failed or the link went: nothing goes until it is up again."""
        self.up = False
        if self.flight is not None:
            self.flight.sent_at = None

    # -- the PubBroker's answers ------------------------------------------------------

    def heard(self, request_id: int, now: float) -> InFlight | None:
        """The request in flight when a frame answers it (it is acknowledged), else None."""
        f = self.flight
        if f is None or f.request.request_id != request_id:
            return None
        f.acked, f.heard, f.sends = True, now, 0
        if f.sent_at is not None:
            f.retry_at = None  # no more waiting for an acknowledgement (a deferred send stays)
        return f

    def on_data(
        self, d: bf.BackfillData, size: int, now: float
    ) -> tuple[Filled | None, list[bytes]]:
        f = self.heard(d.request_id, now)
        if f is None:
            return None, []  # a frame of a request cancelled, replaced or ended
        f.busy = 0
        if d.first > f.next:  # a frame before it was lost on the way
            return None, self._resume_unless_asked(f, now)
        if d.first != f.next:  # in flight before a resume: asked for again
            return None, []
        job, run = f.job, f.job.runs[0]
        asked = None if f.got_data else f.last_sent
        self.meter.data(d.request_id, _size(run), now, size, len(d.values), asked)
        f.got_data = True
        job.bytes += size
        f.next += len(d.values)
        job.done_windows += len(d.values)
        filled = Filled(job, run, f.request, d)
        if f.next >= f.request.windows:  # all of the run: its END may be lost, not waited for
            return filled, self._run_done(f, now)
        return filled, []

    def on_end(self, end: bf.BackfillEnd, now: float) -> list[bytes]:
        f = self.heard(end.request_id, now)
        if f is None:
            return []
        if end.status == bf.EndStatus.DONE:
            if f.next >= f.request.windows:
                return self._run_done(f, now)
            # windows from f.next did not arrive (or this END left before a resume did)
            return self._resume_unless_asked(f, now)
        if end.status in (bf.EndStatus.BUSY, bf.EndStatus.CANCELLED):
            # BUSY: wait and ask again; CANCELLED without our cancel: the same
            f.busy += 1
            f.acked, f.sent_at = False, None
            f.retry_at = now + min(self.timing.busy_s * 2 ** (f.busy - 1), self.timing.busy_max_s)
            f.why = f"the PubBroker said {end.status.name}"
            return []
        self.flight = None
        self._end(f.job, "FAILED", f"{end.status.name}: {end.message}", now)
        return self._serve(now)

    # -- time -------------------------------------------------------------------------

    def wake_at(self) -> float | None:
        """When :meth:`tick` has something to do (None: only an event will)."""
        f = self.flight
        if f is None or not self.up:
            return None
        if f.retry_at is not None:
            return f.retry_at
        if f.acked:
            return f.heard + self.timing.stall(f.job.rate_bps)
        return None

    def tick(self, now: float) -> list[bytes]:
        f = self.flight
        if f is None or not self.up:
            return []
        if f.retry_at is not None and now >= f.retry_at:
            f.retry_at = None
            if f.sent_at is not None:  # not acknowledged in time: sent again
                waited, f.sent_at = now - f.sent_at, None
                return self._again(f, now, f"no answer in {waited:.1f} s")
            return self._send(f, now)
        if f.acked and now - f.heard >= self.timing.stall(f.job.rate_bps) - 1e-6:
            quiet = now - f.heard
            f.acked, f.sent_at, f.sends = False, None, 0
            return self._again(f, now, f"nothing heard for {quiet:.1f} s")
        return []

    # -- progress ---------------------------------------------------------------------

    def reason(self, job: Job, now: float) -> str:
        if job.status != "RUNNING":
            return job.reason
        f = self.flight
        if f is not None and f.job is job:
            if not self.up:
                return "waiting for the link"
            if f.busy and f.retry_at is not None:
                return f"the PubBroker is busy: asking again in {max(0, f.retry_at - now):.0f} s"
            if not f.acked:
                return f"asked the PubBroker {max(f.sends, 1)} time(s), waiting for its answer"
            return f"paced at {job.rate_bps} B/s" if job.rate_bps else "paced by the PubBroker"
        ahead = len(self.order(job)) - 1 + (self.flight is not None)
        return f"queued behind {ahead} job{'s' if ahead != 1 else ''}" + (
            "" if self.up else ", waiting for the link"
        )

    def progress(self, job: Job, now: float) -> dict[str, Any]:
        """The job's progress document; a running job's carries the queue's view
        (``queue``) and its time left from it (None where it cannot be computed)."""
        secs = (job.ended if job.ended is not None else now) - job.started
        left, view = None, None
        if job.status == "RUNNING":
            view, ahead = self.view(now)
            left = time_left(ahead, {job.job_id})[0]
        out: dict[str, Any] = {
            "status": job.status,
            "id": job.job_id,
            "subscriber": job.subscriber,
            "windows": job.delivered,
            "windows_done": job.done_windows,
            "windows_total": job.total,
            "duplicates": job.duplicates,
            "bytes": job.bytes,
            "rate_bps": job.rate_bps,
            "seconds": round(secs, 3),
            "bytes_per_s": round(job.bytes / secs, 1) if secs > 0 else 0.0,
            "seconds_left": None if left is None else round(left, 1),
            "requests": job.requests,
            "resumes": job.resumes,
            "reason": self.reason(job, now),
        }
        if view is not None:
            out["queue"] = view
        return out

    # -- the queue's view -------------------------------------------------------------

    def view(self, now: float) -> tuple[dict[str, Any], list[Ahead]]:
        """The jobs that have not ended in the order they are served (the one on the link
        first; at most MAX_VIEW), each with its state and the seconds its rest takes at
        the measured pace; computed at most every 0.25 s (every job's poll asks for it)."""
        if self._view is not None and 0 <= now - self._view[0] < 0.25:
            return self._view[1], self._view[2]
        busy = [self.flight.job] if self.flight is not None else []
        order = busy + self.order()
        ahead = [self._ahead(j, now) for j in order[:MAX_VIEW]]
        pace, trip = self.meter.pace_bps(), self.meter.trip_s()
        doc = {
            "jobs": [a.to_json() for a in ahead],
            "more": max(0, len(order) - MAX_VIEW),
            "pace_bps": None if pace is None else round(pace, 1),
            "trip_s": None if trip is None else round(trip, 2),
        }
        self._view = (now, doc, ahead)
        return doc, ahead

    def state(self, job: Job, now: float) -> str:
        """What ``job`` waits for, in one word (backfill_view.STATES)."""
        f = self.flight
        if f is None or f.job is not job:
            return "queued"
        if not self.up:
            return "waiting_link"
        if f.busy and f.retry_at is not None:
            return "busy"
        if not f.acked:
            return "asking" if f.sends <= 1 else "unanswered"
        quiet = max(self.meter.pause_s, 128 / job.rate_bps if job.rate_bps else 0.0)
        return "waiting_archive" if now - f.heard > quiet else "sending"

    def _ahead(self, job: Job, now: float) -> Ahead:
        f = self.flight
        on = f is not None and f.job is job
        sizes: dict[Size, int] = {}
        for i, run in enumerate(job.runs):
            left = run.windows - (f.next if on and i == 0 and f is not None else 0)
            sizes[_size(run)] = sizes.get(_size(run), 0) + left
        asked = 1 if on and f is not None and f.got_data else 0
        seconds = send_s(self.meter, list(sizes.items()), len(job.runs) - asked)
        return Ahead(
            job.job_id,
            self.state(job, now),
            job.done_windows,
            job.total,
            len(job.runs),
            seconds,
        )

    def order(self, until: Job | None = None) -> list[Job]:
        """The waiting jobs in the order the queue serves their next runs (up to ``until``)."""
        served = dict(self._served)
        busy = self.flight.job if self.flight is not None else None
        waiting = [j for j in self.jobs.values() if j is not busy]
        out: list[Job] = []
        for turn in range(len(waiting)):
            job = _least_served(waiting, served)
            waiting.remove(job)
            out.append(job)
            if job is until:
                break
            served[_o(job)] = served[_j(job)] = self._turn + turn
        return out

    # -- inside -----------------------------------------------------------------------

    def _serve(self, now: float) -> list[bytes]:
        """The next run in flight when none is, or the waiting one sent."""
        if self.flight is None:
            job = self._pick()
            if job is None:
                return []
            req = _request(self.next_request_id, job.runs[0], job.rate_bps)
            self.next_request_id += 1
            self.flight = InFlight(job, req)
        if self.flight.sent_at is None and self.flight.retry_at is None:
            return self._send(self.flight, now)
        return []

    def _pick(self) -> Job | None:
        if not self.jobs:
            return None
        job = _least_served(list(self.jobs.values()), self._served)
        self._served[_o(job)] = self._served[_j(job)] = self._turn
        self._turn += 1
        return job

    def _send(self, f: InFlight, now: float) -> list[bytes]:
        if not self.up:
            return []
        if f.last_sent is not None and now - f.last_sent < self.timing.min_resend_s:
            f.retry_at = f.last_sent + self.timing.min_resend_s  # never twice within it
            return []
        if f.why:
            self.notes.append(
                f"backfill {f.job.job_id}: {f.why}, resuming at window {f.next} "
                f"of {f.request.windows}"
            )
            f.why = ""
        f.request = dataclasses.replace(f.request, resume=f.next, rate_bps=f.job.rate_bps)
        f.sends += 1
        f.sent_at = f.heard = f.last_sent = now
        f.asked_next = f.next
        f.job.requests += 1
        f.retry_at = (
            None
            if f.acked
            else now + min(self.timing.ack_s * 2 ** (f.sends - 1), self.timing.ack_max_s)
        )
        return [bf.encode(f.request)]

    def _resume_unless_asked(self, f: InFlight, now: float) -> list[bytes]:
        """Ask again from the resume point, unless it was asked a moment ago (frames sent
        before that request reached the PubBroker still arrive)."""
        if (
            f.asked_next == f.next
            and f.sent_at is not None
            and now - f.sent_at < self.timing.resume_grace_s
        ):
            # looked at again once the grace is over, should nothing more come (an END
            # whose DATA was lost on a datagram link left the job silent until the stall)
            f.retry_at = f.sent_at + self.timing.resume_grace_s
            return []
        f.acked, f.sent_at = False, None
        return self._again(f, now, f"windows from {f.next} lost")

    def _again(self, f: InFlight, now: float, why: str) -> list[bytes]:
        """Send the request in flight again from its resume point, saying why."""
        f.job.resumes += 1
        f.why = why
        return self._send(f, now)

    def _run_done(self, f: InFlight, now: float) -> list[bytes]:
        job = f.job
        job.runs.popleft()
        self.flight = None
        if not job.runs:
            self._end(job, "DONE", "", now)
        return self._serve(now)

    def _end(self, job: Job, status: str, reason: str, now: float) -> None:
        job.status, job.reason, job.ended = status, reason, now
        self.jobs.pop(job.job_id, None)
        self._served.pop(_j(job), None)
        if all(j.owner != job.owner for j in self.jobs.values()):
            self._served.pop(_o(job), None)


def _request(request_id: int, run: Run, rate_bps: int) -> bf.BackfillRequest:
    """The link request of a run, from its first window. An event stream's carries its
    parameters and its config's epoch, where the PubBroker's detector state starts."""
    name, p = labels.parse(run.stream.aggregation)
    event, state_from = None, None
    if labels.is_event(run.stream.aggregation):
        if run.epoch_ns is None:
            raise ValueError(f"{run.stream.aggregation}: its config's epoch is not known")
        event, state_from = parse_label(run.stream.aggregation), run.epoch_ns
    return bf.BackfillRequest(
        request_id,
        run.stream.topic,
        ValueType.parse(run.value_type),
        Aggregation[name],
        period_us(run.stream),
        run.from_ns,
        run.windows,
        0,
        rate_bps,
        p,
        event,
        state_from,
    )


def _size(run: Run) -> Size:
    return (run.stream.aggregation, run.value_type)


def _least_served(jobs: list[Job], served: dict[str, int]) -> Job:
    """Fair: the owner served longest ago (or never), then that owner's job served
    longest ago (or never), the oldest first."""
    return min(jobs, key=lambda j: (served.get(_o(j), -1), served.get(_j(j), -1), j.job_id))


def _o(job: Job) -> str:
    return "owner:" + job.owner


def _j(job: Job) -> str:
    return f"job:{job.job_id}"
