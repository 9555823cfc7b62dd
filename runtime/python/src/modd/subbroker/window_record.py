"""What should have arrived and what did, per subscription, since the mission
began (docs/subbroker.md, "Backfill"): every config the PubBroker ran (its
epoch and, per subscriber, the streams it was due), the live windows received
per sent stream and the backfilled ones per subscriber, as merged time
intervals (a few per outage, not one per window). Kept in the state directory
(``windows.json``), so a SubBroker restart, a PubBroker restart or a redeploy
(each a new epoch) leaves the windows of the earlier configs backfillable.

A window of an earlier config is asked for as that config defined it (its
stream, on its epoch's grid) and recomputed on board from the archive.

>>> from fractions import Fraction
>>> rec = WindowRecord()
>>> s = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
>>> rec.begin(Epoch("m", 1, 0, [Due("sub", s, s, "m", "float32")]))
>>> rec.add_received(s, 0, 500_000_000); rec.add_received(s, 1_000_000_000, 2_000_000_000)
>>> [(r.from_ns, r.windows) for r in rec.gaps("sub", 0, 2_000_000_000)]
[(500000000, 2)]
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import Any

from modd_plan.streams import StreamKey

from .backfill_queue import Run
from .fanout import period_us

#: Epochs kept (the oldest are forgotten past this: a mission of many redeploys).
MAX_EPOCHS = 256
#: Merged intervals kept per stream (the newest): a few per outage.
MAX_SPANS = 1024


class Intervals:
    """Disjoint, merged ``[start, end)`` intervals of nanoseconds.

    >>> iv = Intervals(); iv.add(0, 10); iv.add(10, 20); iv.add(30, 40)
    >>> iv.spans, iv.covers(5, 20), iv.covers(15, 35)
    ([(0, 20), (30, 40)], True, False)
    """

    def __init__(self, spans: list[tuple[int, int]] | None = None) -> None:
        self.spans: list[tuple[int, int]] = spans or []

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


@dataclass(frozen=True)
class Due:
    """A stream a subscriber was due in an epoch, and the sent stream it comes from."""

    subscriber: str
    stream: StreamKey
    source: StreamKey
    unit: str
    value_type: str


@dataclass
class Epoch:
    """A config the PubBroker acknowledged: due from ``epoch_ns`` to the next epoch."""

    mission: str
    config_id: int
    epoch_ns: int
    due: list[Due]


class WindowRecord:
    def __init__(self) -> None:
        self.epochs: list[Epoch] = []
        self.received: dict[StreamKey, Intervals] = {}
        # derived windows delivered live, per derived stream: a derived window counts
        # when the fan-out delivered it, not when its source interval arrived
        self.derived: dict[StreamKey, Intervals] = {}
        self.filled: dict[tuple[str, StreamKey], Intervals] = {}

    def begin(self, epoch: Epoch) -> None:
        """A config runs from ``epoch.epoch_ns`` (the same epoch again replaces it: a
        resumed config, or a dynamic subscription added to the running one)."""
        self.epochs = [e for e in self.epochs if e.epoch_ns != epoch.epoch_ns]
        bisect.insort(self.epochs, epoch, key=lambda e: e.epoch_ns)
        del self.epochs[:-MAX_EPOCHS]

    def add_received(self, source: StreamKey, start: int, end: int) -> None:
        self.received.setdefault(source, Intervals()).add(start, end)

    def add_derived(self, stream: StreamKey, start: int, end: int) -> None:
        self.derived.setdefault(stream, Intervals()).add(start, end)

    def holds(self, subscriber: str, stream: StreamKey, start: int, end: int) -> bool:
        """Whether ``subscriber``'s window of ``stream`` is held here: received, derived,
        or filled for it."""
        for spans in (
            self.received.get(stream),
            self.derived.get(stream),
            self.filled.get((subscriber, stream)),
        ):
            if spans is not None and spans.covers(start, end):
                return True
        return False

    def add_filled(self, subscriber: str, stream: StreamKey, start: int, end: int) -> None:
        self.filled.setdefault((subscriber, stream), Intervals()).add(start, end)

    def received_until(self) -> int | None:
        """The end of the latest live window received (the live path covers what follows)."""
        ends = [iv.spans[-1][1] for iv in self.received.values() if iv.spans]
        return max(ends) if ends else None

    def delivered(
        self, subscriber: str, stream: StreamKey, source: StreamKey, start: int, end: int
    ) -> bool:
        live = self.received.get(source) if stream == source else self.derived.get(stream)
        if live is not None and live.covers(start, end):
            return True
        filled = self.filled.get((subscriber, stream))
        return filled is not None and filled.covers(start, end)

    def mission_start(self, mission: str) -> int | None:
        """The epoch of the mission's first config still in the record (the last run of
        epochs with this mission name)."""
        start = None
        for e in self.epochs:
            start = (start if start is not None else e.epoch_ns) if e.mission == mission else None
        return start

    def subscribers(self, since_ns: int) -> set[str]:
        """The subscribers due windows after ``since_ns`` (in any epoch that far)."""
        nexts = [e.epoch_ns for e in self.epochs[1:]] + [1 << 63]
        return {
            d.subscriber
            for e, end in zip(self.epochs, nexts, strict=True)
            if end > since_ns
            for d in e.due
        }

    def gaps(self, subscriber: str, from_ns: int, to_ns: int) -> list[Run]:
        """The runs of ``subscriber``'s windows in ``[from_ns, to_ns)`` not delivered (live
        or backfilled), each epoch's streams on its own window grid."""
        runs: list[Run] = []
        for i, e in enumerate(self.epochs):
            end = self.epochs[i + 1].epoch_ns if i + 1 < len(self.epochs) else to_ns
            lo, hi = max(from_ns, e.epoch_ns), min(to_ns, end)
            if hi <= lo:
                continue
            running = i + 1 == len(self.epochs)  # its windows go on past to_ns
            for d in e.due:
                if d.subscriber == subscriber:
                    runs += self._gaps_of(e, d, lo, hi, running)
        return runs

    def _gaps_of(self, e: Epoch, d: Due, lo: int, hi: int, running: bool = False) -> list[Run]:
        q = period_us(d.stream) * 1000

        def run(start: int, windows: int) -> Run:
            return Run(
                d.subscriber,
                d.stream,
                d.source,
                d.value_type,
                d.unit,
                e.config_id,
                start,
                windows,
                e.epoch_ns,
            )

        first = max(0, -(-(lo - e.epoch_ns) // q))
        last = (hi - e.epoch_ns) // q  # windows [epoch + j q, epoch + (j+1) q) for j < last
        runs: list[Run] = []
        start: int | None = None
        for j in range(first, last + 1):
            s = e.epoch_ns + j * q
            if j < last and not self.delivered(d.subscriber, d.stream, d.source, s, s + q):
                if start is None:
                    start = s
            elif start is not None:
                runs.append(run(start, (s - start) // q))
                start = None
        under_way = e.epoch_ns + last * q
        if running and under_way >= lo and self._cut_short(d, under_way, hi):
            # the derived window under way at hi, which the live path never completes: a run
            # of its own, last, so that the drone, which sends it once its archive holds its
            # end, holds up no other run (the queue serves one run per turn)
            runs.append(run(under_way, 1))
        return runs

    def _cut_short(self, d: Due, start: int, hi: int) -> bool:
        """Whether the derived window of ``d`` that began at ``start`` and is under way
        at ``hi`` already missed a source window (an outage that ended inside it): the
        fan-out delivers a derived window only whole, so it never comes live and is a
        gap now, though it ends after ``hi`` (a fill asked just after the link came back).
        A direct window under way is the live path's."""
        if (
            d.stream == d.source
            or start >= hi
            or self.delivered(
                d.subscriber, d.stream, d.source, start, start + period_us(d.stream) * 1000
            )
        ):
            return False
        live = self.received.get(d.source)
        if live is None or not live.spans:
            return False
        seen = min(hi, live.spans[-1][1])
        return seen > start and not live.covers(start, seen)

    # -- kept in the state directory (read back by record_file.read_record) -----------

    def to_json(self) -> dict[str, Any]:
        return {
            "epochs": [
                {
                    "mission": e.mission,
                    "config_id": e.config_id,
                    "epoch_ns": e.epoch_ns,
                    "due": [
                        [d.subscriber, d.stream.key, d.source.key, d.unit, d.value_type]
                        for d in e.due
                    ],
                }
                for e in self.epochs
            ],
            # the newest MAX_SPANS intervals a stream: what the reader takes (record_file)
            "received": {k.key: iv.spans[-MAX_SPANS:] for k, iv in self.received.items()},
            "derived": {k.key: iv.spans[-MAX_SPANS:] for k, iv in self.derived.items()},
            "filled": [[s, k.key, iv.spans[-MAX_SPANS:]] for (s, k), iv in self.filled.items()],
        }

    def derived_from_sources(self) -> None:
        """Count each derived window delivered where its source interval arrived (how
        a record of an earlier version counted them)."""
        for e in self.epochs:
            for d in e.due:
                if d.stream != d.source:
                    for a, b in self.received.get(d.source, Intervals()).spans:
                        self.add_derived(d.stream, a, b)
