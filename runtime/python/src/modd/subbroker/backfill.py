"""Backfill on the base station (docs/subbroker.md, "Backfill"): the record of
which windows each subscriber got and should have got (window_record.py), the
queue of jobs and their link requests (backfill_queue.py, without I/O), and
here what joins them to the link, the clock and the subscribers: a frame sent,
a frame received, a timer, a window delivered.

One request is on the link at a time; its resume point is the first window not
yet received, so after a link drop or a PubBroker restart it is asked again
from there (nothing sent twice, nothing skipped). A datagram link (udp, serial)
loses frames and does not resend control frames: a lost BACKFILL_DATA shows as a
frame that starts past the resume point, a lost END as a run whose windows all
arrived, a lost request or END as silence; each is answered by asking again.
"""

from __future__ import annotations

import itertools
import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

from modd_contracts.labels import is_event
from modd_plan.streams import StreamKey
from modd_plan.windows import EventsWindow, split_window, window_of

from modd.link import backfill as bf
from modd.link.codec import RawFrame
from modd.link.frames import ProtocolError
from modd.link.receiver import Window

from .backfill_queue import BackfillQueue, Filled, Job, Run, Timing
from .fleet_record import merge
from .payload import DeliveredValue, window_index
from .record_file import read_record
from .window_journal import WindowJournal, replay
from .window_record import Due, Epoch, WindowRecord

if TYPE_CHECKING:
    from .delivery import Sink
    from .kept import StateDir
    from .running import Running

log = logging.getLogger("modd.subbroker.backfill")

#: The window record is written to the state directory at most this often (and at stop).
SAVE_S = 1.0
#: Ended jobs kept for their progress document.
KEEP_ENDED = 64

__all__ = ["BackfillManager", "Job", "Run", "Timing"]


def epoch_of(running: Running) -> Epoch:
    """What each subscriber is due while ``running`` runs."""
    due = []
    for ps in running.plan.streams:
        source = ps.sources[0].stream if ps.sources else ps.stream
        unit, vtype = running.topic_info[ps.stream.topic]
        due += [Due(sub, ps.stream, source, unit, vtype) for sub in ps.subscribers]
    return Epoch(mission_of(running), running.config.config_id, running.epoch_ns, due)


def mission_of(running: Running) -> str:
    return str(running.model.get("name") or "")


