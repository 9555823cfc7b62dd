"""Streams: what the subscribers ask for, which of it crosses the link, and
what the SubBroker derives from what.

A *stream* is (topic, aggregation, window period). Identical streams asked by
several subscribers are one stream. *Sent* streams get ids ``0..k-1`` ordered
by topic declaration order, then aggregation in the schema's enum order, then
period ascending (the shared contract with the link, docs/protocol.md).

Choice of the sent set, per topic: start from every requested stream sent,
then walk the streams from the most expensive on the link (value bytes per
second) and drop each one that stays derivable (:mod:`modd_plan.derive`) from
the streams still sent. Derivability only grows with the sent set, so one pass
is enough: a stream that cannot be dropped now never can be later.
Then try, one at a time, adding a helper ALL stream (nobody asked for it) at
each requested period of the topic where it could pay (it costs less than
the sent streams at multiples of its period): when few samples fall in a
window, the raw samples can cost less than the several aggregates they
replace. The cheapest of these sets wins (ties: no helper).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache
from typing import Any

from modd_contracts.aggregations import NAMES
from modd_model.numbers import fraction_to_decimal, to_fraction

from .derive import PAIR_SOURCE_RULES, SINGLE_SOURCE_RULES

#: The aggregation table's names in wire-code order (the tie-break of stream ids).
AGGREGATIONS: tuple[str, ...] = NAMES


@dataclass(frozen=True)
class StreamKey:
    """(topic, aggregation, window period in seconds).

    >>> StreamKey("usv.a.x", "AVERAGE", Fraction(1, 4)).key
    'usv.a.x/AVERAGE/0.25'
    """

    topic: str
    aggregation: str
    period: Fraction

    def __hash__(self) -> int:
        # Fraction.__hash__ computes a modular inverse; numerator and
        # denominator (always normalised) identify the period as well.
        return hash((self.topic, self.aggregation, self.period.numerator, self.period.denominator))

    @property
    def key(self) -> str:
        return f"{self.topic}/{self.aggregation}/{decimal_of(self.period)}"

    @classmethod
    def parse(cls, key: str) -> StreamKey:
        """Inverse of :attr:`key`."""
        topic, aggregation, period = key.rsplit("/", 2)
        return cls(topic, aggregation, to_fraction(period))


@dataclass(frozen=True)
class Source:
    """A sent stream a derived stream is computed from, ``factor`` windows at a time."""

    stream: StreamKey
    factor: int


@dataclass(frozen=True)
class PlannedStream:
    """A requested (or helper) stream with its fate: sent with an id, or derived."""

    stream: StreamKey
    id: int | None
    sources: tuple[Source, ...]
    subscribers: tuple[str, ...]

    @property
    def sent(self) -> bool:
        return self.id is not None


def requested_streams(model: Mapping[str, Any]) -> dict[StreamKey, list[str]]:
    """Each distinct stream the subscribers ask for, with its subscribers in
    model order."""
    out: dict[StreamKey, list[str]] = {}
    for sub in model.get("subscribers", []):
        key = StreamKey(sub["topic"], sub["aggregation"], period_of(sub["periodS"]))
        out.setdefault(key, []).append(sub["name"])
    return out


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def decimal_of(value: Fraction) -> str:
    """``fraction_to_decimal``, memoised: a plan repeats few distinct periods."""
    return fraction_to_decimal(value)


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def period_of(text: str) -> Fraction:
    """``to_fraction``, memoised: a model repeats few distinct periods."""
    return to_fraction(text)


def _factor(target: StreamKey, source: StreamKey) -> int | None:
    """target.period / source.period if whole (integer arithmetic only)."""
    a, b = target.period, source.period
    num, den = a.numerator * b.denominator, a.denominator * b.numerator
    return num // den if num % den == 0 else None


def find_sources(target: StreamKey, sent: Iterable[StreamKey]) -> tuple[Source, ...] | None:
    """How ``target`` is obtained from ``sent`` streams: ``(Source(target, 1),)``
    if it is sent itself, the preferred derivation otherwise, ``None`` if it
    cannot be computed. Preference: the rule order of
    :data:`~modd_plan.derive.SINGLE_SOURCE_RULES`, then the fewest windows to
    merge (the longest source period), then the pair rule SUM + COUNT."""
    candidates = [s for s in sent if s.topic == target.topic]
    if target in candidates:
        return (Source(target, 1),)
    best: tuple[int, int, StreamKey] | None = None
    for s in candidates:
        if s.aggregation not in SINGLE_SOURCE_RULES[target.aggregation]:
            continue
        factor = _factor(target, s)
        if factor is None:
            continue
        rank = (SINGLE_SOURCE_RULES[target.aggregation].index(s.aggregation), factor, s)
        if best is None or rank[:2] < best[:2]:
            best = rank
    if best is not None:
        return (Source(best[2], best[1]),)
    return _pair_sources(target, candidates)


def _pair_sources(target: StreamKey, candidates: Sequence[StreamKey]) -> tuple[Source, ...] | None:
    pair = PAIR_SOURCE_RULES.get(target.aggregation)
    if pair is None:
        return None
    chosen: list[Source] = []
    for aggregation in pair:
        options = [
            (f, s)
            for s in candidates
            if s.aggregation == aggregation and (f := _factor(target, s)) is not None
        ]
        if not options:
            return None
        factor, stream = min(options, key=lambda o: o[0])
        chosen.append(Source(stream, factor))
    return tuple(chosen)


def stream_order(
    topic_index: Mapping[str, int],
) -> Callable[[StreamKey], tuple[int, int, Fraction]]:
    """Sort key of the contract: topic declaration order, aggregation enum
    order, period ascending."""

    def order(s: StreamKey) -> tuple[int, int, Fraction]:
        return (topic_index[s.topic], AGGREGATIONS.index(s.aggregation), s.period)

    return order


def _drop_derivable(
    required: Sequence[StreamKey],
    cost_per_s: Callable[[StreamKey], float],
    helper: StreamKey | None = None,
) -> list[StreamKey]:
    """The one-pass drop over ``required`` (+ ``helper``, always kept): the
    most expensive first (ties: longest period, then aggregation order)."""
    streams = sorted(
        required, key=lambda s: (-cost_per_s(s), -s.period, AGGREGATIONS.index(s.aggregation))
    )
    kept = [True] * len(streams)
    extra = [helper] if helper is not None else []
    for i in range(len(streams)):
        kept[i] = False
        rest = [s for s, k in zip(streams, kept, strict=True) if k] + extra
        dropped = [s for s, k in zip(streams, kept, strict=True) if not k]
        if any(find_sources(r, rest) is None for r in dropped):
            kept[i] = True
    return [s for s, k in zip(streams, kept, strict=True) if k] + extra


def _choose_for_topic(
    streams: Sequence[StreamKey], cost_per_s: Callable[[StreamKey], float]
) -> list[StreamKey]:
    best = _drop_derivable(streams, cost_per_s)
    best_cost = sum(cost_per_s(s) for s in best)
    for period in sorted({s.period for s in streams}):
        helper = StreamKey(streams[0].topic, "ALL", period)
        if helper in streams:
            continue
        replaceable = sum(cost_per_s(s) for s in best if _factor(s, helper) is not None)
        if cost_per_s(helper) >= replaceable:
            continue  # it cannot pay for itself
        trial = _drop_derivable(streams, cost_per_s, helper)
        trial_cost = sum(cost_per_s(s) for s in trial)
        if trial_cost < best_cost:
            best, best_cost = trial, trial_cost
    return best


def choose_sent(
    requested: Iterable[StreamKey], cost_per_s: Callable[[StreamKey], float]
) -> set[StreamKey]:
    """The sent set: per topic, the cheapest of the requested streams minus
    those derivable from the rest, with or without one helper ALL stream."""
    by_topic: dict[str, list[StreamKey]] = {}
    for s in requested:
        by_topic.setdefault(s.topic, []).append(s)
    sent: set[StreamKey] = set()
    for streams in by_topic.values():
        sent.update(_choose_for_topic(streams, cost_per_s) if len(streams) > 1 else streams)
    return sent


def plan_streams(
    requested: Mapping[StreamKey, Sequence[str]],
    topic_index: Mapping[str, int],
    cost_per_s: Callable[[StreamKey], float],
) -> tuple[PlannedStream, ...]:
    """Every requested stream, in contract order, with its id if sent or its
    sources if derived."""
    sent = choose_sent(requested, cost_per_s)
    sent_by_topic: dict[str, list[StreamKey]] = {}
    for s in sent:
        sent_by_topic.setdefault(s.topic, []).append(s)
    order = stream_order(topic_index)
    ids = {s: i for i, s in enumerate(sorted(sent, key=order))}
    out: list[PlannedStream] = []
    for s in sorted(set(requested) | sent, key=order):
        subscribers = tuple(requested.get(s, ()))
        if s in ids:
            out.append(PlannedStream(s, ids[s], (), subscribers))
        else:
            sources = find_sources(s, sent_by_topic[s.topic])
            assert sources is not None  # choose_sent keeps every stream derivable
            out.append(PlannedStream(s, None, sources, subscribers))
    return tuple(out)
