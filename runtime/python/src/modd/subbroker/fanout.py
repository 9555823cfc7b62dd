"""Fan-out: from the windows of the sent streams in one DATA slot to the
windows of every stream a subscriber listens to, derived streams included.

The SubBroker keeps, per sent stream, the last windows it received (as many
as the largest derivation factor that uses it). A derived stream of period
``k·P`` is due at every date that is a multiple of ``k·P``; its value is
:func:`modd_plan.derive.derive_value` over the ``k`` source windows that tile
it. A derived window whose source windows did not all arrive (the link was
down for part of it, or the subscription began inside it) is *not* delivered:
a MIN over half a window would be a wrong MIN.

>>> from modd_plan.streams import StreamKey
>>> from fractions import Fraction
>>> quarter = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
>>> fan = FanOut([quarter])
>>> fan.route(quarter, (), "sub_q")
>>> [(o.stream.aggregation, o.end_us, o.value) for o in fan.on_slot(0, 250_000, {0: 1.5})]
[('MIN', 250000, 1.5)]
"""

from __future__ import annotations

import itertools
import threading
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from modd_model.numbers import MICROS_PER_SECOND
from modd_plan.derive import derive_value
from modd_plan.streams import Source, StreamKey


def period_us(stream: StreamKey) -> int:
    """Window period of a stream in whole microseconds (the wire's unit)."""
    us = stream.period * MICROS_PER_SECOND
    if us.denominator != 1:
        raise ValueError(f"period of {stream.key} is not a whole number of microseconds")
    return int(us)


@dataclass(frozen=True)
class Output:
    """One window of one routed stream, ready to deliver to ``subscribers``."""

    stream: StreamKey
    slot: int
    end_us: int  # after the config epoch
    value: Any  # the window in the form of modd_plan.derive
    subscribers: tuple[str, ...]

    @property
    def start_us(self) -> int:
        return self.end_us - period_us(self.stream)


@dataclass
class _Route:
    sources: tuple[Source, ...]  # () when the stream is sent itself
    subscribers: list[str]


@dataclass(frozen=True)
class _Due:
    """A route as :meth:`FanOut.on_slot` walks it: everything it needs resolved
    once, when the routes change, not at every slot."""

    stream: StreamKey
    sid: int  # the sent stream's id; -1 when derived
    sources: tuple[tuple[int, int, str], ...]  # (stream id, factor, aggregation)
    subscribers: tuple[str, ...]


