"""The archive routes' work (reading an MCAP topic, formatting CSV, reducing a
series) in a small pool of worker processes, never in the service's own
process: a reader of a large file is pure Python, and several of them in
the worker threads would hold the interpreter lock away from the event loop,
so ``/api/health`` and every light route would wait behind them (issue 23:
health stalled 4-20 s during 40-70 parallel CSV exports). The heavy-route
limiter (guards.HeavyLimiter) bounds how many wait here.

>>> text = await in_worker(csv_text, path, "usv.a.x", None, None)   # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
import csv
import io
import multiprocessing
import threading
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any, TypeVar

from .archives import Sample, read_topic, reduce_minmax

#: Worker processes reading archives (the machine's cores are shared with the brokers).
ARCHIVE_WORKERS = 2
T = TypeVar("T")
_pool: ProcessPoolExecutor | None = None
_lock = threading.Lock()


def csv_text(path: Path, topic: str, start_ns: int | None, end_ns: int | None) -> str:
    """Every sample of the range, unreduced: ``log_time_ns,topic,value``."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["log_time_ns", "topic", "value"])
    for t, v in read_topic(path, topic, start_ns, end_ns):
        writer.writerow([t, topic, v])
    return out.getvalue()


def series(
    path: Path, topic: str, start_ns: int | None, end_ns: int | None, max_points: int
) -> tuple[int, list[Sample]]:
    """(how many samples the range holds, at most ``max_points`` of them)."""
    samples = read_topic(path, topic, start_ns, end_ns)
    return len(samples), reduce_minmax(samples, max_points)


def _get_pool() -> ProcessPoolExecutor:
    global _pool
    with _lock:
        if _pool is None:
            _pool = ProcessPoolExecutor(
                ARCHIVE_WORKERS, mp_context=multiprocessing.get_context("spawn")
            )
        return _pool


async def in_worker(fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)`` in a worker process (a broken pool is replaced once)."""
    for attempt in (1, 2):
        pool = _get_pool()
        try:
            return await asyncio.wrap_future(pool.submit(fn, *args))
        except BrokenProcessPool:
            global _pool
            with _lock:
                if _pool is pool:
                    _pool = None
            if attempt == 2:
                raise
    raise AssertionError("unreachable")


def shutdown_pool() -> None:
    """Stop the workers (the service's shutdown)."""
    global _pool
    with _lock:
        pool, _pool = _pool, None
    if pool is not None:
        pool.shutdown(wait=True, cancel_futures=True)


#: The most samples one export from the browser may hold (about a day of 100 Hz on
#: 100 topics is 860 M: a scientist exports that with ``modd dataset``, not a browser).
MAX_EXPORT_SAMPLES = 20_000_000


def dataset_file(
    paths: list[Path],
    model: dict[str, Any],
    fmt: str,
    out: Path,
    start_ns: int | None,
    end_ns: int | None,
    topics: list[str] | None,
    resample_s: float | None,
    max_samples: int,
    received: bool = False,
    metadata: dict[str, Any] | None = None,
) -> tuple[list[str], int | None, int | None]:
    """``modd dataset`` (``--received`` with ``received``) into ``out`` (in a
    worker), with the dataset ``metadata`` (the object of a ``dataset.yaml``);
    its notes and the time span written (ns). Raises DatasetError."""
    from modd.dataset.build import DatasetError, make_dataset
    from modd.dataset.export import Options
    from modd.dataset.metadata import MetadataError, parse_metadata

    try:
        meta = parse_metadata(metadata, "metadata") if metadata is not None else None
    except MetadataError as exc:
        raise DatasetError(str(exc)) from None

    summary = make_dataset(
        paths,
        model,
        fmt,
        out,
        start_ns=start_ns,
        end_ns=end_ns,
        topics=topics,
        resample_s=resample_s,
        options=Options(max_samples=max_samples),
        received=received,
        metadata=meta,
    )
    return summary.notes, summary.start_ns, summary.end_ns
