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
from functools import cached_property, lru_cache
from typing import Any

from modd_contracts import aggregations_gen as agg
from modd_contracts import labels
from modd_contracts.aggregations_gen import NAMES
from modd_contracts.labels import ByLabel, RankByLabel
from modd_model.numbers import fraction_to_decimal, to_fraction

from .derive import PAIR_SOURCE_RULES, SINGLE_SOURCE_RULES

#: The aggregation table's names in wire-code order (the tie-break of stream ids).
AGGREGATIONS: tuple[str, ...] = NAMES
#: A label's place in it: PERCENTILE(p) after PERCENTILE's code, by p.
_AGG_INDEX = RankByLabel({a: float(agg.BY_NAME[a].code * 1000) for a in AGGREGATIONS})


@dataclass(frozen=True, init=False)
class StreamKey:
    """(topic, aggregation, window period in seconds).

    >>> StreamKey("usv.a.x", "AVERAGE", Fraction(1, 4)).key
    'usv.a.x/AVERAGE/0.25'
    """

    topic: str
    aggregation: str
    period: Fraction

    def __init__(
        self, topic: str, aggregation: str, period: Fraction, nd: tuple[int, int] | None = None
    ) -> None:
        # All attributes written into the instance's __dict__ at once (a
        # frozen dataclass's __init__ sets each through object.__setattr__).
        # Fraction.__hash__ computes a modular inverse and its numerator and
        # denominator are properties: both are read once here (or given as
        # ``nd``). The derived ones are not fields: equality, repr and order
        # stay those of (topic, aggregation, period).
        if nd is None:
            nd = (period.numerator, period.denominator)
        self.__dict__.update(
            topic=topic,
            aggregation=aggregation,
            period=period,
            _nd=nd,
            # sort keys: (float, Fraction) orders as the Fraction, the float first
            _sort_period=(nd[0] / nd[1], period),
            _hash=hash((topic, aggregation, *nd)),
            # the key text now: a plan reads every key, and the instance's
            # own attribute then hides the cached_property below (3.11's
            # takes a lock on its first read)
            key=f"{topic}/{aggregation}/{_decimal_of(*nd)}",
        )

    def __hash__(self) -> int:
        return self._hash  # type: ignore[attr-defined, no-any-return]

    def __reduce__(self) -> tuple[type[StreamKey], tuple[str, str, Fraction]]:
        # rebuilt, not copied: a string's hash differs between processes
        return (StreamKey, (self.topic, self.aggregation, self.period))

    @cached_property
    def key(self) -> str:
        # set by __init__ (a plain attribute of the instance, which hides
        # this non-data descriptor); computed here only for an instance made
        # without __init__
        return f"{self.topic}/{self.aggregation}/{_decimal_of(*self._nd)}"  # type: ignore

    @classmethod
    def parse(cls, key: str) -> StreamKey:
        """Inverse of :attr:`key`."""
        topic, aggregation, period = key.rsplit("/", 2)
        return cls(topic, aggregation, to_fraction(period))


@dataclass(frozen=True, init=False)
class Source:
    """A sent stream a derived stream is computed from, ``factor`` windows at a time."""

    stream: StreamKey
    factor: int

    def __init__(self, stream: StreamKey, factor: int) -> None:
        # one dictionary update, not a frozen dataclass's setattr per field
        self.__dict__.update(stream=stream, factor=factor)


@dataclass(frozen=True, init=False)
class PlannedStream:
    """A requested (or helper) stream with its fate: sent with an id, or derived."""

    stream: StreamKey
    id: int | None
    sources: tuple[Source, ...]
    subscribers: tuple[str, ...]

    def __init__(
        self,
        stream: StreamKey,
        id: int | None,  # noqa: A002 (the field's name)
        sources: tuple[Source, ...],
        subscribers: tuple[str, ...],
    ) -> None:
        # one dictionary update, not a frozen dataclass's setattr per field
        self.__dict__.update(stream=stream, id=id, sources=sources, subscribers=subscribers)

    @property
    def sent(self) -> bool:
        return self.id is not None


