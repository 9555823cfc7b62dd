"""The backfill queue (modd.subbroker.backfill_queue) on a fake clock and a fake link.

The fake PubBroker models the C++ sender (runtime/cpp/src/broker/backfill.cpp): a request
is acknowledged by a PROGRESS, replaces the one of the same id, and its windows go in
BACKFILL_DATA frames paced by a token bucket, then an END; at most ``max_jobs`` requests
at once (BUSY past that), and it forgets every request when the link comes back. Each
window's value is its start in seconds, so a delivered window is checked against the
window it claims to be.
"""

from __future__ import annotations

import dataclasses
import random
from collections import deque
from collections.abc import Callable
from fractions import Fraction

import pytest
from modd.link import backfill as bf
from modd.link.codec import split_frame
from modd.link.frames import Value
from modd.subbroker.backfill_queue import BackfillQueue, Job, Run, Timing
from modd.subbroker.backfill_view import MAX_VIEW, time_left
from modd_contracts.events import parse_label
from modd_contracts.schema import validate
from modd_plan.streams import StreamKey

T0 = 1_700_000_000_000_000_000
Q = 250_000_000
BATCH = 8
DT = 0.01


class FakePubBroker:
    def __init__(
        self,
        rate_bps: int,
        busy: int = 0,
        max_jobs: int = 8,
        drop: Callable[[str, int], bool] = lambda kind, n: False,
    ) -> None:
        self.rate = rate_bps
        self.busy = busy  # requests answered BUSY first
        self.max_jobs = max_jobs
        self.drop = drop
        self.seen: dict[str, int] = {}
        self.jobs: dict[int, list[object]] = {}  # id -> [request, next]
        self.credit = 0.0
        self.out: deque[bytes] = deque()
        self.requests: list[tuple[float, bf.BackfillRequest]] = []
        self.most_at_once = 0
        self.data_bytes = 0

    def _lost(self, kind: str) -> bool:
        n = self.seen.get(kind, 0)
        self.seen[kind] = n + 1
        return self.drop(kind, n)

    def receive(self, frame: bytes, now: float) -> None:
        if self._lost("request"):
            return
        raw = split_frame(frame)
        assert raw is not None
        m = bf.decode(raw)
        if isinstance(m, bf.BackfillCancel):
            self.jobs.pop(m.request_id, None)
            self.out.append(bf.encode(bf.BackfillEnd(m.request_id, bf.EndStatus.CANCELLED, 0)))
            return
        assert isinstance(m, bf.BackfillRequest)
        self.requests.append((now, m))
        self.jobs.pop(m.request_id, None)
        if self.busy or len(self.jobs) >= self.max_jobs:
            self.busy = max(0, self.busy - 1)
            self.out.append(bf.encode(bf.BackfillEnd(m.request_id, bf.EndStatus.BUSY, m.resume)))
            return
        self.jobs[m.request_id] = [m, m.resume]
        self.most_at_once = max(self.most_at_once, len(self.jobs))
        if not self._lost("ack"):
            self.out.append(
                bf.encode(bf.BackfillProgress(m.request_id, m.resume, m.windows, 0, m.rate_bps))
            )

    def held(self, req: bf.BackfillRequest) -> int:
        """Windows of ``req`` the archive holds (all of them here)."""
        return req.windows

    def forget(self) -> None:  # a new link session
        self.jobs.clear()
        self.out.clear()

    def pump(self) -> None:
        self.credit = min(self.credit + self.rate * DT, self.rate * DT * 4)
        for rid, job in list(self.jobs.items()):
            req, first = job
            assert isinstance(req, bf.BackfillRequest) and isinstance(first, int)
            if self.credit <= 0:
                return
            last = min(first + BATCH, req.windows, max(first, self.held(req)))
            if last == first:
                continue  # waiting for the archive (ArchivePubBroker)
            vals = [Value(True, req.window_start_ns(k) / 1e9) for k in range(first, last)]
            frame = bf.encode_data(bf.BackfillData(rid, first, vals), req.kind())
            self.credit -= len(frame)
            self.data_bytes += len(frame)
            job[1] = last
            if not self._lost("data"):
                self.out.append(frame)
            if last >= req.windows:
                del self.jobs[rid]
                if not self._lost("end"):
                    self.out.append(bf.encode(bf.BackfillEnd(rid, bf.EndStatus.DONE, last)))


