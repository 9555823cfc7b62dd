"""Is the SubBroker keeping up with the link? Measured after every DATA slot
it delivers, reported in the status (docs/subbroker.md, "Status") and logged
once per change, so that falling behind is never silent buffering.

Two signs, either one is enough:

- **lag**: how much later than usual a slot's delivery ends, measured from
  the window's end. ``now - end_ns`` mixes the link's latency and the offset
  between the drone's clock and the base station's; its smallest value since
  the link came up is taken as the baseline, and ``lag_s`` is the excess over
  it. A SubBroker that keeps up stays within milliseconds of it; one that falls
  behind sees it grow with the queue.
- **backlog**: bytes received but not yet decoded: the kernel's receive queue
  of the link socket (``FIONREAD``) plus the frame splitter's buffer. Near zero
  when the SubBroker keeps up: it reads each frame as it comes.

``behind`` turns on when the lag passes ``behind_lag_s`` or the backlog
passes ``behind_backlog_bytes``, and off again only when both are back under
half of these (hysteresis: one state change per episode, not one per slot).

Logged: the first episode of a quiet minute as it happens, the episodes
after it within ``log_every_s`` summed up in one line (:class:`ChangeLog`):
over a radio, a NACKed slot that arrives late is a short episode, and one
line per episode was ~15 MB of log a day.

>>> bp = Backpressure(behind_lag_s=1.0)
>>> bp.observe(end_ns=0, backlog_bytes=0, now_ns=5_000_000)        # baseline 5 ms
>>> bp.observe(end_ns=10**9, backlog_bytes=0, now_ns=2_600_000_000)  # 1.595 s late
>>> bp.as_dict()["behind"], bp.as_dict()["lag_s"]
(True, 1.595)
"""

from __future__ import annotations

import contextlib
import fcntl
import logging
import socket
import struct
import termios
import threading
from typing import Any

log = logging.getLogger("modd.subbroker.backpressure")

#: Lag over the baseline that makes the SubBroker report it is behind (s).
BEHIND_LAG_S = 1.0
#: Undecoded bytes that make it report it is behind (the TCP receive queue is filling).
BEHIND_BACKLOG_BYTES = 256 * 1024
#: At most one log line of state changes per this many seconds, after the first.
LOG_EVERY_S = 60.0


def socket_backlog(sock: socket.socket | None) -> int:
    """Bytes in the socket's receive queue not yet read (0 when unknown)."""
    if sock is None:
        return 0
    with contextlib.suppress(OSError, ValueError):
        raw = fcntl.ioctl(sock.fileno(), termios.FIONREAD, b"\0\0\0\0")
        return int(struct.unpack("i", raw)[0])
    return 0


class ChangeLog:
    """The log lines of the state changes: an episode (falling behind, catching up)
    that begins ``every_s`` after the last one logged is logged as it happens; the
    episodes that begin within ``every_s`` of it are counted and logged as one line
    when the interval ends (then one line per interval while they go on).

    >>> c = ChangeLog(60.0)
    >>> c.change(True, 1.2, 0, now_ns=0)            # logged: falling behind
    >>> c.change(False, 0.1, 0, now_ns=10**9)       # logged: caught up
    >>> for t in range(2, 22): c.change(t % 2 == 0, 1.5, 0, now_ns=t * 10**9)
    >>> c.summary(now_ns=61 * 10**9).split(";")[0]    # the 20 changes, in one line
    'over the last 61 s: fell behind the link 10 times, caught up 10 times (lag up to 1.50 s)'
    """

    def __init__(self, every_s: float = LOG_EVERY_S) -> None:
        self.every_ns = int(every_s * 1e9)
        self._since: int | None = None  # when the logged episode began (None: quiet)
        self._logging = False  # the episode under way is the logged one
        self._fell = self._caught = 0
        self._max_lag = 0.0
        self._behind = False

    def change(self, behind: bool, lag: float, backlog: int, now_ns: int) -> None:
        self.tick(now_ns)
        self._behind = behind
        if behind and self._since is None:
            self._since, self._logging = now_ns, True
            log.warning(
                "falling behind the link: delivery %.2f s later than its best, "
                "%d bytes waiting to be decoded",
                lag,
                backlog,
            )
        elif not behind and self._logging:
            self._logging = False
            log.info("caught up with the link (lag %.3f s, %d bytes waiting)", lag, backlog)
        else:
            self._logging = False
            self._fell += int(behind)
            self._caught += int(not behind)
            self._max_lag = max(self._max_lag, lag)

    def tick(self, now_ns: int) -> None:
        """The end of an interval: its changes in one line."""
        line = self.summary(now_ns)
        if line:
            log.warning("%s", line)

    def summary(self, now_ns: int) -> str:
        """The line of the interval once it is over ("" before, or when nothing is
        counted); a new interval begins when something was."""
        if self._since is None or now_ns - self._since < self.every_ns:
            return ""
        if not self._fell and not self._caught:
            self._since = None
            return ""
        line = (
            f"over the last {(now_ns - self._since) / 1e9:.0f} s: fell behind the link "
            f"{self._fell} times, caught up {self._caught} times (lag up to "
            f"{self._max_lag:.2f} s); now {'behind' if self._behind else 'caught up'}"
        )
        self._since, self._fell, self._caught, self._max_lag = now_ns, 0, 0, 0.0
        return line


