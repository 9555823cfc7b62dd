"""A backfill over a lossy datagram link finishes: a lost BACKFILL_DATA, a lost
END and a lost request are each asked for again from the resume point, and
every window is delivered exactly once with the PubBroker's value.

The PubBroker here is a model of its sender (runtime/cpp/src/broker/backfill.cpp):
a request replaces the one of the same id and sends windows resume..windows-1 in
batches, then END DONE. The channel drops the frames a test chooses."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from fractions import Fraction

from modd.link import backfill as bf
from modd.link.codec import split_frame
from modd.link.frames import Value
from modd.subbroker.backfill import BackfillManager, Run, Timing
from modd.subbroker.payload import DeliveredValue
from modd_plan.streams import StreamKey

PERIOD = Fraction(1, 4)
FROM_NS = 1_700_000_000_000_000_000
BATCH = 4


class Sink:
    def __init__(self) -> None:
        self.values: list[DeliveredValue] = []
        self.payloads: list[bytes] = []

    def put(self, subscriber: str, payload: bytes) -> None:
        self.values.append(DeliveredValue.from_json(payload))
        self.payloads.append(payload)


class LossyPubBroker:
    """Answers requests through a channel that drops frames ``drop`` picks (by
    kind and a running count of that kind); frames are handed over by ``pump``."""

    def __init__(self, drop: Callable[[str, int], bool]) -> None:
        self.drop = drop
        self.seen: dict[str, int] = {}
        self.out: list[bytes] = []
        self.requests: list[bf.BackfillRequest] = []
        self.lock = threading.Lock()

    def _send(self, kind: str, frame: bytes) -> None:
        n = self.seen.get(kind, 0)
        self.seen[kind] = n + 1
        if not self.drop(kind, n):
            self.out.append(frame)

    def receive(self, frame: bytes) -> None:  # the manager's send: base -> drone
        with self.lock:
            n = self.seen.get("request", 0)
            self.seen["request"] = n + 1
            if self.drop("request", n):
                return
            raw = split_frame(frame)
            assert raw is not None
            req = bf.decode(raw)
            assert isinstance(req, bf.BackfillRequest)
            self.requests.append(req)
            kind = req.kind()
            for first in range(req.resume, req.windows, BATCH):
                last = min(first + BATCH, req.windows)
                vals = [Value(True, float(k)) for k in range(first, last)]
                self._send(
                    "data", bf.encode_data(bf.BackfillData(req.request_id, first, vals), kind)
                )
            self._send(
                "end", bf.encode(bf.BackfillEnd(req.request_id, bf.EndStatus.DONE, req.windows))
            )

    def pump(self, manager: BackfillManager) -> bool:
        with self.lock:
            frames, self.out = self.out, []
        for f in frames:
            raw = split_frame(f)
            assert raw is not None
            manager.on_frame(raw)
        return bool(frames)


def run_backfill(
    drop: Callable[[str, int], bool], windows: int = 20, timeout_s: float = 10.0
) -> tuple[dict[str, object], Sink, LossyPubBroker]:
    sink = Sink()
    pb = LossyPubBroker(drop)
    m = BackfillManager(
        pb.receive,
        lambda: [sink],
        timing=Timing(stall_s=0.3, resume_grace_s=0.2, ack_s=0.3, min_resend_s=0.05),
    )
    stream = StreamKey("usv.a.z", "MIN", PERIOD)
    run = Run("sub_5", stream, stream, "float32", "m/s2", 1, FROM_NS, windows)
    job = m.start("sub_5", [run], 100_000)
    deadline = time.monotonic() + timeout_s
    while job.status == "RUNNING" and time.monotonic() < deadline:
        if not pb.pump(m):
            time.sleep(0.01)
    m.close()
    return m.progress(job), sink, pb


def check_once_each(sink: Sink, windows: int) -> None:
    q = 250_000_000
    got = sorted((v.start_ns, v.value) for v in sink.values)
    assert got == [(FROM_NS + k * q, float(k)) for k in range(windows)]
    # every window the backfill delivers carries the historical mark, in its bytes
    assert all(v.backfilled for v in sink.values)
    assert all(b'"backfilled":true' in p for p in sink.payloads)


def test_nothing_lost_one_request() -> None:
    prog, sink, pb = run_backfill(lambda kind, n: False)
    assert prog["status"] == "DONE" and prog["windows"] == 20 and prog["duplicates"] == 0
    check_once_each(sink, 20)
    assert len(pb.requests) == 1


def test_lost_data_frame_is_asked_again() -> None:
    prog, sink, pb = run_backfill(lambda kind, n: kind == "data" and n == 1)  # windows 4..7
    assert prog["status"] == "DONE", prog
    check_once_each(sink, 20)
    assert [r.resume for r in pb.requests] == [0, 4]


def test_lost_last_data_frame_is_asked_again_at_the_end() -> None:
    # the run's last batch (windows 16..19) lost: the END tells, a resume fetches it
    prog, sink, pb = run_backfill(lambda kind, n: kind == "data" and n == 4)
    assert prog["status"] == "DONE", prog
    check_once_each(sink, 20)
    assert [r.resume for r in pb.requests] == [0, 16]


def test_lost_end_does_not_hold_the_job() -> None:
    prog, sink, pb = run_backfill(lambda kind, n: kind == "end")
    assert prog["status"] == "DONE", prog
    check_once_each(sink, 20)
    assert len(pb.requests) == 1


def test_lost_request_is_sent_again_after_silence() -> None:
    prog, sink, pb = run_backfill(lambda kind, n: kind == "request" and n == 0)
    assert prog["status"] == "DONE", prog
    check_once_each(sink, 20)
    assert [r.resume for r in pb.requests] == [0]  # the second sending, from window 0


def test_heavy_loss_still_finishes_once_each() -> None:
    # every third frame of every kind lost, requests included
    prog, sink, _ = run_backfill(lambda kind, n: n % 3 == 1, windows=60, timeout_s=20)
    assert prog["status"] == "DONE", prog
    check_once_each(sink, 60)
