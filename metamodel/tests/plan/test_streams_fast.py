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


def _reference_drop(required: Sequence[StreamKey], cost: Callable[[StreamKey], float],
                    helper: StreamKey | None = None) -> list[StreamKey]:
    ordered = sorted(required, key=lambda s: (-cost(s), -s.period,
                                              AGGREGATIONS.index(s.aggregation)))
    kept = [True] * len(ordered)
    extra = [helper] if helper is not None else []
    for i in range(len(ordered)):
        kept[i] = False
        rest = [s for s, k in zip(ordered, kept, strict=True) if k] + extra
        dropped = [s for s, k in zip(ordered, kept, strict=True) if not k]
        if any(find_sources(r, rest) is None for r in dropped):
            kept[i] = True
    return [s for s, k in zip(ordered, kept, strict=True) if k] + extra


def _reference_choose(required: Sequence[StreamKey], cost: Callable[[StreamKey], float]
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

        def cost_of(topic: str, aggregation: str, num: int, den: int,
                    table: dict[StreamKey, float] = table) -> float:
            return table[StreamKey(topic, aggregation, Fraction(num, den))]

        # pricing a helper from its parts, before its key is built: the same choice
        assert streams._choose_for_topic(required, cost, cost_of) == reference
        helper = StreamKey("d.s.v", "ALL", rng.choice(PERIODS))
        if helper not in required:
            assert (streams._drop_derivable(required, cost, helper)
                    == _reference_drop(required, cost, helper))