def asked_streams(
    model: Mapping[str, Any],
) -> tuple[list[tuple[StreamKey, list[str]]], dict[str, StreamKey]]:
    """Each distinct stream the subscribers ask for, with its subscribers in
    model order (streams in the order first asked), and each subscriber's
    stream. One key object per distinct stream: texts of one period ("1",
    "1.0") give one stream. Found by (topic, aggregation, numerator,
    denominator) tuples, whose hash is C's, never by a StreamKey's."""
    by_text: dict[tuple[str, str, str], tuple[StreamKey, list[str]]] = {}
    by_stream: dict[tuple[str, str, int, int], tuple[StreamKey, list[str]]] = {}
    subscriptions: dict[str, StreamKey] = {}
    for sub in model.get("subscribers", []):
        text = (sub["topic"], labels.of_subscriber(sub), sub["periodS"])
        entry = by_text.get(text)
        if entry is None:
            period, nd = _period_parts(text[2])
            ident = (text[0], text[1], *nd)
            entry = by_stream.get(ident)
            if entry is None:
                entry = by_stream[ident] = (StreamKey(text[0], text[1], period, nd), [])
            by_text[text] = entry
        entry[1].append(sub["name"])
        subscriptions[sub["name"]] = entry[0]
    return list(by_stream.values()), subscriptions


def decimal_of(value: Fraction) -> str:
    """``fraction_to_decimal``, memoised: a plan repeats few distinct periods
    (keyed by numerator and denominator: hashing a Fraction is slow)."""
    return _decimal_of(value.numerator, value.denominator)


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def _decimal_of(numerator: int, denominator: int) -> str:
    return fraction_to_decimal(Fraction(numerator, denominator))


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def _period_parts(text: str) -> tuple[Fraction, tuple[int, int]]:
    """A period text's Fraction and its (numerator, denominator)."""
    period = period_of(text)
    return period, (period.numerator, period.denominator)


@lru_cache(maxsize=65_536)  # bounded: a long-running backend plans many models
def period_of(text: str) -> Fraction:
    """``to_fraction``, memoised: a model repeats few distinct periods."""
    return to_fraction(text)


def _factor(target: StreamKey, source: StreamKey) -> int | None:
    """target.period / source.period if whole (integer arithmetic only)."""
    (an, ad), (bn, bd) = target._nd, source._nd  # type: ignore[attr-defined]
    num, den = an * bd, ad * bn
    return num // den if num % den == 0 else None


def find_sources(target: StreamKey, sent: Iterable[StreamKey]) -> tuple[Source, ...] | None:
    """How ``target`` is obtained from ``sent`` streams: ``(Source(target, 1),)``
    if it is sent itself, the preferred derivation otherwise, ``None`` if it
    cannot be computed. Preference: the rule order of
    :data:`~modd_plan.derive.SINGLE_SOURCE_RULES`, then the fewest windows to
    merge (the longest source period), then the pair rule SUM + COUNT."""
    candidates = [s for s in sent if s.topic == target.topic]
    # ``target in candidates``, without the dataclass's __eq__ (two tuples
    # and a Fraction comparison per candidate): the topic is equal already
    agg_nd = (target.aggregation, target._nd)  # type: ignore[attr-defined]
    if any((s.aggregation, s._nd) == agg_nd for s in candidates):  # type: ignore[attr-defined]
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
) -> Callable[[StreamKey], tuple[int, float, tuple[float, Fraction]]]:
    """Sort key of the contract: topic declaration order, aggregation enum
    order, period ascending."""

    def order(s: StreamKey) -> tuple[int, float, tuple[float, Fraction]]:
        return (topic_index[s.topic], _AGG_INDEX[s.aggregation], s._sort_period)  # type: ignore[attr-defined]

    return order


#: Per aggregation: whether an ALL stream serves it alone, its single-source
#: rules' rank (find_sources' first preference), and which of its pair
#: groups an ALL stream joins.
_ALL_SERVES = ByLabel({a: agg.ALL in rules for a, rules in SINGLE_SOURCE_RULES.items()})
_RULE_RANK = ByLabel(
    {a: {x: k for k, x in enumerate(rules)} for a, rules in SINGLE_SOURCE_RULES.items()}
)
_ALL_PAIR = {
    a: [g for g, x in enumerate(pair) if x == agg.ALL] for a, pair in PAIR_SOURCE_RULES.items()
}


