"""The archive workers' fair queue (archive_pool.py): round-robin between
users with a worker always left for the others, a bounded wait (503 with
Retry-After), a bounded run, and work given up stops its worker at once
(and is never started again)."""

from __future__ import annotations

import asyncio
import os
import time
from pathlib import Path

import pytest
from modd_backend.archive_pool import ArchivePool
from modd_backend.errors import ApiError


def _alive(pid: int) -> bool:
    """The process runs (a killed one not yet reaped does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


async def _dead_within(pid: int, seconds: float) -> float:
    t0 = time.monotonic()
    while _alive(pid):
        assert time.monotonic() - t0 < seconds, f"worker {pid} still runs after {seconds} s"
        await asyncio.sleep(0.02)
    return time.monotonic() - t0


def test_one_users_burst_does_not_delay_anothers_single_job() -> None:
    async def main() -> tuple[float, int]:
        pool = ArchivePool(workers=2)
        try:
            await asyncio.gather(*(pool.run(u, os.getpid, time_s=30) for u in (1, 2)))  # warm
            burst = [
                asyncio.ensure_future(pool.run(1, time.sleep, 0.4, time_s=30)) for _ in range(100)
            ]
            await asyncio.sleep(0.2)
            t0 = time.monotonic()
            await pool.run(2, time.sleep, 0.1, time_s=30)
            waited = time.monotonic() - t0
            refused = [f for f in burst if f.done() and isinstance(f.exception(), ApiError)]
            assert refused and all(f.exception().status == 429 for f in refused)  # type: ignore[union-attr]
            left = sum(not f.done() for f in burst)
            for f in burst:
                f.cancel()
            await asyncio.gather(*burst, return_exceptions=True)
            return waited, left
        finally:
            await pool.close()

    waited, left = asyncio.run(main())
    # the burst holds one worker (16 waiting, the rest refused with 429 and
    # Retry-After); the other user's job starts at once on the other
    assert waited < 2.0, waited
    assert left >= 15


def test_round_robin_between_waiting_users() -> None:
    async def main() -> list[int]:
        pool = ArchivePool(workers=1)
        order: list[int] = []

        async def job(user: int) -> None:
            await pool.run(user, time.sleep, 0.05, time_s=30)
            order.append(user)

        try:
            await pool.run(9, os.getpid, time_s=30)  # a warm worker
            tasks = [asyncio.ensure_future(job(1)) for _ in range(4)]
            await asyncio.sleep(0)
            tasks += [asyncio.ensure_future(job(2)) for _ in range(2)]
            await asyncio.gather(*tasks)
            return order
        finally:
            await pool.close()

    order = asyncio.run(main())
    # user 1's first job started alone; then the two take turns
    assert order[1:5] == [1, 2, 1, 2], order


def test_a_job_not_started_within_the_bound_gets_503_with_retry_after() -> None:
    async def main() -> ApiError:
        pool = ArchivePool(workers=1, start_wait_s=0.5)
        try:
            busy = asyncio.ensure_future(pool.run(1, time.sleep, 3, time_s=30))
            await asyncio.sleep(0.1)
            with pytest.raises(ApiError) as caught:
                await pool.run(2, os.getpid, time_s=30)
            busy.cancel()
            return caught.value
        finally:
            await pool.close()

    error = asyncio.run(main())
    assert error.status == 503 and error.headers and int(error.headers["Retry-After"]) >= 1


def test_a_job_over_its_time_is_stopped_with_its_worker() -> None:
    async def main() -> tuple[ApiError, float, int, int]:
        pool = ArchivePool(workers=1)
        try:
            pid = await pool.run(1, os.getpid, time_s=30)
            t0 = time.monotonic()
            with pytest.raises(ApiError) as caught:
                await pool.run(1, time.sleep, 30, time_s=0.5)
            took = time.monotonic() - t0
            await _dead_within(pid, 2)
            return caught.value, took, pool.killed, await pool.run(1, os.getpid, time_s=30)
        finally:
            await pool.close()

    error, took, killed, new_pid = asyncio.run(main())
    assert error.status == 503 and "longer than" in str(error)
    assert took < 2.0 and killed == 1 and new_pid > 0


def test_an_abandoned_job_stops_its_worker_within_2_s_and_is_not_run_again() -> None:
    async def main() -> tuple[float, int, float]:
        pool = ArchivePool(workers=1)
        try:
            pid = await pool.run(1, os.getpid, time_s=30)
            gone_at = time.monotonic() + 0.3

            async def gone() -> bool:
                return time.monotonic() > gone_at

            with pytest.raises(ApiError):
                await pool.run(1, time.sleep, 60, time_s=120, gone=gone)
            stopped = await _dead_within(pid, 2)
            t0 = time.monotonic()
            other = await pool.run(2, os.getpid, time_s=30)  # a fresh worker, no 60 s sleep first
            assert other != pid
            return stopped, pool.killed, time.monotonic() - t0
        finally:
            await pool.close()

    stopped, killed, next_took = asyncio.run(main())
    assert stopped < 2.0 and killed == 1 and next_took < 10


def test_a_cancelled_waiting_job_leaves_the_queue() -> None:
    async def main() -> tuple[int, int]:
        pool = ArchivePool(workers=1)
        try:
            busy = asyncio.ensure_future(pool.run(1, time.sleep, 1, time_s=30))
            waiting = asyncio.ensure_future(pool.run(2, os.getpid, time_s=30))
            await asyncio.sleep(0.2)
            before = pool.waiting
            waiting.cancel()
            await asyncio.gather(waiting, return_exceptions=True)
            await busy
            return before, pool.waiting
        finally:
            await pool.close()

    assert asyncio.run(main()) == (1, 0)