class BackfillManager:
    """The window record, the queue and the link requests of one SubBroker."""

    def __init__(
        self,
        send: Callable[[bytes], None],
        sinks: Callable[[], Sequence[Sink]],
        state: StateDir | None = None,
        timing: Timing | None = None,
        drone: str | None = None,
    ) -> None:
        self.drone = drone  # the windows carry their identity (docs/fleet.md) when set
        self._send = send
        self._sinks = sinks
        self._state = state
        self._lock = threading.RLock()
        self._saving = threading.Lock()  # taken before _lock, never under it
        self._wake = threading.Condition(self._lock)
        # request ids from 1 (one byte in every BACKFILL_DATA): the PubBroker forgets its
        # requests at each authentication, so a restarted SubBroker's ids meet no old one
        self._queue = BackfillQueue(timing or Timing())
        self.record = self._load()
        self._journal = self._open_journal()
        self._dirty = False
        self._saved_at = 0.0
        self._jobs: dict[int, Job] = {}
        self._ids = itertools.count(1)
        self._closed = False
        self._thread: threading.Thread | None = None

    # -- the record -----------------------------------------------------------------

    def _load(self) -> WindowRecord:
        """The record kept, with the windows journalled since it was written."""
        record = self._read_record()
        path = self._state.journal_path() if self._state is not None else None
        if path is not None and (lines := replay(path, record)):
            log.info("window journal: %d deliveries since the record was saved", lines)
        return record

    def _open_journal(self) -> WindowJournal | None:
        path = self._state.journal_path() if self._state is not None else None
        if path is None:
            return None
        try:
            return WindowJournal(path)
        except OSError as exc:  # as a record that cannot be written: said, and the run goes on
            log.error("cannot keep the window journal %s: %s", path, exc)
            return None

    def _read_record(self) -> WindowRecord:
        doc = self._state.load_windows() if self._state is not None else None
        if doc is None:
            return WindowRecord()
        try:
            return read_record(doc)
        except (ValueError, ArithmeticError) as exc:
            if self._state is not None:
                self._state.set_aside(
                    "windows.json",
                    f"not a window record: {exc}; the gaps of earlier configs are forgotten "
                    "(the running config's are recorded afresh)",
                )
            return WindowRecord()

    def save(self) -> None:
        """Write the record to the state directory (if any) when it changed. On return
        the record as it was at the call is on disk, also when the clock thread's save
        took it: a save under way is waited for (one writer at a time)."""
        with self._saving:
            self._save()

    def _save(self) -> None:
        with self._lock:
            if self._state is None or not self._dirty:
                return
            doc, self._dirty, self._saved_at = self.record.to_json(), False, time.monotonic()
            journal = self._journal
            try:
                if journal is not None:
                    journal.rotate()  # what follows the snapshot goes to a new journal
            except OSError as exc:
                log.error("cannot set the window journal aside: %s", exc)
                journal = None
        try:
            self._state.save_windows(doc)
        except OSError as exc:
            log.error("cannot keep the window record: %s", exc)
            with self._lock:
                self._dirty = True  # the journal set aside is kept until it is
            return
        if journal is not None:
            journal.saved()

    def on_config(self, running: Running) -> None:
        """A config runs (acknowledged): its windows are due from its epoch."""
        with self._lock:
            self.record.begin(epoch_of(running))
            self._dirty = True
            self._ensure_thread()
        self.save()

    def journal_live(self, running: Running, windows: Sequence[Window]) -> None:
        """Live windows about to be delivered: written down first (window_journal.py)
        and held in the record at once, both under the lock a save takes its snapshot
        and sets the journal aside under. So a line the save sets aside is in the
        snapshot it writes, and one it does not is in the next journal. (Added to the
        record only after the put, a window journalled just before a save was in neither
        the record written nor the journal kept: a kill -9 within the next second then
        lost it, and a restarted station backfilled a window it had delivered.)"""
        sent = running.fanout.sent
        with self._lock:
            if self._journal is not None:
                self._journal.append(
                    [["r", sent[w.stream].key, w.start_ns, w.end_ns] for w in windows]
                )
            for w in windows:
                self.record.add_received(sent[w.stream], w.start_ns, w.end_ns)
            self._changed()

    def journal_derived(self, stream: StreamKey, start: int, end: int) -> None:
        """A derived window about to be delivered (as :meth:`journal_live`)."""
        with self._lock:
            if self._journal is not None:
                self._journal.append([["d", stream.key, start, end]])
            self.record.add_derived(stream, start, end)
            self._changed()

    def on_windows(
        self,
        running: Running,
        windows: Sequence[Window],
        derived: Sequence[tuple[StreamKey, int, int]] = (),
    ) -> None:
        """Live windows, and the derived windows they completed (stream, start, end),
        written down and held at once (what the broker does a step at a time, before
        each put)."""
        self.journal_live(running, windows)
        for d in derived:
            self.journal_derived(*d)

    def _changed(self) -> None:
        """The record changed (under the lock): the clock thread saves it within SAVE_S."""
        if not self._dirty:
            self._dirty = True
            self._wake.notify_all()

    def filled_already(self, subscriber: str, stream: StreamKey, start: int, end: int) -> bool:
        """Did a backfill deliver this window already? (A NACK's resend may arrive
        after the backfill that filled the same gap: it must not be delivered twice.)"""
        with self._lock:
            spans = self.record.filled.get((subscriber, stream))
            return spans is not None and spans.covers(start, end)

    def received_until(self) -> int | None:
        with self._lock:
            return self.record.received_until()

    #: The other stations' records (fleet_record.py): a window one holds is no gap.
    fleet: Callable[[], list[WindowRecord]] | None = None

    def _view(self) -> WindowRecord:
        """This station's record, merged with the fleet's when there is one."""
        return self.record if self.fleet is None else merge([self.record, *self.fleet()])

    def mission_start(self, running: Running) -> int:
        with self._lock:
            start = self._view().mission_start(mission_of(running))
        return running.epoch_ns if start is None else min(start, running.epoch_ns)

    def knows(self, running: Running, subscriber: str) -> bool:
        with self._lock:
            self.record.begin(epoch_of(running))
            return subscriber in self._view().subscribers(self.mission_start(running))

    def record_json(self) -> dict[str, Any]:
        """The window record as kept in the state directory (what the fleet is told)."""
        with self._lock:
            return self.record.to_json()

    def gaps(self, running: Running, subscriber: str, from_ns: int, to_ns: int) -> list[Run]:
        """The runs of ``subscriber``'s windows in ``[from_ns, to_ns)`` not delivered,
        in every config that ran then (each on its own window grid)."""
        with self._lock:
            self.record.begin(epoch_of(running))  # dynamic subscriptions added since
            return self._view().gaps(subscriber, from_ns, to_ns)

    # -- jobs -------------------------------------------------------------------------

    def start(self, subscriber: str, runs: list[Run], rate_bps: int, owner: str = "") -> Job:
        job = Job(
            next(self._ids), subscriber, owner, deque(runs), sum(r.windows for r in runs), rate_bps
        )
        with self._lock:
            self._jobs[job.job_id] = job
            ended = [j for j in self._jobs.values() if j.status != "RUNNING"]
            for old in ended[:-KEEP_ENDED]:
                del self._jobs[old.job_id]
            _, frames = self._queue.submit(job, time.monotonic())
            self._transmit(frames)
            self._ensure_thread()
        if job.status != "RUNNING":
            self._ended(job)
        return job

    def running(self, subscriber: str, owner: str) -> bool:
        """Whether ``owner`` has a job for ``subscriber`` that has not ended."""
        with self._lock:
            return any(
                j.subscriber == subscriber and j.owner == owner for j in self._queue.jobs.values()
            )

    def job(self, job_id: int) -> Job | None:
        return self._jobs.get(job_id)

    def progress(self, job: Job) -> dict[str, Any]:
        with self._lock:
            return self._queue.progress(job, time.monotonic())

    def cancel(self, job_id: int) -> Job | None:
        with self._lock:
            job = self._jobs.get(job_id)
            if job is None or job.status != "RUNNING":
                return job
            self._transmit(self._queue.cancel(job, time.monotonic()))
        self._ended(job)
        return job

    def cap(self, job_id: int, rate_bps: int) -> Job | None:
        """Set the pace of a job; a running request is asked again at it from its resume
        point (the PubBroker replaces a request with the same id)."""
        with self._lock:
            job = self._jobs.get(job_id)
            if job is not None and job.status == "RUNNING":
                self._transmit(self._queue.cap(job, rate_bps, time.monotonic()))
            return job

    def on_up(self) -> None:
        """The link is up (again): the request in flight is asked from its resume point."""
        with self._lock:
            self._transmit(self._queue.link_up(time.monotonic()))

    def close(self) -> None:
        with self._lock:
            self._closed = True
            self._wake.notify_all()
        self.save()
        if self._journal is not None:
            self._journal.close()

    # -- frames to and from the PubBroker ----------------------------------------------

    def _transmit(self, frames: list[bytes]) -> None:
        for frame in frames:
            try:
                self._send(frame)
            except (ConnectionError, OSError) as exc:  # sent again when the link is up
                log.info("backfill request waits for the link: %s", exc)
                self._queue.link_down()
                break
        for note in self._queue.notes:
            log.info("%s", note)
        self._queue.notes.clear()
        self._wake.notify_all()

    def on_frame(self, frame: RawFrame) -> None:
        """A backfill frame from the PubBroker (link thread)."""
        with self._lock:
            ended_before = set(self._queue.jobs)
            now = time.monotonic()
            flight = self._queue.flight
            try:
                if frame.type == bf.BackfillType.DATA:
                    if flight is None or bf.data_request_id(frame) != flight.request.request_id:
                        return  # a frame of a request cancelled, replaced or ended
                    data = bf.decode_data(frame, flight.request.kind())
                    filled, frames = self._queue.on_data(data, len(frame.body) + 2, now)
                    if filled is not None:
                        self._deliver(filled)
                else:
                    msg = bf.decode(frame)
                    frames = []
                    if isinstance(msg, bf.BackfillEnd):
                        frames = self._queue.on_end(msg, now)
                    elif isinstance(msg, bf.BackfillProgress):
                        self._queue.heard(msg.request_id, now)
            except ProtocolError as exc:
                log.warning("backfill frame refused: %s", exc)
                return
            self._transmit(frames)
            ended = [self._jobs[i] for i in ended_before - set(self._queue.jobs) if i in self._jobs]
        for job in ended:
            self._ended(job)

    def _deliver(self, f: Filled) -> None:
        """The windows of a BACKFILL_DATA frame to the subscriber (those not delivered)."""
        run, job, now = f.run, f.job, time.time_ns()
        q = f.request.period_us * 1000
        sinks = self._sinks()
        view = self._view()  # a window another station delivered since is not sent twice
        for i, value in enumerate(f.data.values):
            start = f.request.window_start_ns(f.data.first + i)
            if view.delivered(run.subscriber, run.stream, run.source, start, start + q):
                job.duplicates += 1
                continue
            window = window_of(value, run.stream.aggregation, run.value_type)
            self.record.add_filled(run.subscriber, run.stream, start, start + q)
            if window is None and is_event(run.stream.aggregation):
                continue  # no event in the window: nothing to deliver (as live)
            val, count = split_window(run.stream.aggregation, window)
            ev = window if isinstance(window, EventsWindow) else None
            out = DeliveredValue(
                run.subscriber,
                run.stream.topic,
                run.stream.aggregation,
                run.stream.key.rsplit("/", 1)[1],
                run.unit,
                run.config_id,
                (start + q) // q,
                start,
                start + q,
                cast(Any, val),  # a list of the window's samples: list[float | bool] here
                count,
                now,
                True,
                *self._identity(run, start, q),
                None if ev is None else ev.event_ns(start),
                None if ev is None else ev.coalesced,
            )
            payload = out.to_json()
            if self._journal is not None:  # written down before it is put
                self._journal.append([["f", run.subscriber, run.stream.key, start, start + q]])
            for sink in sinks:
                sink.put(run.subscriber, payload)
            job.delivered += 1
        self._dirty = True

    def _identity(
        self, run: Run, start_ns: int, period_ns: int
    ) -> tuple[str | None, int | None, int | None]:
        """(drone, epoch_ns, window) of a backfilled window, Nones when not known."""
        if self.drone is None or run.epoch_ns is None:
            return (None, None, None)
        return (self.drone, run.epoch_ns, window_index(start_ns, run.epoch_ns, period_ns))

    def _ended(self, job: Job) -> None:
        log.info(
            "backfill %d for %s: %s (%d windows, %d duplicates, %d bytes, %d requests)%s",
            job.job_id,
            job.subscriber,
            job.status,
            job.delivered,
            job.duplicates,
            job.bytes,
            job.requests,
            f": {job.reason}" if job.reason else "",
        )

    # -- the clock --------------------------------------------------------------------

    def _ensure_thread(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="modd-backfill", daemon=True)
            self._thread.start()

    def _run(self) -> None:
        """Retries, resumes after a silence, and the record's saving, on time."""
        while True:
            with self._lock:
                if self._closed:
                    return
                wake = self._queue.wake_at()
                now = time.monotonic()
                if self._dirty and self._state is not None:
                    wake = min(wake or now + SAVE_S, self._saved_at + SAVE_S)
                timeout = None if wake is None else max(0.0, wake - now)
                if timeout is None or timeout > 0:
                    self._wake.wait(timeout)
                    continue
                before = set(self._queue.jobs)
                self._transmit(self._queue.tick(now))
                ended = [self._jobs[i] for i in before - set(self._queue.jobs) if i in self._jobs]
                save = self._dirty and now - self._saved_at >= SAVE_S and self._state is not None
            if save:
                self.save()
            for job in ended:
                self._ended(job)
