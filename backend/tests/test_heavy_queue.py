"""Heavy requests beyond a user's share wait their turn in a bounded queue
(guards.HeavyLimiter.turn) instead of being told to retry: in the order they
came, at most ``wait_s``, a few per user; the one beyond is refused at once."""

from __future__ import annotations

import asyncio
import time

import pytest
from modd_backend.errors import ApiError
from modd_backend.guards import HeavyLimiter


async def _hold(
    lim: HeavyLimiter, user: int, log: list[str], name: str, release: asyncio.Event
) -> None:
    async with lim.turn(user):
        log.append(name)
        await release.wait()


async def _settle(lim: HeavyLimiter, waiting: int, in_flight: int) -> None:
    """Until the limiter reports these counts (generous deadline: a loaded machine)."""
    deadline = time.monotonic() + 10
    while (lim.waiting, lim.in_flight) != (waiting, in_flight):
        assert time.monotonic() < deadline, (lim.waiting, lim.in_flight)
        await asyncio.sleep(0.01)


def test_a_request_beyond_the_share_waits_its_turn_in_order() -> None:
    async def main() -> list[str]:
        lim = HeavyLimiter(per_user=2, total=8, poll_s=0.01)
        log: list[str] = []
        gates = {n: asyncio.Event() for n in "abcd"}
        tasks = []
        for n in "abcd":  # a, b run; c then d wait, in that order
            tasks.append(asyncio.create_task(_hold(lim, 1, log, n, gates[n])))
            await asyncio.sleep(0.02)
        await _settle(lim, waiting=2, in_flight=2)
        assert log == ["a", "b"]
        gates["b"].set()  # b's slot goes to c (first to wait), not d
        await _settle(lim, waiting=1, in_flight=2)
        gates["a"].set()
        await _settle(lim, waiting=0, in_flight=2)
        gates["c"].set()
        gates["d"].set()
        await asyncio.gather(*tasks)
        assert (lim.in_flight, lim.waiting) == (0, 0)
        return log

    assert asyncio.run(main()) == ["a", "b", "c", "d"]


def test_the_queue_is_bounded_per_user_and_in_all() -> None:
    async def main() -> None:
        lim = HeavyLimiter(per_user=1, total=8, queue_per_user=1, queue_total=2, poll_s=0.01)
        release = asyncio.Event()
        tasks = [
            asyncio.create_task(_hold(lim, 1, [], "run", release)),
            asyncio.create_task(_hold(lim, 1, [], "wait", release)),
        ]
        await _settle(lim, waiting=1, in_flight=1)
        with pytest.raises(ApiError) as exc:  # the user's queue is full: at once
            async with lim.turn(1):
                pass
        assert exc.value.status == 429 and exc.value.headers == {"Retry-After": "1"}
        assert "waiting their turn" in str(exc.value)
        tasks += [asyncio.create_task(_hold(lim, 2, [], "other", release))]  # runs
        tasks += [asyncio.create_task(_hold(lim, 2, [], "other waits", release))]
        await _settle(lim, waiting=2, in_flight=2)
        with pytest.raises(ApiError):  # two waiting in all: the bound
            async with lim.turn(3), lim.turn(3):
                pass
        release.set()
        await asyncio.gather(*tasks)
        assert (lim.in_flight, lim.waiting) == (0, 0)

    asyncio.run(main())


def test_a_turn_waited_for_too_long_or_given_up_leaves_nothing_behind() -> None:
    async def main() -> None:
        lim = HeavyLimiter(per_user=1, total=1, wait_s=0.2, poll_s=0.01)
        release = asyncio.Event()
        holder = asyncio.create_task(_hold(lim, 1, [], "run", release))
        await _settle(lim, waiting=0, in_flight=1)
        t0 = time.monotonic()
        with pytest.raises(ApiError) as exc:  # another user: all slots taken, waited 0.2 s
            async with lim.turn(2):
                pass
        assert exc.value.status == 503 and time.monotonic() - t0 >= 0.2
        gone = asyncio.create_task(_hold(lim, 2, [], "gone", release))  # the client goes away
        await _settle(lim, waiting=1, in_flight=1)
        gone.cancel()
        await _settle(lim, waiting=0, in_flight=1)
        release.set()
        await holder
        assert (lim.in_flight, lim.waiting) == (0, 0)

    asyncio.run(main())
