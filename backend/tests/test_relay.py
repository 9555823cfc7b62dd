"""Backpressure between zenoh threads and a WebSocket: the producer never
blocks, a slow consumer loses the oldest items and learns how many."""

from __future__ import annotations

import asyncio
import threading
import time

import pytest
from modd_backend.modeldiff import diff
from modd_backend.relay import DropOldestQueue
from modd_backend.roles import may_edit, owners_of_changes


def test_full_queue_drops_oldest_and_counts() -> None:
    q: DropOldestQueue[int] = DropOldestQueue(3)
    for i in range(10):
        q.put(i)
    assert q.take_dropped() == 7
    assert q.drain() == [7, 8, 9]
    assert q.take_dropped() == 0
    with pytest.raises(ValueError):
        DropOldestQueue(0)


def test_thread_producer_never_blocks_on_a_slow_consumer() -> None:
    async def scenario() -> tuple[list[int], int, float]:
        q: DropOldestQueue[int] = DropOldestQueue(16)
        q.bind(asyncio.get_running_loop())
        done = threading.Event()
        took: list[float] = []

        def produce() -> None:
            start = time.perf_counter()
            for i in range(5000):
                q.put(i)
            took.append(time.perf_counter() - start)
            done.set()

        threading.Thread(target=produce).start()
        got: list[int] = []
        dropped = 0
        while True:
            batch = await q.get_batch()
            dropped += q.take_dropped()
            got.extend(batch)
            await asyncio.sleep(0.01)  # a slow browser
            if done.is_set() and got[-1] == 4999:
                break
        return got, dropped, took[0]

    got, dropped, took = asyncio.run(scenario())
    assert got == sorted(got)  # order kept
    assert got[-1] == 4999  # the newest always arrives
    assert len(got) + dropped == 5000  # everything is either delivered or counted
    assert dropped > 0
    assert took < 1.0  # 5000 puts never waited for the consumer


def test_get_batch_wakes_on_put_from_another_thread() -> None:
    async def scenario() -> list[str]:
        q: DropOldestQueue[str] = DropOldestQueue(4)
        q.bind(asyncio.get_running_loop())
        threading.Timer(0.05, q.put, args=("late",)).start()
        return await asyncio.wait_for(q.get_batch(), 2)

    assert asyncio.run(scenario()) == ["late"]


def test_diff_matches_named_items_by_name() -> None:
    before = {"subscribers": [{"name": "a", "p": 1}, {"name": "b", "p": 2}]}
    after = {"subscribers": [{"name": "b", "p": 2}, {"name": "c", "p": 3}]}
    assert diff(before, after) == [
        {"op": "remove", "pointer": "/subscribers/0", "before": {"name": "a", "p": 1}},
        {"op": "add", "pointer": "/subscribers/1", "after": {"name": "c", "p": 3}},
    ]
    assert diff({"x": [1, 2]}, {"x": [1]}) == [{"op": "remove", "pointer": "/x/1", "before": 2}]
    assert diff({"a/b": 1}, {"a/b": True}) == [
        {"op": "replace", "pointer": "/a~1b", "before": 1, "after": True}
    ]


def test_role_ownership_rules() -> None:
    changes = owners_of_changes({}, {"drone": {"name": "d", "sensors": []}, "layout": {}})
    assert changes == {"/drone": "designer", "/drone/sensors": "integrator", "/layout": None}
    assert may_edit({"designer"}, changes) == ["/drone/sensors"]
    assert may_edit({"designer", "integrator"}, changes) == []
    assert may_edit({"operator"}, {"/layout": None}) == ["/layout"]
    assert may_edit({"admin"}, changes) == []
    assert owners_of_changes({}, {"extra": 1}) == {"/extra": "designer"}


def test_one_wakeup_per_batch_and_nothing_lost() -> None:
    """Producers wake the consumer only when the queue stops being empty; a
    consumer that drains and sleeps never misses an item put meanwhile (an
    item left in the queue with the consumer asleep would hang this test)."""

    async def scenario() -> tuple[list[int], int]:
        q: DropOldestQueue[int] = DropOldestQueue(100_000)
        q.bind(asyncio.get_running_loop())
        n, threads = 20_000, 4

        def produce(k: int) -> None:
            for i in range(k, n, threads):
                q.put(i)
                if i % 997 == 0:
                    time.sleep(0.001)  # let the consumer drain and go to sleep

        workers = [threading.Thread(target=produce, args=(k,)) for k in range(threads)]
        for w in workers:
            w.start()
        got: list[int] = []
        while len(got) < n:
            got += await asyncio.wait_for(q.get_batch(), 5.0)
        for w in workers:
            w.join()
        return got, q.wakeups_saved

    got, saved = asyncio.run(scenario())
    assert sorted(got) == list(range(20_000))
    assert saved > 0