class FanOut:
    """Windows of the routed streams from the windows of the sent ones.

    ``sent`` lists the sent streams in stream-id order. Thread-safe: the link
    thread calls :meth:`on_slot` while zenoh threads add and remove routes.
    The routes are grouped by period once per change (:meth:`_rebuild`), so a
    slot costs one modulo per distinct routed period plus the streams due.
    """

    def __init__(self, sent: Sequence[StreamKey]) -> None:
        self._ids = {s: i for i, s in enumerate(sent)}
        self._periods = [period_us(s) for s in sent]
        self._history: list[deque[tuple[int, Any]]] = [deque() for _ in sent]
        self._keep = [0] * len(sent)
        self._routes: dict[StreamKey, _Route] = {}
        self._by_period: list[tuple[int, list[_Due]]] = []
        self._lock = threading.Lock()

    @property
    def sent(self) -> tuple[StreamKey, ...]:
        return tuple(self._ids)

    def route(self, stream: StreamKey, sources: Iterable[Source], subscriber: str) -> None:
        """Deliver ``stream`` to ``subscriber``. ``sources`` is empty for a sent
        stream, else the derivation (as the planner gives it)."""
        srcs = tuple(sources)
        if srcs and len(srcs) == 1 and srcs[0].stream == stream and srcs[0].factor == 1:
            srcs = ()
        for src in srcs or (Source(stream, 1),):
            if src.stream not in self._ids:
                raise ValueError(f"{src.stream.key} is not sent in the running plan")
        period_us(stream)  # a period the wire cannot express fails here, not per slot
        with self._lock:
            route = self._routes.setdefault(stream, _Route(srcs, []))
            if subscriber not in route.subscribers:
                route.subscribers.append(subscriber)
            self._retain()

    def unroute(self, subscriber: str) -> bool:
        """Stop delivering anything to ``subscriber``; False if it had nothing."""
        found = False
        with self._lock:
            for stream, route in list(self._routes.items()):
                if subscriber in route.subscribers:
                    route.subscribers.remove(subscriber)
                    found = True
                if not route.subscribers:
                    del self._routes[stream]
            self._retain()
        return found

    def routes(self) -> dict[str, tuple[str, ...]]:
        """Stream key -> subscribers, for status and tests."""
        with self._lock:
            return {s.key: tuple(r.subscribers) for s, r in self._routes.items()}

    def _retain(self) -> None:
        keep = [0] * len(self._periods)
        for route in self._routes.values():
            for src in route.sources:
                sid = self._ids[src.stream]
                keep[sid] = max(keep[sid], src.factor)
        self._keep = keep
        for sid, hist in enumerate(self._history):
            while len(hist) > keep[sid]:
                hist.popleft()
        self._rebuild()

    def _rebuild(self) -> None:
        """Group the routes by period (in route order within a period)."""
        groups: dict[int, list[_Due]] = {}
        for stream, route in self._routes.items():
            due = _Due(
                stream,
                -1 if route.sources else self._ids[stream],
                tuple((self._ids[s.stream], s.factor, s.stream.aggregation) for s in route.sources),
                tuple(route.subscribers),
            )
            groups.setdefault(period_us(stream), []).append(due)
        self._by_period = list(groups.items())

    def on_slot(self, slot: int, date_us: int, windows: Mapping[int, Any]) -> list[Output]:
        """Take the windows of one DATA slot (stream id -> window, for the
        streams due at ``date_us``) and return the windows due for delivery."""
        with self._lock:
            keep, history, periods = self._keep, self._history, self._periods
            for sid, window in windows.items():
                if keep[sid]:
                    hist = history[sid]
                    hist.append((date_us // periods[sid], window))
                    if len(hist) > keep[sid]:
                        hist.popleft()
            out: list[Output] = []
            for period, dues in self._by_period:
                if date_us % period:
                    continue
                for due in dues:
                    if due.sid >= 0:
                        value = windows.get(due.sid, _INCOMPLETE)
                    else:
                        value = self._derive(due, date_us)
                    if value is not _INCOMPLETE:
                        out.append(Output(due.stream, slot, date_us, value, due.subscribers))
            return out

    def _derive(self, due: _Due, date_us: int) -> Any:
        parts: list[tuple[str, list[Any]]] = []
        for sid, factor, aggregation in due.sources:
            windows = self._tail(sid, factor, date_us // self._periods[sid])
            if windows is None:
                return _INCOMPLETE
            parts.append((aggregation, windows))
        return derive_value(due.stream.aggregation, parts)

    def _tail(self, sid: int, factor: int, last: int) -> list[Any] | None:
        """The windows ``last - factor + 1 .. last`` of a sent stream, or None
        when one is missing. The history is kept in slot order, so they are
        its last ``factor`` entries when those are numbered right."""
        hist = self._history[sid]
        if len(hist) < factor:
            return None
        tail = list(itertools.islice(hist, len(hist) - factor, None))
        if (
            tail[0][0] == last - factor + 1
            and tail[-1][0] == last
            and all(b[0] - a[0] == 1 for a, b in itertools.pairwise(tail))
        ):
            return [w for _, w in tail]
        wanted = range(last - factor + 1, last + 1)  # out of order (never seen): look up
        have = {i: w for i, w in hist if i in wanted}
        return [have[i] for i in wanted] if len(have) == factor else None


_INCOMPLETE = object()
