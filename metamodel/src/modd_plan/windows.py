"""Windows in and out of the SubBroker: the one place that turns a decoded
link value into a window of :mod:`modd_plan.derive` (:func:`window_of`) and a
window into the delivered value's ``(value, count)`` (:func:`split_window`,
docs/subbroker.md, "Delivered values"). Beside :mod:`.derive`, whose window
forms both follow.

>>> split_window("AVERAGE", (2.5, 4)), split_window("MIN", None)
((2.5, 4), (None, None))
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol

from modd_contracts import aggregations_gen as agg
from modd_contracts import labels

Scalar = float | int | bool
Value = Scalar | list[Scalar] | None


class LinkValue(Protocol):
    """One stream's value in a DATA frame (:class:`modd.link.frames.Value`)."""

    present: bool
    number: float
    integer: int
    count: int
    samples: Any
    times_us: Any
    coalesced: int


class EventsWindow(NamedTuple):
    """An event stream's window (ON_CHANGE, THRESHOLD): its events' values and
    times (µs after the window's start) and the events coalesced beyond N."""

    values: list[Scalar]
    times_us: list[int]
    coalesced: int

    def event_ns(self, start_ns: int) -> list[int]:
        """Each event's time, ns since the Unix epoch on the drone's clock."""
        return [start_ns + t * 1000 for t in self.times_us]


def window_of(value: LinkValue, aggregation: str, value_type: str) -> Any:
    """A decoded DATA value as a window in the form of :mod:`modd_plan.derive`
    (``None`` when marked absent); an event stream's is an :class:`EventsWindow`."""
    result = labels.spec(aggregation).result[value_type]  # the value's wire type
    if not value.present:
        return None
    if labels.is_event(aggregation):
        values = [bool(x) for x in value.samples] if value_type == "bool" else list(value.samples)
        return EventsWindow(values, list(value.times_us), value.coalesced)
    if aggregation == agg.AVERAGE:
        return (value.number, value.count) if value.count else None
    if aggregation == agg.COUNT:
        return value.count
    if aggregation == agg.ALL:
        return [bool(x) for x in value.samples] if value_type == "bool" else list(value.samples)
    if result in ("float32", "float64"):
        return value.number
    return bool(value.integer) if result == "bool" else value.integer


def split_window(aggregation: str, window: Any) -> tuple[Value, int | None]:
    """``(value, count)`` of a window, as the delivered value carries them:
    ``count`` for the aggregations that have one (AVERAGE, COUNT, ALL)."""
    if aggregation == agg.AVERAGE:
        return (None, 0) if window is None else (float(window[0]), int(window[1]))
    if aggregation == agg.COUNT:
        count = int(window or 0)
        return count, count
    if aggregation == agg.ALL:
        samples = list(window or [])
        return samples, len(samples)
    if isinstance(window, EventsWindow):
        return list(window.values), len(window.values) + window.coalesced
    return window, None