class Bench:
    """The queue, the fake PubBroker and the fake clock; what was delivered."""

    def __init__(self, pb: FakePubBroker, timing: Timing | None = None) -> None:
        self.q = BackfillQueue(timing or Timing())
        self.pb = pb
        self.now = 0.0
        self.up = True
        self.got: dict[tuple[str, int], float] = {}
        self.twice = 0
        self.reasons: dict[int, set[str]] = {}
        self.track_reasons = True
        self.ids = 0

    def send(self, frames: list[bytes]) -> None:
        for f in frames:
            if self.up:
                self.pb.receive(f, self.now)

    def submit(self, subscriber: str, runs: list[Run], rate: int, owner: str = "") -> Job:
        self.ids += 1
        job = Job(self.ids, subscriber, owner, deque(runs), sum(r.windows for r in runs), rate)
        self.send(self.q.submit(job, self.now)[1])
        return job

    def step(self) -> None:
        self.now += DT
        if self.up:
            self.pb.pump()
        while self.up and self.pb.out:
            raw = split_frame(self.pb.out.popleft())
            assert raw is not None
            if raw.type == bf.BackfillType.DATA:
                f = self.q.flight
                if f is None or bf.data_request_id(raw) != f.request.request_id:
                    continue
                filled, frames = self.q.on_data(
                    bf.decode_data(raw, f.request.kind()), len(raw.body) + 2, self.now
                )
                if filled is not None:
                    for i, v in enumerate(filled.data.values):
                        start = filled.request.window_start_ns(filled.data.first + i)
                        key = (filled.run.subscriber, start)
                        self.twice += key in self.got
                        self.got[key] = v.number
                        filled.job.delivered += 1
                self.send(frames)
                continue
            m = bf.decode(raw)
            if isinstance(m, bf.BackfillEnd):
                self.send(self.q.on_end(m, self.now))
            elif isinstance(m, bf.BackfillProgress):
                self.q.heard(m.request_id, self.now)
        wake = self.q.wake_at()
        if wake is not None and wake <= self.now:
            self.send(self.q.tick(self.now))
        for job in self.q.jobs.values() if self.track_reasons else ():
            self.reasons.setdefault(job.job_id, set()).add(self.q.reason(job, self.now))

    def run_until(self, done: Callable[[], bool], limit_s: float) -> float:
        start = self.now
        while not done():
            assert self.now - start < limit_s, [
                self.q.progress(j, self.now) for j in self.q.jobs.values()
            ]
            self.step()
        return self.now - start


def runs_of(subscriber: str, n_runs: int, windows: int, offset: int = 0) -> list[Run]:
    s = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
    return [
        Run(subscriber, s, s, "float64", "m", 1, T0 + (offset + 100 * k) * Q, windows)
        for k in range(n_runs)
    ]


def expected(
    subscriber: str, n_runs: int, windows: int, offset: int = 0
) -> dict[tuple[str, int], float]:
    return {
        (subscriber, r.from_ns + k * Q): (r.from_ns + k * Q) / 1e9
        for r in runs_of(subscriber, n_runs, windows, offset)
        for k in range(windows)
    }


