"""Each window once, by its identity (docs/fleet.md): the contracts' repeats
(contracts/vectors/delivered_value.json, "repeats", which the Python subscriber
API (test_fleet_units.py), the C++ subscriber client and the backend keep) are
what a SubBroker writes, and the memory of windows had agrees with a plain set
while it stays bounded."""

from __future__ import annotations

import json
import random
import threading
from itertools import pairwise
from pathlib import Path
from typing import Any

from modd.subbroker.payload import DeliveredValue
from modd.subbroker.seen import Runs, Seen, identity, identity_of
from modd_contracts.schema import validate

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors" / "delivered_value.json"


def _repeats() -> list[dict[str, Any]]:
    cases: list[dict[str, Any]] = json.loads(VECTORS.read_text())["repeats"]["sequence"]
    return cases


def test_the_repeats_are_payloads_a_subbroker_writes() -> None:
    for case in _repeats():
        line = case["line"].encode()
        assert validate("delivered_value", json.loads(line)) == [], case["name"]
        value = DeliveredValue.from_json(line)
        assert value.to_json() == line, case["name"]
        assert identity_of(json.loads(line)) == identity(value), case["name"]


def test_runs_agree_with_a_set() -> None:
    """Random windows of a few epochs, in random order with repeats: the runs answer
    as a set of every (epoch, window) had does, and merge as windows fill in."""
    rng = random.Random(44)
    runs, oracle = Runs(limit=10**6), set()
    for _ in range(20_000):
        e, w = rng.choice((5, 9, 12)), rng.randrange(-50, 2000)
        assert runs.first(e, w) == ((e, w) not in oracle), (e, w)
        oracle.add((e, w))
    expected = sum(1 for e, w in oracle if (e, w - 1) not in oracle)  # a run per start
    assert len(runs.runs) == expected
    assert all(a[:2] < b[:2] and (a[0], a[2]) != (b[0], b[1]) for a, b in pairwise(runs.runs))


def test_live_windows_in_order_take_one_run() -> None:
    runs = Runs(limit=4)
    assert all(runs.first(7, k) for k in range(100_000))
    assert runs.runs == [(7, 0, 100_000)]


def test_memory_is_bounded_oldest_out_first() -> None:
    runs = Runs(limit=3)
    for k in range(0, 10, 2):  # five runs: gaps between them
        runs.first(1, k)
    assert runs.runs == [(1, 4, 5), (1, 6, 7), (1, 8, 9)]
    assert runs.first(1, 0)  # forgotten: it passes again
    seen = Seen(runs=2, keys=2)
    for name in ("a", "b", "c"):
        assert seen.first(("usv", name, "1", 1, 0))
    assert not seen.first(("usv", "c", "1", 1, 0)) and not seen.first(("usv", "b", "1", 1, 0))
    assert seen.first(("usv", "a", "1", 1, 0))  # the least recently heard key went first


def test_threads_get_each_window_once() -> None:
    seen, firsts = Seen(runs=10**6), []  # random orders leave ~1,250 runs at once
    lock = threading.Lock()

    def feed(order: list[int]) -> None:
        mine = [k for k in order if seen.first(("usv", "s", "1", 1, k))]
        with lock:
            firsts.extend(mine)

    orders = [random.Random(i).sample(range(5000), 5000) for i in range(4)]
    threads = [threading.Thread(target=feed, args=(o,)) for o in orders]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(firsts) == list(range(5000))