class _Relations:
    """Which of a topic's requested streams can serve which (the rules of
    :func:`find_sources`), computed once per topic in the drop order: the
    most expensive first (ties: longest period, then aggregation order).
    A helper ALL stream adds one column (:meth:`drop`), so trying several
    helpers costs a scan each, not the pairs again. Streams are handled by
    position (``costs[i]`` is the cost of ``streams[i]``, ``order[i]`` its
    position in ``required``), never hashed."""

    def __init__(self, required: Sequence[StreamKey], costs: Sequence[float]) -> None:
        # one sort of plain tuples: cost and period descending, aggregation
        # order ascending (its index negated); (aggregation, period) is
        # unique within a topic, so the position is never compared
        ranked = sorted(
            zip(
                costs,
                [s._sort_period for s in required],  # type: ignore
                [-_AGG_INDEX[s.aggregation] for s in required],
                range(len(required)),
                strict=True,
            ),
            reverse=True,
        )
        self.order = order = [t[3] for t in ranked]
        self.costs = [t[0] for t in ranked]
        self.streams = streams = [required[i] for i in order]
        nds: list[tuple[int, int]] = [s._nd for s in streams]  # type: ignore[attr-defined]
        self.nds = nds
        self.aggs = aggs = [s.aggregation for s in streams]
        # the streams of each aggregation (position, period): a target scans
        # only those of its rules' aggregations (the order of a list of
        # servers does not matter: the drop asks whether any is kept)
        by_agg: dict[str, list[tuple[int, int, int]]] = {}
        for j, ((bn, bd), a) in enumerate(zip(nds, aggs, strict=True)):
            by_agg.setdefault(a, []).append((j, bn, bd))
        empty: list[tuple[int, int, int]] = []
        singles: list[list[int]] = []
        pairs: list[list[list[int]] | None] = []
        for r, (an, ad) in enumerate(nds):
            # j serves r: j's aggregation is a rule of r's and target period /
            # period j is whole
            a = aggs[r]
            singles.append(
                [
                    j
                    for b in SINGLE_SOURCE_RULES[a]
                    for j, bn, bd in by_agg.get(b, empty)
                    if j != r and (an * bd) % (ad * bn) == 0
                ]
            )
            pair = PAIR_SOURCE_RULES.get(a)
            pairs.append(
                None
                if pair is None
                else [
                    [j for j, bn, bd in by_agg.get(b, empty) if (an * bd) % (ad * bn) == 0]
                    for b in pair
                ]
            )
        self.singles, self.pairs = singles, pairs

    def drop(self, helper: tuple[int, int] | None = None) -> list[int]:
        """The one-pass drop over the requested streams (+ a helper ALL
        stream of period ``helper`` = (numerator, denominator), always kept,
        last): the positions kept, the helper's being ``len(streams)``."""
        n = len(self.streams)
        singles, pairs = self.singles, self.pairs
        if helper is not None:  # its column: the targets it serves
            hn, hd = helper
            singles, pairs = list(singles), list(pairs)
            for r, (an, ad) in enumerate(self.nds):
                if (an * hd) % (ad * hn):
                    continue
                a = self.aggs[r]
                if _ALL_SERVES[a]:
                    singles[r] = [*singles[r], n]
                groups = pairs[r]
                if groups is not None and _ALL_PAIR[a]:
                    joined = _ALL_PAIR[a]
                    pairs[r] = [[*g, n] if k in joined else g for k, g in enumerate(groups)]
        kept = [True] * (n + 1)  # the helper (index n) stays kept
        is_kept = kept.__getitem__

        def derivable(r: int) -> bool:
            if any(map(is_kept, singles[r])):
                return True
            groups = pairs[r]
            return groups is not None and all(any(map(is_kept, g)) for g in groups)

        dropped: list[int] = []
        for i in range(n):
            kept[i] = False
            # i itself first: most streams that stay are those the others
            # cannot serve; then every stream dropped before it
            if derivable(i) and all(map(derivable, dropped)):
                dropped.append(i)
            else:
                kept[i] = True
        out = [i for i in range(n) if kept[i]]
        return out + [n] if helper is not None else out

    def sources(
        self, r: int, kept: Sequence[bool], helper: StreamKey | None
    ) -> tuple[Source, ...] | None:
        """:func:`find_sources` of the stream at position ``r`` from the kept
        positions (``kept[len(streams)]``: the helper, when there is one):
        the same preference, on the relations already computed."""
        n = len(self.streams)
        an, ad = self.nds[r]
        a = self.aggs[r]
        serves = helper is not None and _factor(self.streams[r], helper) is not None
        rank = _RULE_RANK[a]
        best: tuple[int, int, int] | None = None  # (rule rank, factor, position)
        for j in (*self.singles[r], n) if serves and _ALL_SERVES[a] else self.singles[r]:
            if not kept[j]:
                continue
            bn, bd = self.nds[j] if j < n else helper._nd  # type: ignore[union-attr]
            candidate = (rank[self.aggs[j] if j < n else agg.ALL], (an * bd) // (ad * bn), j)
            if best is None or candidate[:2] < best[:2]:
                best = candidate
        if best is not None:
            j = best[2]
            return (Source(self.streams[j] if j < n else helper, best[1]),)  # type: ignore[arg-type]
        groups = self.pairs[r]
        if groups is None:
            return None
        chosen: list[Source] = []
        joined = _ALL_PAIR[a] if serves else ()
        for k, group in enumerate(groups):
            options = [j for j in group if kept[j]] + ([n] if k in joined else [])
            if not options:
                return None
            nds = [self.nds[j] if j < n else helper._nd for j in options]  # type: ignore
            factors = [(an * bd) // (ad * bn) for bn, bd in nds]
            f = min(factors)
            j = options[factors.index(f)]
            chosen.append(Source(self.streams[j] if j < n else helper, f))  # type: ignore[arg-type]
        return tuple(chosen)


def _drop_derivable(
    required: Sequence[StreamKey],
    cost_per_s: Callable[[StreamKey], float],
    helper: StreamKey | None = None,
) -> list[StreamKey]:
    """The one-pass drop over ``required`` (+ ``helper``, always kept): the
    most expensive first (ties: longest period, then aggregation order).

    The streams are of one topic. Which stream can serve which is computed
    once (the rules of :func:`find_sources`), so that each drop costs a
    scan of those relations, not a search over the sent set."""
    relations = _Relations(required, [cost_per_s(s) for s in required])
    kept = relations.drop(None if helper is None else helper._nd)  # type: ignore[attr-defined]
    streams = [*relations.streams, helper]
    return [streams[i] for i in kept]  # type: ignore[misc]


#: The cost of a stream given as (topic, aggregation, period numerator,
#: period denominator): lets the choice price a helper before building its key.
CostOf = Callable[[str, str, int, int], float]

#: The cost of a stream of one topic given as (aggregation, period numerator,
#: period denominator); :func:`plan_streams` asks one per topic.
Price = Callable[[str, int, int], float]


def _choose_for_topic(
    streams: Sequence[StreamKey],
    cost_per_s: Callable[[StreamKey], float],
    cost_of: CostOf | None = None,
) -> list[StreamKey]:
    topic = streams[0].topic

    def price(aggregation: str, num: int, den: int) -> float:
        if cost_of is not None:
            return cost_of(topic, aggregation, num, den)
        return cost_per_s(StreamKey(topic, aggregation, Fraction(num, den)))

    relations, best, helper = _choose(streams, [cost_per_s(s) for s in streams], price)
    n = len(relations.streams)
    kept = [relations.streams[i] for i in best if i < n]
    return kept + [helper] if helper is not None else kept


def _choose(
    streams: Sequence[StreamKey],
    stream_costs: Sequence[float],
    price: Price,
) -> tuple[_Relations, list[int], StreamKey | None]:
    """The choice for one topic's streams (their costs given): the
    relations, the kept positions (the helper's is ``len(streams)``) and the
    helper ALL stream, if one pays (priced by ``price``)."""
    relations = _Relations(streams, stream_costs)
    n = len(streams)
    costs = [*relations.costs, 0.0]  # position n: the helper on trial
    cost = costs.__getitem__
    best = relations.drop()
    best_cost = sum(map(cost, best))  # the same order of additions as a loop
    best_helper: StreamKey | None = None
    best_nd = (1, 1)  # the period of best_helper, once there is one (position n)
    periods = {s._nd: s._sort_period for s in streams}  # type: ignore[attr-defined]
    asked_all = {s._nd for s in streams if s.aggregation == agg.ALL}  # type: ignore[attr-defined]
    nds = relations.nds
    for nd, (_, period) in sorted(periods.items(), key=lambda item: item[1]):
        if nd in asked_all:
            continue  # an ALL stream at this period is asked for already
        hn, hd = nd
        helper_cost = price(agg.ALL, hn, hd)
        if helper_cost >= best_cost:
            continue  # more than all the sent streams: it cannot pay for itself
        # the sent streams at multiples of the helper's period, in order
        replaceable = 0.0
        for i in best:
            sn, sd = nds[i] if i < n else best_nd
            if (sn * hd) % (sd * hn) == 0:
                replaceable += cost(i)
        if helper_cost >= replaceable:
            continue  # it cannot pay for itself (its key not even built)
        trial = relations.drop(nd)
        previous, costs[n] = costs[n], helper_cost
        trial_cost = sum(map(cost, trial))
        if trial_cost < best_cost:
            best, best_cost, best_nd = trial, trial_cost, nd
            best_helper = StreamKey(streams[0].topic, agg.ALL, period)
        else:
            costs[n] = previous  # the best set's helper keeps its cost
    return relations, best, best_helper


def choose_sent(
    requested: Iterable[StreamKey],
    cost_per_s: Callable[[StreamKey], float],
    cost_of: CostOf | None = None,
) -> set[StreamKey]:
    """The sent set: per topic, the cheapest of the requested streams minus
    those derivable from the rest, with or without one helper ALL stream.
    ``cost_of``, when given, must equal ``cost_per_s`` on the key's parts."""
    by_topic: dict[str, list[StreamKey]] = {}
    for s in requested:
        by_topic.setdefault(s.topic, []).append(s)
    sent: set[StreamKey] = set()
    for streams in by_topic.values():
        sent.update(
            _choose_for_topic(streams, cost_per_s, cost_of) if len(streams) > 1 else streams
        )
    return sent


def plan_streams(
    requested: Iterable[tuple[StreamKey, Sequence[str]]],
    topic_index: Mapping[str, int],
    pricing: Callable[[str], Price],
) -> tuple[PlannedStream, ...]:
    """Every requested stream (with its subscribers), in contract order,
    with its id if sent or its sources if derived.

    Topic by topic (the contract's order begins with the topic's), so that
    the choice, the order, the ids and the sources are decided on a few
    streams at a time, by position, with no stream hashed: the choice of
    :func:`choose_sent`, the order of :func:`stream_order`, the sources of
    :func:`find_sources`."""
    by_topic: dict[str, list[tuple[StreamKey, Sequence[str]]]] = {}
    for pair in requested:
        by_topic.setdefault(pair[0].topic, []).append(pair)
    out: list[PlannedStream] = []
    append = out.append
    next_id = 0
    for topic in sorted(by_topic, key=topic_index.__getitem__):
        pairs = by_topic[topic]
        if len(pairs) == 1:
            key, names = pairs[0]
            append(PlannedStream(key, next_id, (), tuple(names)))
            next_id += 1
            continue
        price = pricing(topic)
        keys = [k for k, _ in pairs]
        relations, best, helper = _choose(keys, [price(k.aggregation, *k._nd) for k in keys], price)  # type: ignore
        n = len(pairs)
        names_at = [pairs[i][1] for i in relations.order]
        kept = [False] * (n + 1)
        for i in best:
            kept[i] = True
        streams = relations.streams
        # contract order: aggregation order, then period
        periods = [s._sort_period for s in streams]  # type: ignore
        aggs = [_AGG_INDEX[a] for a in relations.aggs]
        ranked = sorted(zip(aggs, periods, range(n), strict=True))
        if helper is not None:  # nobody's: its place among the others
            ranked.append((_AGG_INDEX[agg.ALL], helper._sort_period, n))  # type: ignore
            ranked.sort()
        for *_, i in ranked:
            if i == n:
                append(PlannedStream(helper, next_id, (), ()))  # type: ignore[arg-type]
                next_id += 1
            elif kept[i]:
                append(PlannedStream(streams[i], next_id, (), tuple(names_at[i])))
                next_id += 1
            else:
                sources = relations.sources(i, kept, helper)
                assert sources is not None  # the choice keeps every stream derivable
                append(PlannedStream(streams[i], None, sources, tuple(names_at[i])))
    return tuple(out)