def test_thirteen_jobs_at_once_all_done_one_request_at_a_time_in_the_paced_time() -> None:
    b = Bench(FakePubBroker(rate_bps=600))
    jobs = [b.submit(f"sub_{i}", runs_of(f"sub_{i}", 3, 24, i), 600) for i in range(13)]
    secs = b.run_until(lambda: all(j.status != "RUNNING" for j in jobs), 600)
    assert [j.status for j in jobs] == ["DONE"] * 13
    want: dict[tuple[str, int], float] = {}
    for i in range(13):
        want |= expected(f"sub_{i}", 3, 24, i)
    assert b.got == want and b.twice == 0
    assert b.pb.most_at_once == 1  # one request on the link at a time
    assert len(b.pb.requests) == 13 * 3  # none lost, none repeated
    paced = b.pb.data_bytes / 600
    assert paced * 0.9 <= secs <= paced * 1.1 + 39 * 2 * DT, (secs, paced)
    # every waiting job said why
    assert any(r.startswith("queued behind 12 jobs") for r in b.reasons[13])
    assert "paced at 600 B/s" in b.reasons[1]


def test_owners_are_served_in_turn() -> None:
    b = Bench(FakePubBroker(rate_bps=10_000))
    a_jobs = [
        b.submit("sub_a", runs_of("sub_a", 4, 8, 1000 * i), 10_000, owner="alice") for i in range(3)
    ]
    bob = b.submit("sub_b", runs_of("sub_b", 1, 8), 10_000, owner="bob")
    b.run_until(lambda: bob.status == "DONE", 60)
    # bob's one run came second, not after alice's twelve
    assert [r.request_id for _, r in b.pb.requests].index(b.pb.requests[1][1].request_id) == 1
    assert b.pb.requests[1][1].from_ns == runs_of("sub_b", 1, 8)[0].from_ns
    assert all(j.status == "RUNNING" for j in a_jobs)
    b.run_until(lambda: all(j.status == "DONE" for j in a_jobs), 60)


def test_busy_means_wait_and_ask_again_never_fail() -> None:
    b = Bench(FakePubBroker(rate_bps=5000, busy=4))
    job = b.submit("sub_1", runs_of("sub_1", 2, 16), 5000)
    b.run_until(lambda: job.status != "RUNNING", 120)
    assert job.status == "DONE" and b.got == expected("sub_1", 2, 16)
    times = [t for t, _ in b.pb.requests]
    gaps = [round(y - x, 1) for x, y in zip(times, times[1:], strict=False)][:4]
    assert gaps == [1.0, 2.0, 4.0, 8.0]  # waited longer each time, within busy_max_s
    assert any(r.startswith("the PubBroker is busy") for r in b.reasons[1])


def test_a_request_is_sent_again_until_acknowledged() -> None:
    lost = {0, 1, 2}  # the first three requests never reach the PubBroker
    b = Bench(FakePubBroker(rate_bps=5000, drop=lambda k, n: k == "request" and n in lost))
    job = b.submit("sub_1", runs_of("sub_1", 1, 16), 5000)
    b.run_until(lambda: job.status != "RUNNING", 120)
    assert job.status == "DONE" and b.got == expected("sub_1", 1, 16)
    assert job.requests == 4 and len(b.pb.requests) == 1
    assert "asked the PubBroker 2 time(s), waiting for its answer" in b.reasons[1]


def test_a_flapping_link_never_sends_more_than_one_request_a_second() -> None:
    b = Bench(FakePubBroker(rate_bps=100))
    job = b.submit("sub_1", runs_of("sub_1", 1, 400), 100)
    sent: list[float] = []
    for k in range(130):  # 1.3 s: the link goes down and up every 20 ms
        b.up = k % 2 == 1
        if b.up:
            b.pb.forget()
            before = len(b.pb.requests)
            b.send(b.q.link_up(b.now))
            sent += [b.now] * (len(b.pb.requests) - before)
        else:
            b.q.link_down()
            assert b.q.reason(job, b.now) == "waiting for the link"
        b.step()
    sent = [t for t, _ in b.pb.requests]
    assert all(y - x >= 1.0 - 1e-9 for x, y in zip(sent, sent[1:], strict=False)), sent
    assert len(sent) <= 2
    b.up = True
    b.run_until(lambda: job.status != "RUNNING", 60)
    assert job.status == "DONE" and b.got == expected("sub_1", 1, 400) and b.twice == 0


