"""Merge functions: deriving from k windows equals aggregating the k windows'
samples at once (the SubBroker's result equals the PubBroker's)."""

from __future__ import annotations

import random

import pytest
from modd_contracts.events import EVENT_AGGREGATIONS
from modd_plan.derive import aggregate, derive_value, merge
from modd_plan.streams import AGGREGATIONS

RULES = [
    ("MIN", "MIN"),
    ("MAX", "MAX"),
    ("FIRST", "FIRST"),
    ("LAST", "LAST"),
    ("SUM", "SUM"),
    ("COUNT", "COUNT"),
    ("COUNT", "AVERAGE"),
    ("ALL", "ALL"),
    ("AVERAGE", "AVERAGE"),
] + [
    (a if a != "PERCENTILE" else "PERCENTILE(37.5)", "ALL")
    for a in AGGREGATIONS
    if a not in EVENT_AGGREGATIONS  # events derive from nothing (their state spans windows)
]


def _windows(rng: random.Random) -> list[list[int]]:
    # integer samples keep sums exact; some windows empty
    return [
        [rng.randint(-50, 50) for _ in range(rng.choice([0, 1, 3, 5]))]
        for _ in range(rng.randint(1, 8))
    ]


@pytest.mark.parametrize(("target", "source"), RULES)
def test_derived_equals_direct(target: str, source: str) -> None:
    rng = random.Random(f"{target}{source}")
    for _ in range(200):
        windows = _windows(rng)
        flat = [x for w in windows for x in w]
        got = derive_value(target, [(source, [aggregate(source, w) for w in windows])])
        assert got == aggregate(target, flat)


def test_average_from_sum_and_count() -> None:
    windows = [[1, 2], [], [6]]
    sums = [aggregate("SUM", w) for w in windows]
    counts = [aggregate("COUNT", w) for w in windows]
    assert derive_value("AVERAGE", [("SUM", sums), ("COUNT", counts)]) == (3.0, 3)
    assert derive_value("AVERAGE", [("SUM", [0]), ("COUNT", [0])]) is None


def test_absent_windows_and_bad_rules() -> None:
    assert merge("MIN", [None, None]) is None
    assert merge("FIRST", [None, 4, 2]) == 4
    assert merge("LAST", [4, 2, None]) == 2
    assert merge("AVERAGE", [None, (2.0, 0)]) is None
    with pytest.raises(ValueError):
        derive_value("MIN", [("MAX", [1.0])])
    with pytest.raises(ValueError):
        derive_value("SUM", [("AVERAGE", [(1.0, 2)])])
