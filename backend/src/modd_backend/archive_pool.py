"""The archive worker processes and the fair queue in front of them.

Archive work (reading an MCAP topic, a CSV, a series, a dataset export) runs
in a few worker processes, never in the service's own (a pure-Python reader
would hold the interpreter lock away from the event loop). In front of them:

- **a per-user fair queue**: waiting jobs are started round-robin between
  users (one job of each waiting user in turn), and one user runs at most
  ``share`` jobs at once (``workers - 1``, at least 1), so a worker is always
  left for the others: one user's burst never holds every worker;
- **a bounded wait**: a job not started within ``start_wait_s`` (30 s) is
  refused with 503 and ``Retry-After``; at most ``queue_per_user`` jobs of a
  user (429 beyond) and ``queue_total`` in all (503 beyond) wait;
- **a bounded run**: a job running longer than its ``time_s`` is stopped
  (its worker killed and replaced) and answered with 503;
- **abandoned work stops**: a job whose request went away (the client
  disconnected, the route's task was cancelled) is taken out of the queue,
  or its worker is killed (within a second) and replaced by a fresh one.
  A job is never started twice.

>>> pool = ArchivePool(workers=2)                                  # doctest: +SKIP
>>> text = await pool.run(user_id, csv_text, path, topic, None, None, time_s=60)  # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
import multiprocessing
import time
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from typing import Any, TypeVar

from .errors import ApiError, retry_later

T = TypeVar("T")
#: Address space of one worker process at most (resource.RLIMIT_AS), bytes: what
#: an export holds (samples, the platform track, the writer's buffers) ends there
#: with a MemoryError, answered 413, instead of growing until the machine swaps.
WORKER_MEMORY_BYTES = 6 * 1024**3
#: How much nicer than the service a worker process runs (os.nice): archive
#: work is batch work; the CPU it shares with the event loop goes to the loop
#: first (issue 41: four CSV exports kept both cores busy at the service's own
#: priority, and the loop's answers waited for the scheduler).
WORKER_NICE = 10


def _worker_main(conn: Connection, memory_bytes: int) -> None:
    """A worker: run ``fn(*args)`` for each job received; answer
    ``("ok", result)`` or ``("err", exception)``."""
    import os
    import resource

    os.nice(WORKER_NICE)
    if memory_bytes > 0:
        resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
    while True:
        try:
            fn, args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            answer: tuple[str, Any] = ("ok", fn(*args))
        except MemoryError:
            answer = ("err", MemoryError("the work needed more memory than a worker may hold"))
        except Exception as exc:  # sent back to the route, which words it
            answer = ("err", exc)
        try:
            conn.send(answer)
        except Exception as exc:  # an exception or result that does not pickle
            conn.send(("err", RuntimeError(f"the worker's answer cannot be sent: {exc}")))


class _Worker:
    """One worker process and the parent's end of its pipe."""

    def __init__(self, memory_bytes: int) -> None:
        ctx = multiprocessing.get_context("spawn")
        self.conn, child = ctx.Pipe()
        self.process: BaseProcess = ctx.Process(
            target=_worker_main, args=(child, memory_bytes), daemon=True
        )
        self.process.start()
        child.close()

    def kill(self) -> None:
        """Stop the process at once (a job given up or over its time)."""
        if self.process.is_alive():
            self.process.kill()
        self.process.join(5)
        self.conn.close()


@dataclass(eq=False)
class _Job:
    user: int
    fn: Callable[..., Any]
    args: tuple[Any, ...]
    time_s: float
    future: asyncio.Future[Any]
    deadline: float
    task: asyncio.Task[None] | None = None
    worker: _Worker | None = field(default=None, repr=False)