def test_silence_after_the_ack_asks_again_from_the_resume_point() -> None:
    # the second and third data frames are lost, and so is the END: a silence
    drop = {("data", 1), ("data", 2), ("end", 0)}
    b = Bench(FakePubBroker(rate_bps=5000, drop=lambda k, n: (k, n) in drop), Timing(stall_s=3.0))
    job = b.submit("sub_1", runs_of("sub_1", 1, 24), 5000)
    b.run_until(lambda: job.status != "RUNNING", 60)
    assert job.status == "DONE" and b.got == expected("sub_1", 1, 24) and b.twice == 0
    assert [r.resume for _, r in b.pb.requests] == [0, 8]


@pytest.mark.parametrize("rate", [0, 5000])
def test_an_end_whose_data_was_lost_is_asked_again_after_the_grace(rate: int) -> None:
    """A datagram link lost the run's only DATA frame but not its PROGRESS and END
    (DONE at a resume point short of the run): asked again once the grace is over, well
    before the stall; at the PubBroker's own pace (rate 0) too, where the stall was
    1,000 s (a job left RUNNING for ever, found over udp at 10 % loss)."""
    b = Bench(FakePubBroker(rate_bps=5000, drop=lambda k, n: (k, n) == ("data", 0)))
    job = b.submit("sub_1", runs_of("sub_1", 1, 5), rate)
    secs = b.run_until(lambda: job.status != "RUNNING", 60)
    assert job.status == "DONE" and b.got == expected("sub_1", 1, 5) and b.twice == 0
    assert secs < Timing().resume_grace_s + 0.5, secs
    assert Timing().stall(0) == Timing().stall_s


def test_cancel_and_a_refusal_move_the_queue_on() -> None:
    b = Bench(FakePubBroker(rate_bps=50))
    first = b.submit("sub_1", runs_of("sub_1", 1, 400), 50)
    second = b.submit("sub_2", runs_of("sub_2", 1, 8), 50)
    assert b.q.reason(second, b.now) == "queued behind 1 job"
    b.step()
    b.send(b.q.cancel(first, b.now))
    assert first.status == "CANCELLED" and first.job_id not in b.pb.jobs
    b.run_until(lambda: second.status == "DONE", 30)
    # a refusal other than BUSY ends that job, and the next one still runs
    third = b.submit("sub_3", runs_of("sub_3", 1, 8), 5000)
    fourth = b.submit("sub_4", runs_of("sub_4", 1, 8), 5000)
    rid = b.q.flight.request.request_id if b.q.flight else -1
    b.pb.jobs.pop(rid)
    b.send(b.q.on_end(bf.BackfillEnd(rid, bf.EndStatus.UNKNOWN_TOPIC, 0, "no such topic"), b.now))
    assert third.status == "FAILED" and "UNKNOWN_TOPIC" in third.reason
    b.run_until(lambda: fourth.status == "DONE", 30)


