"""The fleet-wide record of which windows some station holds (docs/fleet.md): each
station answers its window record on ``modd/<drone>/fleet/held/<station>`` (and,
under ``running``, the config its PubBroker runs: handover.py); each
station asks the others every few seconds and keeps their last answers (a station
that died is remembered as it last answered), so a backfill asks only for windows no
station holds, and a station that takes a drone over knows the configs the previous
one ran (their epochs) and backfills the handover's gap on their grids.

>>> from fractions import Fraction
>>> from modd_plan.streams import StreamKey
>>> from .window_record import Due, Epoch
>>> s = StreamKey("usv.a.x", "MIN", Fraction(1))
>>> a, b = WindowRecord(), WindowRecord()
>>> a.begin(Epoch("m", 1, 0, [Due("sub", s, s, "m", "float32")])); a.add_received(s, 0, 3 * 10**9)
>>> b.begin(Epoch("m", 2, 5 * 10**9, [Due("sub", s, s, "m", "float32")]))
>>> b.add_received(s, 6 * 10**9, 8 * 10**9)
>>> [(r.config_id, r.from_ns, r.windows) for r in merge([b, a]).gaps("sub", 0, 8 * 10**9)]
[(1, 3000000000, 2), (2, 5000000000, 1)]
"""

from __future__ import annotations

import json
import logging
import threading
from collections.abc import Callable
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from modd_contracts.keys import held_key, values_of
from modd_plan.streams import StreamKey

from .handover import RunningConfig
from .payload import DeliveredValue
from .record_file import read_record
from .window_record import Intervals, WindowRecord

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.fleet")

#: Seconds between two askings of the other stations' records.
POLL_S = 2.0
#: Stations remembered per drone, and the bytes of one answer read.
MAX_STATIONS = 16
MAX_ANSWER_BYTES = 4 * 1024 * 1024


def merge(records: list[WindowRecord]) -> WindowRecord:
    """One record of every epoch and every window held by any of ``records`` (the first
    one's epoch wins when two name the same epoch)."""
    out = WindowRecord()
    for rec in reversed(records):
        for e in rec.epochs:
            out.begin(e)
        for into, spans in ((out.received, rec.received), (out.derived, rec.derived)):
            for key, iv in spans.items():
                _union(into.setdefault(key, Intervals()), iv)
        for fkey, iv in rec.filled.items():
            _union(out.filled.setdefault(fkey, Intervals()), iv)
    return out


def _union(into: Intervals, other: Intervals) -> None:
    for start, end in other.spans:
        into.add(start, end)


class FleetRecord:
    """This station's record on zenoh, and the other stations' last answers."""

    def __init__(
        self,
        session: zenoh.Session,
        drone: str,
        station: str,
        own: Callable[[], dict[str, Any]],
    ) -> None:
        self.drone, self.station = drone, station
        self._session = session
        self._own = own
        self._lock = threading.Lock()
        self._others: dict[str, WindowRecord] = {}
        self._running: dict[str, RunningConfig] = {}  # what each said its PubBroker runs
        self._stop = threading.Event()
        # what this station hears the serving one deliver (docs/fleet.md): exact where a
        # polled record is seconds old, and what a dead station delivered last
        self._heard = WindowRecord()
        self._queryable = session.declare_queryable(held_key(drone, station), self._answer)
        self._values = session.declare_subscriber(values_of(drone), self._on_value)
        self._thread = threading.Thread(target=self._run, name="modd-fleet", daemon=True)
        self._thread.start()

    def _answer(self, query: zenoh.Query) -> None:
        try:
            # on this station's own key (the query's is the wildcard): its answer is named
            own = held_key(self.drone, self.station)
            query.reply(own, json.dumps(self._own(), separators=(",", ":")))
        finally:
            query.drop()  # type: ignore[no-untyped-call]

    def _on_value(self, sample: zenoh.Sample) -> None:
        try:
            v = DeliveredValue.from_json(sample.payload.to_bytes())
            stream = StreamKey(v.topic, v.aggregation, Fraction(v.period_s))
        except (ValueError, ZeroDivisionError):
            return
        with self._lock:
            self._heard.add_filled(v.subscriber, stream, v.start_ns, v.end_ns)

    def others(self) -> list[WindowRecord]:
        """The other stations' records and what this one heard delivered."""
        with self._lock:
            return [*self._others.values(), self._heard]

    def heard_until(self) -> int | None:
        """The end of the latest window this station heard another deliver (ns)."""
        with self._lock:
            ends = [iv.spans[-1][1] for iv in self._heard.filled.values() if iv.spans]
        return max(ends, default=None)

    def running(self) -> list[tuple[str, RunningConfig]]:
        """What the other stations last said their PubBroker runs (a dead one's too)."""
        with self._lock:
            return list(self._running.items())

    def ask(self, timeout_s: float = 1.0) -> None:
        """Ask every other station for its record now; keep the answers."""
        for reply in self._session.get(held_key(self.drone, None), timeout=timeout_s):
            if reply.ok is None:
                continue
            station = str(reply.ok.key_expr).rsplit("/", 1)[1]
            data = reply.ok.payload.to_bytes()
            if station == self.station or len(data) > MAX_ANSWER_BYTES:
                continue
            try:
                doc = json.loads(data)
                told = doc.pop("running", None) if isinstance(doc, dict) else None
                record = read_record(doc)
                running = None if told is None else RunningConfig.from_json(told)
            except (ValueError, RecursionError) as exc:
                log.warning("the record of station %s is refused: %s", station[:64], exc)
                continue
            with self._lock:
                if running is not None and (
                    station in self._running or len(self._running) < MAX_STATIONS
                ):
                    self._running[station] = running
                # merged into what it said before: a station restarted without its state
                # directory forgets windows it delivered, the fleet does not
                if station in self._others:
                    self._others[station] = merge([record, self._others[station]])
                elif len(self._others) < MAX_STATIONS:
                    self._others[station] = record

    def _run(self) -> None:
        while not self._stop.wait(POLL_S):
            try:
                self.ask()
            except Exception:  # the fleet record must never stop the SubBroker
                log.exception("asking the other stations' records failed")

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=3.0)
        self._values.undeclare()  # type: ignore[no-untyped-call]
        self._queryable.undeclare()  # type: ignore[no-untyped-call]
