"""Fan-out: from the windows of the sent streams in one DATA slot to the
windows of every stream a subscriber listens to, derived streams included.

A derived stream of period ``k·P`` has, for each of its windows, the value
:func:`modd_plan.derive.derive_value` over the ``k`` source windows that tile
it, put together by window index (:mod:`.derivation`): it is delivered when
its last source window arrives, whatever the order they arrive in. A derived
window whose source windows do not all arrive (the link was down for part of
it and the NACKs gave up, or the subscription began inside it) is *not*
delivered live: a MIN over half a window would be a wrong MIN; it is a gap for
backfill.

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
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from modd_model.numbers import MICROS_PER_SECOND
from modd_plan.derive import derive_value
from modd_plan.streams import Source, StreamKey

from .derivation import Assembly


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
    assembly: Assembly | None = None  # the derived windows being put together


@dataclass(frozen=True)
class _Derived:
    """A derived route as :meth:`FanOut.on_slot` walks it, resolved once per
    change of the routes (:meth:`FanOut._rebuild`), not at every slot."""

    stream: StreamKey
    period: int  # µs
    aggregations: tuple[str, ...]  # of the sources, in the derivation's order
    assembly: Assembly
    subscribers: tuple[str, ...]


class FanOut:
    """Windows of the routed streams from the windows of the sent ones.

    ``sent`` lists the sent streams in stream-id order. Thread-safe: the link
    thread calls :meth:`on_slot` while zenoh threads add and remove routes.
    A derived window is put together by window index (:mod:`.derivation`), so
    a source window that arrives late (a NACK's resend) still completes it,
    once. The routes are indexed by sent stream once per change
    (:meth:`_rebuild`), so a slot costs a look-up per window it carries.
    """

    def __init__(self, sent: Sequence[StreamKey]) -> None:
        self._ids = {s: i for i, s in enumerate(sent)}
        self._periods = [period_us(s) for s in sent]
        self._routes: dict[StreamKey, _Route] = {}
        self._direct: dict[int, list[tuple[StreamKey, tuple[str, ...]]]] = {}
        self._derived: dict[int, list[_Derived]] = {}
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
        period = period_us(stream)  # a period the wire cannot express fails here, not per slot
        with self._lock:
            route = self._routes.get(stream)
            if route is None:
                assembly = None
                if srcs:
                    assembly = Assembly(
                        tuple((self._ids[s.stream], s.factor) for s in srcs), period
                    )
                route = self._routes[stream] = _Route(srcs, [], assembly)
            if subscriber not in route.subscribers:
                route.subscribers.append(subscriber)
            self._rebuild()

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
            self._rebuild()
        return found

    def routes(self) -> dict[str, tuple[str, ...]]:
        """Stream key -> subscribers, for status and tests."""
        with self._lock:
            return {s.key: tuple(r.subscribers) for s, r in self._routes.items()}

    def pending(self) -> int:
        """Partial derived windows held (bounded: :data:`.derivation.MAX_PENDING` a route)."""
        with self._lock:
            return sum(r.assembly.pending for r in self._routes.values() if r.assembly)

    def _rebuild(self) -> None:
        """Index the routes by the sent stream they take windows from (in route order)."""
        direct: dict[int, list[tuple[StreamKey, tuple[str, ...]]]] = {}
        derived: dict[int, list[_Derived]] = {}
        for stream, route in self._routes.items():
            subs = tuple(route.subscribers)
            if route.assembly is None:
                direct.setdefault(self._ids[stream], []).append((stream, subs))
                continue
            d = _Derived(
                stream,
                period_us(stream),
                tuple(s.stream.aggregation for s in route.sources),
                route.assembly,
                subs,
            )
            for sid, _ in route.assembly.sources:
                derived.setdefault(sid, []).append(d)
        self._direct, self._derived = direct, derived

    def on_slot(self, slot: int, date_us: int, windows: Mapping[int, Any]) -> list[Output]:
        """Take the windows of one DATA slot (stream id -> window, for the
        streams due at ``date_us``, in any order of slots: a late slot is
        welcome) and return the windows this completes for delivery."""
        with self._lock:
            out: list[Output] = []
            for sid, window in windows.items():
                for stream, subs in self._direct.get(sid, ()):
                    out.append(Output(stream, slot, date_us, window, subs))
                derived = self._derived.get(sid)
                if not derived:
                    continue
                index = date_us // self._periods[sid]
                for d in derived:
                    for j, parts in d.assembly.add(sid, index, window):
                        value = derive_value(
                            d.stream.aggregation, list(zip(d.aggregations, parts, strict=True))
                        )
                        out.append(Output(d.stream, slot, j * d.period, value, d.subscribers))
            return out