class Backpressure:
    """The behind/caught-up state; the link thread observes, any thread reads."""

    def __init__(
        self,
        behind_lag_s: float = BEHIND_LAG_S,
        behind_backlog_bytes: int = BEHIND_BACKLOG_BYTES,
        log_every_s: float = LOG_EVERY_S,
    ) -> None:
        self.behind_lag_s = behind_lag_s
        self.behind_backlog_bytes = behind_backlog_bytes
        self._changes = ChangeLog(log_every_s)
        self._lock = threading.Lock()
        self._baseline_ns: int | None = None
        self.lag_s: float | None = None
        self.backlog_bytes = 0
        self.max_lag_s = 0.0
        self.behind = False
        self.since_ns: int | None = None  # when the current state began
        self.episodes = 0  # times it fell behind

    def observe(self, end_ns: int, backlog_bytes: int, now_ns: int) -> None:
        """One slot delivered at ``now_ns`` (base clock); its window ended at
        ``end_ns`` (drone clock); ``backlog_bytes`` still wait to be decoded."""
        raw = now_ns - end_ns
        with self._lock:
            if self._baseline_ns is None or raw < self._baseline_ns:
                self._baseline_ns = raw
            lag = (raw - self._baseline_ns) / 1e9
            self.lag_s, self.backlog_bytes = lag, backlog_bytes
            self.max_lag_s = max(self.max_lag_s, lag)
            if not self.behind and (
                lag > self.behind_lag_s or backlog_bytes > self.behind_backlog_bytes
            ):
                self.behind, self.since_ns = True, now_ns
                self.episodes += 1
                self._changes.change(True, lag, backlog_bytes, now_ns)
            elif (
                self.behind
                and lag < self.behind_lag_s / 2
                and backlog_bytes < self.behind_backlog_bytes / 2
            ):
                self.behind, self.since_ns = False, now_ns
                self._changes.change(False, lag, backlog_bytes, now_ns)
            else:
                self._changes.tick(now_ns)

    def reset(self, now_ns: int) -> None:
        """A new link session: the baseline is measured again."""
        with self._lock:
            self._baseline_ns = None
            self.lag_s, self.backlog_bytes = None, 0
            if self.behind:
                self.behind, self.since_ns = False, now_ns
                log.info("link reconnected: the lag is measured afresh")

    def as_dict(self) -> dict[str, Any]:
        """The status fields: ``behind``, ``lag_s``, ``max_lag_s``,
        ``recv_backlog_bytes``, ``behind_since_ns``, ``behind_episodes``."""
        with self._lock:
            return {
                "behind": self.behind,
                "lag_s": None if self.lag_s is None else round(self.lag_s, 3),
                "max_lag_s": round(self.max_lag_s, 3),
                "recv_backlog_bytes": self.backlog_bytes,
                "behind_since_ns": self.since_ns if self.behind else None,
                "behind_episodes": self.episodes,
            }
