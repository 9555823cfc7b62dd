"""Derived windows built by window INDEX, not by arrival order (sans-I/O: fed
source windows, returns the derived windows they complete).

A derived stream of period ``k·P`` takes, for its window ``j`` (the one that
ends at ``j·k·P`` after the config epoch), the source windows ``(j−1)·k+1 ..
j·k`` of each sent stream it comes from (window ``i`` of a sent stream of
period ``P`` ends at ``i·P``). They may arrive in any order: a window repaired
by a NACK's resend comes seconds late, after later ones. Each derived window is
completed, and so returned, **once**; its partial state is kept while it may
still complete:

* at most :data:`MAX_PENDING` partial windows per derived stream (the oldest
  is given up first), and none whose end is more than :data:`HOLD_US` before
  the newest source window seen (a resend comes within the NACK's give-up
  horizon, 5 asks of at most the accepted delay: well under 30 s);
* a window given up is not delivered live: the window record does not count
  it, so it is a gap that backfill fills from the archive.

An empty source window (no sample: the link carries it as absent, ``None``)
is a window that arrived; only a window that never arrives keeps its derived
window from completing (docs/subbroker.md, "Derived windows").

>>> a = Assembly(((0, 2),))
>>> a.add(0, 2, 5.0), a.add(0, 1, 3.0)  # window 2 first, then the late window 1
([], [(1, [[3.0, 5.0]])])
>>> a.add(0, 1, 3.0)  # the same window again: completed already
[]
"""

from __future__ import annotations

from typing import Any

#: Partial derived windows kept per derived stream.
MAX_PENDING = 64
#: A partial derived window whose end is this far behind the newest source window is given up.
HOLD_US = 30_000_000

_MISSING = object()


class _Partial:
    __slots__ = ("missing", "parts")

    def __init__(self, factors: tuple[int, ...]) -> None:
        self.parts: list[list[Any]] = [[_MISSING] * k for k in factors]
        self.missing = sum(factors)


class Assembly:
    """The derived windows of one derived stream from its sources.

    ``sources``: ``(source position, factor)`` per source, in the derivation's
    order (the position is the caller's, e.g. the sent stream's id; a source
    appears once). ``period_us``: the derived stream's period (for the horizon).
    """

    def __init__(self, sources: tuple[tuple[int, int], ...], period_us: int = 1) -> None:
        self.sources = sources
        self._factors = tuple(k for _, k in sources)
        self._index = {sid: n for n, (sid, _) in enumerate(sources)}
        self._period = period_us
        self._pending: dict[int, _Partial] = {}
        self._done: dict[int, None] = {}  # completed, in completion order (about j order)
        self._newest = 0  # newest derived window index touched
        self.given_up = 0  # partial windows dropped (their gap is for backfill)

    @property
    def pending(self) -> int:
        return len(self._pending)

    def add(self, sid: int, index: int, window: Any) -> list[tuple[int, list[list[Any]]]]:
        """Source window ``index`` (≥ 1) of source ``sid``; the derived windows
        it completes as ``(j, parts)``, ``parts`` in source order, each the
        source's ``k`` windows in time order."""
        n = self._index.get(sid)
        if n is None or index < 1:
            return []
        k = self._factors[n]
        j = -(-index // k)
        if j in self._done or self._too_old(j):
            return []
        partial = self._pending.get(j)
        if partial is None:
            partial = self._pending[j] = _Partial(self._factors)
        slot = index - (j - 1) * k - 1
        if partial.parts[n][slot] is _MISSING:
            partial.missing -= 1
        partial.parts[n][slot] = window
        out: list[tuple[int, list[list[Any]]]] = []
        if partial.missing == 0:
            del self._pending[j]
            self._done[j] = None
            out.append((j, partial.parts))
        if j > self._newest:
            self._newest = j
            self._prune()
        elif len(self._pending) > MAX_PENDING:
            self._prune()
        return out

    def _too_old(self, j: int) -> bool:
        return (self._newest - j) * self._period > HOLD_US

    def _prune(self) -> None:
        for j in [j for j in self._pending if self._too_old(j)]:
            del self._pending[j]
            self.given_up += 1
        while len(self._pending) > MAX_PENDING:
            del self._pending[min(self._pending)]
            self.given_up += 1
        done = self._done
        while done and self._too_old(next(iter(done))):
            del done[next(iter(done))]
