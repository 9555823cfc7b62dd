"""The hot routes' store work in processes of their own (issue 41).

A model's read and save and its versions (deps.in_store) spend ~4 ms of
Python each (SQLAlchemy's ORM, the answer's JSON). In threads of the
service's process that Python holds the interpreter lock the event loop
needs: under 50 editors the loop waited for it behind the store threads, and
``/api/health``'s p99 was 3× a bare app's on the same cores. Here that work
runs in ``processes`` spawned worker processes, each with its own store
connection (the service migrated the store before they start): the event
loop only sends the request's arguments and receives the answer's bytes.

- A store process that dies (killed, out of memory) breaks the pool: the
  requests it held are answered 503 with ``Retry-After`` and a fresh pool
  replaces it for the next ones.
- A store process ends with the service (``PR_SET_PDEATHSIG`` on Linux) even
  when the service is killed without its shutdown.
- ``processes = 0`` (``Settings.store_processes``, the default of
  :class:`Settings` and so of tests building the app in-process) keeps the
  work in the service's own threads (deps.STORE_THREADS); so does a SQLite
  database in memory, which no other process can open.

>>> procs = StoreProcesses("sqlite:////tmp/modd.sqlite3", 2)       # doctest: +SKIP
>>> answer = await procs.run(token, (), work, (project_id,))        # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
import multiprocessing
import os
import signal
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, TypeVar

from .db import Store, sqlite_path
from .errors import retry_later
from .storework import store_work

T = TypeVar("T")
#: At most this many store processes (``Settings.store_processes``).
MAX_STORE_PROCESSES = 16
#: The store a store process opened (None in the service's own process).
_store: Store | None = None


def usable(url: str, processes: int) -> bool:
    """Whether the store at ``url`` can be shared with store processes."""
    return processes > 0 and (not url.startswith("sqlite:") or sqlite_path(url) is not None)


#: A store process's name (``ps -o comm``, /proc/PID/stat), apart from the
#: archive workers, which are also spawned children of the service.
PROCESS_NAME = b"modd-store"


def _die_with_parent(parent: int) -> None:
    """Linux: SIGTERM when the service's process ends (however it ends), and
    the name :data:`PROCESS_NAME`. A service gone before this (it ended
    while the process was starting) ends the process at once."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        libc.prctl(15, PROCESS_NAME)  # PR_SET_NAME
    except (OSError, AttributeError):  # another system: the pool's shutdown ends them
        pass
    if os.getppid() != parent:
        os._exit(0)


def _start(url: str, parent: int) -> None:
    """A store process's start: connect (no migration: the service did it)."""
    global _store
    _die_with_parent(parent)
    _store = Store.open(url, migrate_first=False)


def _ready() -> bool:
    return _store is not None


def _run(token: str, roles: tuple[Any, ...], fn: Callable[..., T], args: tuple[Any, ...]) -> T:
    assert _store is not None, "a store process opens its store when it starts"
    return store_work(_store, token, roles, fn, args)


class StoreProcesses:
    """``processes`` store worker processes (spawned: the service's threads
    are not copied), started at once and replaced together if one dies."""

    def __init__(self, url: str, processes: int) -> None:
        if not 1 <= processes <= MAX_STORE_PROCESSES:
            raise ValueError(f"store_processes must be 0..{MAX_STORE_PROCESSES}, not {processes}")
        self.url = url
        self.processes = processes
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        pool = ProcessPoolExecutor(
            self.processes,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_start,
            initargs=(self.url, os.getpid()),
        )
        for _ in range(self.processes):  # start them now, not on the first requests
            pool.submit(_ready)
        return pool

    async def run(
        self, token: str, roles: tuple[Any, ...], fn: Callable[..., T], args: tuple[Any, ...]
    ) -> T:
        """``fn(db, user, *args)`` for the session ``token`` in a store process
        (deps.store_work); its exceptions (401, 403, 404, 409, 422) are raised here."""
        pool = self._pool
        loop = asyncio.get_running_loop()
        try:
            return await loop.run_in_executor(pool, _run, token, roles, fn, args)
        except BrokenProcessPool:
            if self._pool is pool:
                self._pool = self._new_pool()
                pool.shutdown(wait=False, cancel_futures=True)
            detail = "a store process stopped during the request (read the head before saving)"
            raise retry_later(503, detail, 1) from None

    def close(self) -> None:
        """Stop the store processes (at the service's end: uvicorn has waited
        for its requests). Terminated, not only told to stop: one ended while
        it read its queue (killed, or its starting thread gone) leaves the
        queue's lock taken and the others waiting for it, and the service's
        exit waiting for them."""
        pool = self._pool
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
