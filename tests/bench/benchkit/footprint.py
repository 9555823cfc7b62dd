"""CPU and memory of a process from /proc, sampled over a run: CPU % of one core over the
whole interval (utime + stime), RSS (VmRSS) sampled every ``period_s``, median and peak."""

from __future__ import annotations

import os
import statistics
import threading
import time
from dataclasses import dataclass
from pathlib import Path

CLK_TCK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int, tid: int | None = None) -> float:
    """User + system CPU time of the process (all its threads), or of one thread."""
    path = f"/proc/{pid}/task/{tid}/stat" if tid else f"/proc/{pid}/stat"
    fields = Path(path).read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / CLK_TCK


def rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError(f"no VmRSS for pid {pid}")


@dataclass(frozen=True)
class Footprint:
    cpu_percent: float  # of one core, over the interval
    cpu_seconds: float
    seconds: float
    rss_median_kb: int
    rss_peak_kb: int


class Sampler:
    """Samples one process from start() to stop() on a thread of its own."""

    def __init__(self, pid: int, period_s: float = 0.5) -> None:
        self.pid, self.period_s = pid, period_s
        self._rss: list[int] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self) -> Sampler:
        self._cpu0, self._t0 = cpu_seconds(self.pid), time.monotonic()
        self._rss.append(rss_kb(self.pid))
        self._thread.start()
        return self

    def _run(self) -> None:
        while not self._stop.wait(self.period_s):
            self._rss.append(rss_kb(self.pid))

    def stop(self) -> Footprint:
        cpu1, t1 = cpu_seconds(self.pid), time.monotonic()
        self._stop.set()
        self._thread.join()
        self._rss.append(rss_kb(self.pid))
        cpu = cpu1 - self._cpu0
        return Footprint(
            cpu_percent=100 * cpu / (t1 - self._t0),
            cpu_seconds=cpu,
            seconds=t1 - self._t0,
            rss_median_kb=int(statistics.median(self._rss)),
            rss_peak_kb=max(self._rss),
        )
