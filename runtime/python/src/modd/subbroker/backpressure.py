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


def socket_backlog(sock: socket.socket | None) -> int:
    """Bytes in the socket's receive queue not yet read (0 when unknown)."""
    if sock is None:
        return 0
    with contextlib.suppress(OSError, ValueError):
        raw = fcntl.ioctl(sock.fileno(), termios.FIONREAD, b"\0\0\0\0")
        return int(struct.unpack("i", raw)[0])
    return 0


class Backpressure:
    """The behind/caught-up state; the link thread observes, any thread reads."""

    def __init__(self, behind_lag_s: float = BEHIND_LAG_S,
                 behind_backlog_bytes: int = BEHIND_BACKLOG_BYTES) -> None:
        self.behind_lag_s = behind_lag_s
        self.behind_backlog_bytes = behind_backlog_bytes
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
            if not self.behind and (lag > self.behind_lag_s
                                    or backlog_bytes > self.behind_backlog_bytes):
                self.behind, self.since_ns = True, now_ns
                self.episodes += 1
                log.warning("falling behind the link: delivery %.2f s later than its best, "
                            "%d bytes waiting to be decoded", lag, backlog_bytes)
            elif self.behind and lag < self.behind_lag_s / 2 \
                    and backlog_bytes < self.behind_backlog_bytes / 2:
                self.behind, self.since_ns = False, now_ns
                log.info("caught up with the link (lag %.3f s, %d bytes waiting)",
                         lag, backlog_bytes)

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
