"""Event subscriptions, ON_CHANGE and THRESHOLD: the reference definition
(docs/planning.md, "Event subscriptions"). Their codes and the bound of a
window's events are in wire.json (group ``events``); the C++ PubBroker's
detector (runtime/cpp/include/modd/broker/events.hpp) is checked against the
vectors this module writes (contracts/vectors/events.json, gen_events.py).

An event subscription has a period P like any window: the PubBroker reports,
per window [E + (j-1)P, E + jP) of the running config (epoch E), the events of
the samples stamped inside it, each with its sample time, at most N of them
(the subscription's worst case, declared or derived). Whether a sample is an
event depends on the samples before it, from the config's first sample on
(the detector's state carries over from window to window):

- ON_CHANGE(d): the first sample is an event; a later one is an event when it
  differs from the last event's value by more than the deadband,
  ``|x - last| > d`` (absolute) or ``|x - last| > d * |last|`` (relative, d a
  fraction). Then it becomes ``last``.
- THRESHOLD(L, h, crossing): the first sample sets the side (above when
  ``x > L``, else below) and is no event. Below, a sample ``x > L + h`` goes
  above (an UP crossing); above, a sample ``x < L - h`` goes below (a DOWN
  crossing). The side changes whatever the subscription's crossings; only the
  crossings asked for (UP, DOWN or BOTH) are events. So between two events of
  one direction the signal went at least ``2h`` the other way (hysteresis).

Beyond N events in one window the newest replaces the window's last kept one
and ``coalesced`` counts the events it replaced: a window delivers its first
N - 1 events as they happened, its newest one, and how many were coalesced;
nothing is dropped silently. Comparisons are in double precision (an int
topic's samples as doubles, exact to 2**53); the ingress refuses non-finite
samples, so none reaches a detector.

>>> spec = EventSpec(EventKind.THRESHOLD, max_events=2, level=5.0, hysteresis=0.5)
>>> d = Detector(spec)
>>> [d.feed(x) for x in [4.0, 5.2, 5.6, 5.0, 4.6, 4.4, 6.0]]
[None, None, 1, None, None, 2, 1]
>>> w = windows(spec, [(t, x) for t, x in enumerate([4.0, 5.6, 4.4, 5.6, 4.4])], 0, 10)
>>> w[0].events, w[0].coalesced
([(1, 5.6), (4, 4.4)], 2)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

from .link_wire_gen import MAX_EVENTS, Crossing, DeadbandMode, EventKind

__all__ = ["Detector", "EventSpec", "EventWindow", "Crossing", "DeadbandMode", "EventKind"]


@dataclass(frozen=True)
class EventSpec:
    """One event subscription's definition and its bound N (``max_events``)."""

    kind: EventKind
    max_events: int
    deadband: float = 0.0
    mode: DeadbandMode = DeadbandMode.ABSOLUTE
    level: float = 0.0
    hysteresis: float = 0.0
    crossing: Crossing = Crossing.BOTH

    def __post_init__(self) -> None:
        if not 1 <= self.max_events <= MAX_EVENTS:
            raise ValueError(f"at most N events: N from 1 to {MAX_EVENTS}, not {self.max_events}")
        if not (self.deadband >= 0 and self.hysteresis >= 0):  # NaN too
            raise ValueError("a deadband or hysteresis is a finite number >= 0")


class Detector:
    """Which samples are events: the state carried from sample to sample."""

    def __init__(self, spec: EventSpec) -> None:
        self.spec = spec
        self.last: float | None = None  # ON_CHANGE: the last event's value
        self.above: bool | None = None  # THRESHOLD: the side, None before the first sample

    def feed(self, x: float) -> int | None:
        """None when ``x`` is no event; else the crossing (Crossing.UP or
        DOWN) of a THRESHOLD, 0 for ON_CHANGE."""
        x = float(x)
        if self.spec.kind == EventKind.ON_CHANGE:
            return self._on_change(x)
        return self._threshold(x)

    def _on_change(self, x: float) -> int | None:
        last, s = self.last, self.spec
        if last is not None:
            band = s.deadband * abs(last) if s.mode == DeadbandMode.RELATIVE else s.deadband
            if not abs(x - last) > band:
                return None
        self.last = x
        return 0

    def _threshold(self, x: float) -> int | None:
        s = self.spec
        if self.above is None:
            self.above = x > s.level
            return None
        if not self.above and x > s.level + s.hysteresis:
            self.above, crossing = True, Crossing.UP
        elif self.above and x < s.level - s.hysteresis:
            self.above, crossing = False, Crossing.DOWN
        else:
            return None
        return int(crossing) if s.crossing & crossing else None


@dataclass
class EventWindow:
    """One window's events, (sample time, value), at most N, and how many
    more were coalesced into its last one."""

    events: list[tuple[int, float]] = field(default_factory=list)
    coalesced: int = 0

    def add(self, t: int, x: float, bound: int) -> None:
        """One more event, kept within ``bound``: beyond it, the newest
        replaces the last kept one and is counted."""
        if len(self.events) < bound:
            self.events.append((t, x))
        else:
            self.events[-1] = (t, x)
            self.coalesced += 1

    @property
    def present(self) -> bool:
        """Whether the window has an event (an empty one is absent on the link)."""
        return bool(self.events)