@pytest.mark.parametrize("seed", range(8))
def test_many_owners_loss_flaps_and_busy_every_window_once(seed: int) -> None:
    """Random loss of every kind of frame, BUSY answers, link flaps, 3 owners with 12 jobs:
    every job DONE, every window once, one request on the link at a time, the same
    request never twice within min_resend_s."""
    rng = random.Random(seed)
    pb = FakePubBroker(rate_bps=2000, busy=3, drop=lambda k, n: rng.random() < 0.15)
    b = Bench(pb, Timing(stall_s=2.0))
    b.track_reasons = False
    want: dict[tuple[str, int], float] = {}
    jobs = []
    for i in range(12):
        name, runs = f"sub_{i}", 1 + i % 3
        jobs.append(
            b.submit(name, runs_of(name, runs, 10 + 3 * i, 1000 * i), 2000, owner=f"user_{i % 3}")
        )
        want |= expected(name, runs, 10 + 3 * i, 1000 * i)
    last_sent: dict[int, float] = {}
    for _ in range(60_000):
        if all(j.status != "RUNNING" for j in jobs):
            break
        if rng.random() < 0.002:  # the link drops for a moment, the PubBroker forgets
            b.up = False
            b.q.link_down()
        elif not b.up and rng.random() < 0.05:
            b.up = True
            pb.forget()
            b.send(b.q.link_up(b.now))
        n = len(pb.requests)
        b.step()
        for t, r in pb.requests[n:]:
            assert t - last_sent.get(r.request_id, -9.0) >= b.q.timing.min_resend_s - 1e-9
            last_sent[r.request_id] = t
    assert [j.status for j in jobs] == ["DONE"] * 12, [b.q.progress(j, b.now) for j in jobs]
    assert b.got == want and b.twice == 0
    assert pb.most_at_once == 1


# -- the queue's view and its time left (backfill_view.py) -------------------------------


