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


class FanOut:
    """Windows of the routed streams from the windows of the sent ones.

    ``sent`` lists the sent streams in stream-id order. Thread-safe: the link
    thread calls :meth:`on_slot` while zenoh threads add and remove routes.
    """

    def __init__(self, sent: Sequence[StreamKey]) -> None:
        self._ids = {s: i for i, s in enumerate(sent)}
        self._periods = [period_us(s) for s in sent]
        self._history: list[deque[tuple[int, Any]]] = [deque() for _ in sent]
        self._keep = [0] * len(sent)
        self._routes: dict[StreamKey, _Route] = {}
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

    def on_slot(self, slot: int, date_us: int, windows: Mapping[int, Any]) -> list[Output]:
        """Take the windows of one DATA slot (stream id -> window, for the
        streams due at ``date_us``) and return the windows due for delivery."""
        with self._lock:
            for sid, window in windows.items():
                if self._keep[sid]:
                    hist = self._history[sid]
                    hist.append((date_us // self._periods[sid], window))
                    if len(hist) > self._keep[sid]:
                        hist.popleft()
            out: list[Output] = []
            for stream, route in self._routes.items():
                if date_us % period_us(stream):
                    continue
                if route.sources:
                    value = self._derive(stream, route.sources, date_us)
                else:
                    value = windows.get(self._ids[stream], _INCOMPLETE)
                if value is not _INCOMPLETE:
                    out.append(Output(stream, slot, date_us, value, tuple(route.subscribers)))
            return out

    def _derive(self, stream: StreamKey, sources: tuple[Source, ...], date_us: int) -> Any:
        parts: list[tuple[str, list[Any]]] = []
        for src in sources:
            sid = self._ids[src.stream]
            last = date_us // self._periods[sid]
            wanted = range(last - src.factor + 1, last + 1)
            have = {i: w for i, w in self._history[sid] if i in wanted}
            if len(have) != src.factor:
                return _INCOMPLETE
            parts.append((src.stream.aggregation, [have[i] for i in wanted]))
        return derive_value(stream.aggregation, parts)


_INCOMPLETE = object()


def window_of(value: Any, aggregation: str, value_type: str) -> Any:
    """A decoded DATA value (:class:`modd.link.frames.Value`) as a window in
    the form of :mod:`modd_plan.derive` (``None`` when marked absent)."""
    floats = value_type in ("float32", "float64")
    if not value.present:
        return None
    if aggregation == "AVERAGE":
        return (value.number, value.count) if value.count else None
    if aggregation == "COUNT":
        return value.count
    if aggregation == "ALL":
        return [bool(x) for x in value.samples] if value_type == "bool" else list(value.samples)
    if aggregation == "SUM":
        return value.number if floats else value.integer
    if floats:
        return value.number
    return bool(value.integer) if value_type == "bool" else value.integer
