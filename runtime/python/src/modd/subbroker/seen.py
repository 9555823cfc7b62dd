"""The windows a subscriber has had, by identity (docs/fleet.md, "A window's
identity"): the point where a window two stations sent (two serving for a moment
after a partition heals, a backfill racing the live value) is kept once. Used by
the Python subscriber API and the backend (every value it relays or keeps).

Windows are remembered as runs of consecutive indices per (drone, subscriber,
period) and epoch, not one entry each: live windows come in order, so an hour of a
4 Hz subscription is one run, and memory stays flat over a mission. Bounded: at most
:data:`MAX_RUNS` runs per key, the oldest (lowest epoch, then lowest window) out
first, and at most :data:`MAX_KEYS` keys, the least recently heard out first. A
window forgotten that way passes again.

The period is part of what is compared: a window's identity names it on its
configuration's grid, and a dynamic subscription cancelled and made again under the
same name with another period, in the same configuration, numbers its windows on
another grid (its window 3 is not the first one's). A genuine repeat is the same
payload, period included, so comparing it drops none.

>>> seen = Seen()
>>> [seen.first(("usv", "s", "0.25", 1, k)) for k in (0, 1, 0, 3, 2, 3)]
[True, True, False, True, True, False]
>>> seen.first(("usv", "s", "0.25", 2, 0)), seen.first(("usv", "t", "0.25", 1, 0))
(True, True)
>>> seen.first(("usv", "s", "1", 1, 3))  # the name made again with another period
True
"""

from __future__ import annotations

import bisect
import threading
from collections import OrderedDict
from collections.abc import Mapping
from typing import Any

from .payload import DeliveredValue

#: Runs of windows remembered per (drone, subscriber, period): one per gap left unfilled.
MAX_RUNS = 1024
#: (drone, subscriber, period) keys remembered: the least recently heard go first.
MAX_KEYS = 1024
#: A window's identity with its period: (drone, subscriber, period_s, epoch_ns, window).
Identity = tuple[str, str, str, int, int]
_AFTER = float("inf")  # sorts after any run starting at the same (epoch, window)


class Runs:
    """The windows of one (drone, subscriber, period): sorted, merged runs
    ``(epoch, first, end)`` (``end`` exclusive), at most ``limit``.

    >>> r = Runs(); [r.first(5, k) for k in (0, 2, 1, 1)], r.runs
    ([True, True, True, False], [(5, 0, 3)])
    """

    def __init__(self, limit: int = MAX_RUNS) -> None:
        self.limit = limit
        self.runs: list[tuple[int, int, int]] = []

    def first(self, epoch: int, window: int) -> bool:
        """True the first time (epoch, window) comes (it is remembered), else False."""
        runs = self.runs
        i = bisect.bisect_right(runs, (epoch, window, _AFTER))  # runs[:i] start at or before it
        start, end, a, b = window, window + 1, i, i  # runs[a:b] become (epoch, start, end)
        if i and runs[i - 1][0] == epoch:
            _, first, last = runs[i - 1]
            if window < last:
                return False
            if last == window:
                start, a = first, i - 1
        if i < len(runs) and runs[i][0] == epoch and runs[i][1] == end:
            end, b = runs[i][2], i + 1
        runs[a:b] = [(epoch, start, end)]
        if len(runs) > self.limit:
            del runs[0]
        return True


class Seen:
    """The windows had so far, per (drone, subscriber, period); safe from several
    threads (zenoh calls back from its own)."""

    def __init__(self, runs: int = MAX_RUNS, keys: int = MAX_KEYS) -> None:
        self.runs, self.keys = runs, keys
        self._by_key: OrderedDict[tuple[str, str, str], Runs] = OrderedDict()
        self._lock = threading.Lock()

    def first(self, identity: Identity) -> bool:
        """True the first time ``identity`` comes (it is remembered), else False."""
        drone, subscriber, period, epoch, window = identity
        k = (drone, subscriber, period)
        with self._lock:
            runs = self._by_key.get(k)
            if runs is None:
                runs = self._by_key[k] = Runs(self.runs)
                if len(self._by_key) > self.keys:
                    self._by_key.popitem(last=False)
            else:
                self._by_key.move_to_end(k)
            return runs.first(epoch, window)


def identity(value: DeliveredValue) -> Identity | None:
    """(drone, subscriber, period_s, epoch_ns, window), or None for a payload without it."""
    if value.drone is None or value.epoch_ns is None or value.window is None:
        return None
    return (value.drone, value.subscriber, value.period_s, value.epoch_ns, value.window)


def identity_of(doc: Mapping[str, Any]) -> Identity | None:
    """The identity of a parsed payload (a JSON object), or None when it has none
    or a malformed one: such a payload is passed on as it is, never dropped.

    >>> doc = {"drone": "usv", "subscriber": "s", "period_s": "1", "epoch_ns": 7, "window": 2}
    >>> identity_of(doc)
    ('usv', 's', '1', 7, 2)
    >>> identity_of({"subscriber": "s", "topic": "usv.a.x"}) is None
    True
    """
    drone, subscriber, period = doc.get("drone"), doc.get("subscriber"), doc.get("period_s")
    epoch, window = doc.get("epoch_ns"), doc.get("window")
    if not (isinstance(drone, str) and isinstance(subscriber, str) and isinstance(period, str)):
        return None
    if not (isinstance(epoch, int) and isinstance(window, int)):
        return None
    if isinstance(epoch, bool) or isinstance(window, bool):
        return None
    return (drone, subscriber, period, epoch, window)