class ArchivePubBroker(FakePubBroker):
    """The fake PubBroker whose archive holds windows only up to ``archived(now)`` (ns):
    a window past it is sent once a flush brings it in, so a fill goes by bursts."""

    def __init__(self, rate_bps: int, archived: Callable[[], int]) -> None:
        super().__init__(rate_bps)
        self.archived = archived

    def held(self, req: bf.BackfillRequest) -> int:
        return int((self.archived() - req.from_ns) // (req.period_us * 1000))


def _recent(subscriber: str, end_ns: int, windows: int) -> list[Run]:
    """One run of ``windows`` windows ending at ``end_ns`` (a gap the link just had)."""
    s = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
    return [Run(subscriber, s, s, "float64", "m", 1, end_ns - windows * Q, windows)]


def _naive(seen: list[tuple[float, int]], left: int) -> float | None:
    """The time left the workbench said before: windows left at the last 3 s's pace."""
    t1, d1 = seen[-1]
    t0, d0 = next((t, d) for t, d in seen if t >= t1 - 3)
    return left / ((d1 - d0) / (t1 - t0)) if t1 - t0 >= 1 and d1 > d0 else None


def test_time_left_after_a_drone_wide_fill_is_true_or_not_said() -> None:
    """A drone-wide fill, then a rehearsal's fill of 10 jobs whose last windows wait for
    the drone's archive (flushed every 5 s, durable 2 s later) while another owner's
    job shares the link: every time left said is within 1.5x + 3 s of the truth (the
    journey asks 3x + 10 s), said most of the time; where it cannot be said the state says
    why. The pace of the last 3 s (what the workbench said before) is off by more."""
    flush = int(5e9)
    pb = ArchivePubBroker(100, lambda: 0)
    b = Bench(pb)

    def drone() -> int:  # the drone's clock
        return T0 + 600 * 10**9 + int(b.now * 1e9)

    pb.archived = lambda: (drone() - 2 * 10**9) // flush * flush
    b.track_reasons = False
    wide = [b.submit(f"sub_{i}", runs_of(f"sub_{i}", 2, 12, 5 * i), 600, "op") for i in range(6)]
    b.run_until(lambda: all(j.status == "DONE" for j in wide), 600)
    now = drone()
    ours = [
        b.submit(f"sub_{i}", _recent(f"sub_{i}", now, 24 + 8 * i), 100, "op") for i in range(10)
    ]
    states: set[str] = set()
    samples: list[tuple[float, float | None, float | None]] = []
    seen: list[tuple[float, int]] = []
    while any(j.status == "RUNNING" for j in ours):
        if not samples or b.now - samples[-1][0] >= 0.5:  # the workbench polls every 0.5 s
            ahead = b.q.view(b.now)[1]
            states |= {a.state for a in ahead}
            done = sum(j.done_windows for j in ours)
            seen.append((b.now, done))
            left = time_left(ahead, {j.job_id for j in ours})[0]
            samples.append((b.now, left, _naive(seen, sum(j.total for j in ours) - done)))
        b.step()
        if len(samples) == 3 and b.ids == 16:  # another owner's job shares the link from then
            b.submit("sub_x", runs_of("sub_x", 3, 40, 1000), 100, "scientist")
        assert b.now < 2000
    end = b.now
    said = [(end - at, left) for at, left, _ in samples if left is not None]
    assert len(said) >= len(samples) * 2 // 3, samples  # a number most of the time
    for truth, left in said:
        assert left <= 1.5 * truth + 3 and truth <= 1.5 * left + 3, (truth, left)
    naive = [(end - at, n) for at, _, n in samples if n is not None]
    assert any(n > 1.5 * t + 3 or t > 1.5 * n + 3 for t, n in naive), naive
    assert {"waiting_archive", "queued", "sending", "asking"} <= states


def test_the_view_is_bounded_and_says_each_jobs_state() -> None:
    b = Bench(FakePubBroker(rate_bps=600))
    jobs = [b.submit(f"sub_{i}", runs_of(f"sub_{i}", 2, 8, i), 600) for i in range(MAX_VIEW + 8)]
    doc, ahead = b.q.view(b.now)
    assert len(doc["jobs"]) == MAX_VIEW and doc["more"] == 8
    assert [a["state"] for a in doc["jobs"]][:2] == ["asking", "queued"]
    assert doc["pace_bps"] is None  # nothing measured: no number
    assert time_left(ahead, {jobs[1].job_id}) == (None, "measuring the pace")
    assert time_left(ahead, {jobs[-1].job_id})[1] == "not in the queue"  # past MAX_VIEW
    b.run_until(lambda: bool(jobs[0].runs) and b.q.meter.pace_bps() is not None, 60)
    doc, ahead = b.q.view(b.now + 1)
    assert doc["jobs"][0]["state"] == "sending" and doc["jobs"][0]["send_s"] > 0
    on = b.q.flight.job if b.q.flight else jobs[0]
    b.up = False
    b.q.link_down()
    assert b.q.view(b.now + 2)[0]["jobs"][0]["state"] == "waiting_link"
    assert time_left(b.q.view(b.now + 2)[1], {on.job_id}) == (None, "waiting for the link")
    progress = b.q.progress(on, b.now + 2)
    assert progress["seconds_left"] is None and len(progress["queue"]["jobs"]) == MAX_VIEW
    assert validate("backfill", progress) == []  # the contract (backfill.schema.json)


def test_an_event_runs_request_carries_its_definition_and_its_configs_epoch() -> None:
    """ON_CHANGE and THRESHOLD runs: the request names the label's parameters and the
    epoch the PubBroker replays its archive from; asked again (the link back, a resume
    point further on), it keeps both."""
    q = BackfillQueue(Timing())
    epoch = T0 - 40 * Q
    for label in ("ON_CHANGE(0.5, 4)", "THRESHOLD(DOWN 5, 0.2)"):
        s = StreamKey("usv.a.x", label, Fraction(1, 4))
        run = Run("sub_1", s, s, "float32", "m", 1, T0, 16, epoch)
        job = Job(len(q.jobs) + 1, "sub_1", "", deque([run]), 16, 600)
        _, frames = q.submit(job, 0.0)
        raw = split_frame(frames[0])
        assert raw is not None
        req = bf.decode(raw)
        assert isinstance(req, bf.BackfillRequest)
        assert req.event == parse_label(label) and req.state_from_ns == epoch
        assert (req.from_ns, req.windows, req.resume) == (T0, 16, 0)
        assert q.flight is not None
        q.flight.next = 5
        q.link_down()
        again = split_frame(q.link_up(10.0)[0])
        assert again is not None
        assert bf.decode(again) == dataclasses.replace(req, resume=5)
        q.cancel(job, 10.0)