def windows(
    spec: EventSpec, samples: Iterable[tuple[int, float]], epoch: int, period: int
) -> list[EventWindow]:
    """The windows, from the one holding ``epoch`` to the last sample's, of
    time-ordered ``(t, x)`` samples (samples before ``epoch`` are skipped:
    the state starts with the config)."""
    detector = Detector(spec)
    out: list[EventWindow] = []
    for t, x in samples:
        if t < epoch:
            continue
        j = (t - epoch) // period
        while len(out) <= j:
            out.append(EventWindow())
        if detector.feed(x) is not None:
            out[j].add(t, float(x), spec.max_events)
    return out


def implied(spec: EventSpec, samples: Sequence[tuple[int, float]]) -> list[tuple[int, float]]:
    """Every event the definition implies, unbounded (the oracle of a
    delivery test: a window's events are these, coalesced beyond N)."""
    detector = Detector(spec)
    return [(t, float(x)) for t, x in samples if detector.feed(x) is not None]


# -- Labels: an event stream's name in the plan, CONFIG's reader and delivered
# values (modd_contracts.labels), ``ON_CHANGE(0.5)``, ``ON_CHANGE(5%, 4)``,
# ``THRESHOLD(DOWN 5, 0.2, 2)``: the definition's parameters, then N when declared.

ON_CHANGE, THRESHOLD = "ON_CHANGE", "THRESHOLD"
#: The aggregation table's event subscriptions.
EVENT_AGGREGATIONS = frozenset({ON_CHANGE, THRESHOLD})
_CROSSINGS = {"up": Crossing.UP, "down": Crossing.DOWN, "both": Crossing.BOTH}


def _num(x: float) -> str:
    return repr(float(x)).removesuffix(".0")


@dataclass(frozen=True)
class EventLabel:
    """An event stream's parameters; ``max_events`` None when derived."""

    spec: EventSpec
    declared: bool
    percent: float | None = field(default=None, compare=False)  # relative, as written

    @property
    def max_events(self) -> int | None:
        return self.spec.max_events if self.declared else None

    def text(self) -> str:
        s = self.spec
        n = f", {s.max_events}" if self.declared else ""
        if s.kind == EventKind.ON_CHANGE:
            d = _num(self.percent) + "%" if self.percent is not None else _num(s.deadband)
            return f"{ON_CHANGE}({d}{n})"
        h = f", {_num(s.hysteresis)}" if n or s.hysteresis else ""
        return f"{THRESHOLD}({s.crossing.name} {_num(s.level)}{h}{n})"


def of_subscriber(sub: Any) -> EventLabel:
    """The parameters of a model's ON_CHANGE or THRESHOLD subscriber (the
    validator has checked them)."""
    n = sub.get("maxEvents")
    bound = int(n) if n is not None else MAX_EVENTS
    if sub["aggregation"] == ON_CHANGE:
        relative = "deadbandPercent" in sub
        d = float(sub["deadbandPercent"]) / 100 if relative else float(sub.get("deadband", 0.0))
        mode = DeadbandMode.RELATIVE if relative else DeadbandMode.ABSOLUTE
        spec = EventSpec(EventKind.ON_CHANGE, bound, deadband=d, mode=mode)
        return EventLabel(spec, n is not None, float(sub["deadbandPercent"]) if relative else None)
    spec = EventSpec(
        EventKind.THRESHOLD,
        bound,
        level=float(sub["level"]),
        hysteresis=float(sub.get("hysteresis", 0.0)),
        # An alert's stream reports both crossings: the way back clears it (the
        # model's crossing names the alert's direction; docs/dsl.md, "Alerts").
        crossing=Crossing.BOTH if sub.get("alert") else _CROSSINGS[sub.get("crossing", "both")],
    )
    return EventLabel(spec, n is not None)


def parse_label(text: str) -> EventLabel:
    """An event label's parameters; ValueError naming the text when it is none.

    >>> parse_label("THRESHOLD(DOWN 5, 0.2, 2)").text(), parse_label("ON_CHANGE(5%)").spec.deadband
    ('THRESHOLD(DOWN 5, 0.2, 2)', 0.05)
    """
    name, _, rest = text.partition("(")
    parts = [p.strip() for p in rest.removesuffix(")").split(",")] if rest.endswith(")") else []
    try:
        sub: dict[str, Any] = {"aggregation": name}
        if name == ON_CHANGE and 1 <= len(parts) <= 2:
            key = "deadbandPercent" if parts[0].endswith("%") else "deadband"
            sub[key] = float(parts[0].removesuffix("%"))
        elif name == THRESHOLD and 1 <= len(parts) <= 3:
            crossing, _, level = parts[0].partition(" ")
            sub |= {"crossing": crossing.lower(), "level": float(level)}
            sub["hysteresis"] = float(parts[1]) if len(parts) > 1 else 0.0
            if crossing != crossing.upper() or sub["crossing"] not in _CROSSINGS:
                raise ValueError(crossing)
        else:
            raise ValueError(text)
        limit = 2 if name == ON_CHANGE else 3
        if len(parts) == limit:
            if not parts[-1].isdigit():
                raise ValueError(parts[-1])
            sub["maxEvents"] = int(parts[-1])
        out = of_subscriber(sub)
    except (ValueError, KeyError) as exc:
        raise ValueError(f"unknown aggregation {text!r} ({exc})") from None
    if not all(map(math.isfinite, (out.spec.deadband, out.spec.level, out.spec.hysteresis))):
        raise ValueError(f"unknown aggregation {text!r} (not a finite number)")
    return out
