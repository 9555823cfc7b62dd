"""The sent-set choice (streams._drop_derivable, which precomputes which
stream can serve which) against the straightforward one it replaced: a
search of the sent set with find_sources at every drop. Random topics of up
to 12 requested streams, costs with many ties, seeded."""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from fractions import Fraction

import pytest
from modd_plan import streams
from modd_plan.streams import AGGREGATIONS, StreamKey, find_sources

PERIODS = [Fraction(x) for x in ("0.25", "0.5", "1", "2", "2.5", "5", "10", "0.3", "0.7", "1.5")]


def _reference_drop(
    required: Sequence[StreamKey],
    cost: Callable[[StreamKey], float],
    helper: StreamKey | None = None,
) -> list[StreamKey]:
    ordered = sorted(
        required, key=lambda s: (-cost(s), -s.period, AGGREGATIONS.index(s.aggregation))
    )
    kept = [True] * len(ordered)
    extra = [helper] if helper is not None else []
    for i in range(len(ordered)):
        kept[i] = False
        rest = [s for s, k in zip(ordered, kept, strict=True) if k] + extra
        dropped = [s for s, k in zip(ordered, kept, strict=True) if not k]
        if any(find_sources(r, rest) is None for r in dropped):
            kept[i] = True
    return [s for s, k in zip(ordered, kept, strict=True) if k] + extra


def _reference_choose(
    required: Sequence[StreamKey], cost: Callable[[StreamKey], float]
) -> list[StreamKey]:
    best = _reference_drop(required, cost)
    best_cost = sum(cost(s) for s in best)
    for period in sorted({s.period for s in required}):
        helper = StreamKey(required[0].topic, "ALL", period)
        if helper in required:
            continue
        replaceable = sum(cost(s) for s in best if streams._factor(s, helper) is not None)
        if cost(helper) >= replaceable:
            continue
        trial = _reference_drop(required, cost, helper)
        trial_cost = sum(cost(s) for s in trial)
        if trial_cost < best_cost:
            best, best_cost = trial, trial_cost
    return best


@pytest.mark.parametrize("seed", range(5))
def test_choice_matches_the_reference(seed: int) -> None:
    rng = random.Random(seed)
    for _ in range(300):
        pool = [StreamKey("d.s.v", a, p) for a in AGGREGATIONS for p in PERIODS]
        required = rng.sample(pool, rng.randint(2, 12))
        levels = [rng.choice([1.0, 2.0, 4.0, 0.5]) for _ in range(3)]
        table = {s: rng.choice(levels) / float(s.period) for s in pool}

        def cost(s: StreamKey, table: dict[StreamKey, float] = table) -> float:
            return table[s]

        reference = _reference_choose(required, cost)
        assert streams._choose_for_topic(required, cost) == reference

        def cost_of(
            topic: str, aggregation: str, num: int, den: int, table: dict[StreamKey, float] = table
        ) -> float:
            return table[StreamKey(topic, aggregation, Fraction(num, den))]

        # pricing a helper from its parts, before its key is built: the same choice
        assert streams._choose_for_topic(required, cost, cost_of) == reference
        helper = StreamKey("d.s.v", "ALL", rng.choice(PERIODS))
        if helper not in required:
            assert streams._drop_derivable(required, cost, helper) == _reference_drop(
                required, cost, helper
            )


@pytest.mark.parametrize("seed", range(3))
def test_plan_streams_sources_match_find_sources(seed: int) -> None:
    """plan_streams takes each derived stream's sources from the relations
    the choice computed; find_sources over the sent streams is the oracle
    (the same preference: rule order, fewest windows, then SUM + COUNT)."""
    rng = random.Random(100 + seed)
    for _ in range(200):
        topics = [f"d.s.v{t}" for t in range(rng.randint(1, 4))]
        requested: dict[StreamKey, list[str]] = {}
        for t in topics:
            for s in rng.sample(
                [StreamKey(t, a, p) for a in AGGREGATIONS for p in PERIODS], rng.randint(1, 10)
            ):
                requested[s] = [f"sub{len(requested)}"]
        levels = [rng.choice([1.0, 2.0, 4.0, 0.5]) for _ in range(3)]
        prices: dict[tuple[str, str, int, int], float] = {}

        def pricing(
            topic: str,
            prices: dict[tuple[str, str, int, int], float] = prices,
            levels: list[float] = levels,
        ) -> streams.Price:
            def price(aggregation: str, num: int, den: int) -> float:
                return prices.setdefault(
                    (topic, aggregation, num, den), rng.choice(levels) * den / num
                )

            return price

        index = {t: i for i, t in enumerate(topics)}
        planned = streams.plan_streams(requested.items(), index, pricing)
        sent = [p.stream for p in planned if p.sent]
        assert len({p.stream for p in planned}) == len(planned)
        assert [p.id for p in planned if p.sent] == list(range(len(sent)))
        for p in planned:
            if not p.sent:
                assert p.sources == find_sources(p.stream, sent), p.stream
            assert p.subscribers == tuple(requested.get(p.stream, ()))


@pytest.mark.parametrize("seed", range(3))
def test_relations_sources_match_find_sources(seed: int) -> None:
    """The relations' sources of one stream from any kept set (with or
    without a helper ALL stream) against find_sources over those streams:
    many candidates per rule, so the preference order is exercised."""
    rng = random.Random(200 + seed)
    pool = [StreamKey("d.s.v", a, p) for a in AGGREGATIONS for p in PERIODS]
    for _ in range(300):
        required = rng.sample(pool, rng.randint(2, 30))
        relations = streams._Relations(required, [rng.random() for _ in required])
        n = len(required)
        helper = rng.choice([None, StreamKey("d.s.v", "ALL", rng.choice(PERIODS))])
        if helper is not None and helper in required:
            helper = None
        kept = [rng.random() < 0.7 for _ in range(n)] + [helper is not None]
        for r in range(n):
            was, kept[r] = kept[r], False
            sent = [s for s, k in zip(relations.streams, kept, strict=False) if k]
            expected = find_sources(relations.streams[r], sent + ([helper] if helper else []))
            assert relations.sources(r, kept, helper) == expected
            kept[r] = was


def test_asked_streams_one_stream_per_period_whatever_its_text() -> None:
    model = {
        "subscribers": [
            {"name": f"s{k}", "topic": "d.s.v", "aggregation": "MAX", "periodS": p}
            for k, p in enumerate(["1", "2.0", "1.0", "2", "1.00", "0.5"])
        ]
    }
    requested, subscriptions = streams.asked_streams(model)
    assert [(k.key, names) for k, names in requested] == [
        ("d.s.v/MAX/1.0", ["s0", "s2", "s4"]),
        ("d.s.v/MAX/2.0", ["s1", "s3"]),
        ("d.s.v/MAX/0.5", ["s5"]),
    ]
    assert subscriptions["s4"] is requested[0][0] and subscriptions["s3"] is requested[1][0]
    assert len(subscriptions) == 6
