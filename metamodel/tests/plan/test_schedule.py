"""The compact schedule against a brute-force listing of due dates."""

from __future__ import annotations

import itertools
import random
import time
from fractions import Fraction
from math import lcm
from typing import Any

import pytest
from modd_plan.plan import make_plan
from modd_plan.schedule import Schedule


def brute_dates(periods: list[int], horizon: int) -> list[int]:
    return sorted({d for p in periods for d in range(p, horizon + 1, p)})


def test_count_and_walk_match_brute_force_on_random_periods() -> None:
    rng = random.Random(3)
    checked = 0
    while checked < 300:
        periods = [rng.randint(1, 40) * rng.choice([1, 10]) for _ in range(rng.randint(1, 6))]
        if lcm(*periods) > 50_000:
            continue  # keep the brute-force listing small
        checked += 1
        s = Schedule.from_periods_us(periods)
        dates = brute_dates(periods, s.hyperperiod_us)
        assert s.messages_per_hyperperiod == len(dates)
        k = rng.randrange(len(dates))
        index, date, ids = next(s.iter_slots(k))
        assert index == k and date * 1_000_000 == dates[k]
        assert ids == [i for i, p in enumerate(periods) if dates[k] % p == 0]


def test_slots_go_on_past_the_hyperperiod() -> None:
    s = Schedule.from_periods_us([2, 3])
    slots = list(itertools.islice(s.iter_slots(), 9))
    assert [int(d * 1_000_000) for _, d, _ in slots] == [2, 3, 4, 6, 8, 9, 10, 12, 14]
    assert slots[3][2] == [0, 1]
    assert next(s.iter_slots(8))[1] * 1_000_000 == 14


def test_hyperperiod_may_be_longer_than_the_sent_periods() -> None:
    # scenario 1: 0.25 s sent, 2 s derived: 8 messages in the 2 s hyperperiod
    s = Schedule.from_periods_us([250_000] * 4, hyperperiod_us=2_000_000)
    assert (s.hyperperiod, s.messages_per_hyperperiod) == (Fraction(2), 8)
    with pytest.raises(ValueError):
        Schedule.from_periods_us([300_000], hyperperiod_us=1_000_000)


def test_twenty_six_day_hyperperiod_plans_in_milliseconds() -> None:
    periods = [
        int(Fraction(p) * 1_000_000) for p in ["0.3", "0.7", "1.1", "2.3", "1.3", "1.7", "1.9"]
    ]
    start = time.perf_counter()
    s = Schedule.from_periods_us(periods)
    count = s.messages_per_hyperperiod
    first = list(itertools.islice(s.iter_slots(), 5))
    far = next(s.iter_slots(count - 1))
    elapsed = time.perf_counter() - start
    assert s.hyperperiod == Fraction(22309287, 10)  # 25.8 days
    assert s.hyperperiod_us == lcm(*periods)
    assert far[1] == s.hyperperiod and far[2] == list(range(7))  # all due at the end
    assert [str(d) for _, d, _ in first] == ["3/10", "3/5", "7/10", "9/10", "11/10"]
    # inclusion-exclusion by hand for 7 pairwise coprime periods (in 0.1 s units)
    units = [3, 7, 11, 23, 13, 17, 19]
    h = 22309287
    expected = sum(
        (-1) ** (len(c) + 1) * (h // lcm(*c))
        for r in range(1, 8)
        for c in itertools.combinations(units, r)
    )
    assert count == expected
    assert elapsed < 0.05


def test_empty_schedule() -> None:
    s = Schedule.from_periods_us([])
    assert s.messages_per_hyperperiod == 0
    assert list(s.iter_slots()) == []
    assert s.first_slots(10) == []


def test_same_slots_as_the_link_runtime() -> None:
    """The shared contract: the link's slot iterator (runtime/python) and the
    planner's schedule agree slot by slot."""
    import modd.link.schedule as link_schedule

    rng = random.Random(11)
    for _ in range(50):
        periods = [
            rng.choice([250_000, 300_000, 700_000, 1_000_000, 2_000_000])
            for _ in range(rng.randint(1, 6))
        ]
        theirs = link_schedule.SlotIterator(periods)
        ours = Schedule.from_periods_us(periods).iter_slots()
        for _ in range(60):
            slot = next(theirs)
            index, date, ids = next(ours)
            assert (slot.index, slot.offset_us, list(slot.streams)) == (
                index,
                int(date * 1_000_000),
                ids,
            )


def test_twenty_six_day_model_plans_in_milliseconds(make_model: Any) -> None:
    periods = ["0.3", "0.7", "1.1", "2.3", "1.3", "1.7", "1.9"]
    names = [f"v{i}" for i in range(7)]
    subs = [(f"sub{i}", names[i], p, "MAX") for i, p in enumerate(periods)]
    model = make_model(names, [("p", "0.1", names)], subs)
    make_plan(model)  # warm-up (imports)
    start = time.process_time()  # CPU, not wall: other processes on the machine do not count
    j = make_plan(model).to_json()
    elapsed = time.process_time() - start
    assert j["hyperperiod_s"] == "2230928.7" and j["messages_per_hyperperiod"] == 13185447
    assert j["schedule"]["slots_truncated"] and j["schedule"]["slots_listed"] == 1000
    # ~2 ms here; the exponential planner took 12.9 s on this model
    assert elapsed < 1.0