class ArchivePool:
    """``workers`` processes behind a per-user round-robin queue (module docstring)."""

    def __init__(
        self,
        workers: int = 2,
        *,
        start_wait_s: float = 30.0,
        queue_per_user: int = 16,
        queue_total: int = 64,
        memory_bytes: int = WORKER_MEMORY_BYTES,
    ) -> None:
        self.workers = workers
        self.share = max(1, workers - 1)
        self.start_wait_s = start_wait_s
        self.queue_per_user = queue_per_user
        self.queue_total = queue_total
        self.memory_bytes = memory_bytes
        self._idle: list[_Worker] = []
        self._queues: dict[int, deque[_Job]] = {}
        self._order: deque[int] = deque()  # users with waiting jobs, round-robin
        self._running: dict[int, int] = {}
        self._closed = False
        self._tasks: set[asyncio.Task[None]] = set()
        #: Workers killed since the start (a job given up or over its time).
        self.killed = 0

    @property
    def waiting(self) -> int:
        return sum(len(q) for q in self._queues.values())

    @property
    def running(self) -> int:
        return sum(self._running.values())

    async def run(
        self,
        user: int,
        fn: Callable[..., T],
        *args: Any,
        time_s: float,
        since: float | None = None,
        gone: Callable[[], Awaitable[bool]] | None = None,
    ) -> T:
        """``fn(*args)`` in a worker, in this user's turn. ``since``: when the
        request began waiting (the start bound counts from there); ``gone``:
        polled every 0.5 s, true when the client went away (the job is then
        given up and its worker stopped)."""
        job = self._enqueue(user, fn, args, time_s, since)
        watch = asyncio.ensure_future(_watch(gone)) if gone is not None else None
        try:
            if watch is None:
                result: T = await job.future
                return result
            done, _ = await asyncio.wait({job.future, watch}, return_when=asyncio.FIRST_COMPLETED)
            if job.future in done:
                return job.future.result()  # type: ignore[no-any-return]
            raise ApiError(499, "the client went away; the work was stopped")
        finally:
            if watch is not None:
                watch.cancel()
            if not job.future.done():
                self._abandon(job)

    def _enqueue(
        self,
        user: int,
        fn: Callable[..., Any],
        args: tuple[Any, ...],
        time_s: float,
        since: float | None,
    ) -> _Job:
        if self._closed:
            raise retry_later(503, "the service is stopping", 5)
        if len(self._queues.get(user, ())) >= self.queue_per_user:
            raise retry_later(
                429, f"{self.queue_per_user} archive requests of yours wait already", 5
            )
        if self.waiting >= self.queue_total:
            raise retry_later(503, "the archive workers' queue is full; retry shortly", 5)
        loop = asyncio.get_running_loop()
        start = time.monotonic() if since is None else since
        job = _Job(user, fn, args, time_s, loop.create_future(), start + self.start_wait_s)
        queue = self._queues.setdefault(user, deque())
        if not queue:
            self._order.append(user)
        queue.append(job)
        loop.call_at(loop.time() + max(0.0, job.deadline - time.monotonic()), self._expire, job)
        self._dispatch()
        return job

    def _expire(self, job: _Job) -> None:
        """A job still waiting at its deadline: 503 with Retry-After."""
        if job.task is None and not job.future.done():
            self._unqueue(job)
            job.future.set_exception(
                retry_later(
                    503,
                    f"the archive workers could not start this within "
                    f"{self.start_wait_s:.0f} s; retry shortly",
                    5,
                )
            )

    def _unqueue(self, job: _Job) -> None:
        queue = self._queues.get(job.user)
        if queue is not None and job in queue:
            queue.remove(job)
            if not queue:
                del self._queues[job.user]
                self._order.remove(job.user)

    def _abandon(self, job: _Job) -> None:
        if job.task is None:
            self._unqueue(job)
            job.future.cancel()
        else:
            job.task.cancel()  # _execute kills the worker

    def _next_job(self) -> _Job | None:
        """The first waiting job of the next user under their share, round-robin."""
        for _ in range(len(self._order)):
            user = self._order[0]
            self._order.rotate(-1)
            if self._running.get(user, 0) < self.share:
                job = self._queues[user][0]
                self._unqueue(job)
                return job
        return None

    def _dispatch(self) -> None:
        while not self._closed and self.running < self.workers:
            job = self._next_job()
            if job is None:
                return
            self._running[job.user] = self._running.get(job.user, 0) + 1
            job.task = asyncio.ensure_future(self._execute(job))
            self._tasks.add(job.task)
            job.task.add_done_callback(self._tasks.discard)

    async def _take_worker(self) -> _Worker:
        if self._idle:
            return self._idle.pop()
        spawn = asyncio.ensure_future(asyncio.to_thread(_Worker, self.memory_bytes))
        try:
            return await asyncio.shield(spawn)
        except asyncio.CancelledError:  # given up while starting: stop it once it is up
            spawn.add_done_callback(_kill_spawned)
            raise

    async def _execute(self, job: _Job) -> None:
        worker: _Worker | None = None
        reusable = False
        try:
            worker = await self._take_worker()
            job.worker = worker
            await asyncio.to_thread(worker.conn.send, (job.fn, job.args))
            async with asyncio.timeout(job.time_s):
                kind, value = await asyncio.to_thread(worker.conn.recv)
            reusable = True
            _settle(job.future, kind, value)
        except TimeoutError:
            _fail(job.future, _too_long(job.time_s))
        except (EOFError, OSError) as exc:
            _fail(job.future, ApiError(500, f"the archive worker stopped ({exc or 'killed'})"))
        except BaseException as exc:
            _fail(job.future, exc)
            if not isinstance(exc, asyncio.CancelledError | Exception):
                raise
        finally:
            self._finish(job, worker, reusable)

    def _finish(self, job: _Job, worker: _Worker | None, reusable: bool) -> None:
        left = self._running[job.user] - 1
        if left:
            self._running[job.user] = left
        else:
            del self._running[job.user]
        if worker is not None and reusable and not self._closed:
            self._idle.append(worker)
        elif worker is not None:
            self.killed += 0 if reusable else 1
            if worker.process.is_alive():
                worker.process.kill()  # at once; reaped in a thread
            asyncio.get_running_loop().run_in_executor(None, worker.kill)
        self._dispatch()

    async def close(self) -> None:
        """Stop every worker and refuse what waits (the service's shutdown)."""
        self._closed = True
        for queue in list(self._queues.values()):
            for job in list(queue):
                self._unqueue(job)
                _fail(job.future, retry_later(503, "the service is stopping", 5))
        tasks = list(self._tasks)
        for task in tasks:
            task.cancel()
        if tasks:
            await asyncio.wait(tasks, timeout=5)
        idle, self._idle = self._idle, []
        for worker in idle:
            await asyncio.to_thread(worker.kill)


def _kill_spawned(spawn: asyncio.Future[_Worker]) -> None:
    if not spawn.cancelled() and spawn.exception() is None:
        asyncio.get_running_loop().run_in_executor(None, spawn.result().kill)


async def _watch(gone: Callable[[], Awaitable[bool]]) -> None:
    while not await gone():
        await asyncio.sleep(0.5)


def _too_long(time_s: float) -> ApiError:
    return ApiError(
        503,
        f"the archive work took longer than {time_s:.0f} s and was stopped: ask for a "
        "shorter range, fewer topics or files, or use `modd dataset` on the base station",
        limit_s=time_s,
    )


def _settle(future: asyncio.Future[Any], kind: str, value: Any) -> None:
    if future.done():
        return
    if kind == "ok":
        future.set_result(value)
    else:
        future.set_exception(value)


def _fail(future: asyncio.Future[Any], exc: BaseException) -> None:
    if not future.done():
        if isinstance(exc, asyncio.CancelledError):
            future.cancel()
        else:
            future.set_exception(exc)
