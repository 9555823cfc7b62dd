"""When each drone-side publisher of a load is due: the one schedule the load
processes of every system (MQTT, zenoh) publish on, so they offer the same load."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Sequence


def publisher_ticks(
    periods_s: Sequence[float], seconds: float, stopped: Callable[[], bool]
) -> Iterator[tuple[int, int]]:
    """``(publisher index, wall-clock ns)`` each time a publisher is due, earliest
    first, sleeping until then, for ``seconds`` or until ``stopped()``."""
    start = time.monotonic()
    due = [start + p for p in periods_s]
    while not stopped() and time.monotonic() - start < seconds:
        i = min(range(len(due)), key=lambda k: due[k])
        delay = due[i] - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        yield i, time.time_ns()
        due[i] += periods_s[i]
