"""Shared session watches: every socket open on the same session (and roles)
awaits one watch, which asks ``check`` every ``every_s`` and hands its verdict
to all of them at once (sessionwatch.py uses it for the backend's sockets)."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

Seen = tuple[int, str]
Verdict = tuple[int, str]


def verdict(now: Seen | None, seen: Seen) -> Verdict | None:
    """The close code and reason once a session ended (4401) or its roles
    changed (4403); None while it holds.

    >>> verdict(None, (1, "admin")), verdict((1, ""), (1, "admin")), verdict((1, "a"), (1, "a"))
    ((4401, 'the session ended'), (4403, 'your roles changed; reconnect'), None)
    """
    if now is None:
        return 4401, "the session ended"
    if now != seen:
        return 4403, "your roles changed; reconnect"
    return None


@dataclass
class _Watch:
    ended: asyncio.Future[Verdict]
    task: asyncio.Task[None] | None = None
    sockets: int = 0


class SessionWatches:
    """Shared watches by (token, seen) on the event loop; ``check`` answers
    the session's state now (a store query, run in a worker thread)."""

    def __init__(self, check: Callable[[str], Awaitable[Seen | None]], every_s: float) -> None:
        self._check = check
        self.every_s = every_s
        self._watches: dict[tuple[str, Seen], _Watch] = {}

    def __len__(self) -> int:
        return len(self._watches)

    async def wait(self, token: str, seen: Seen) -> Verdict:
        """Returns when the session ends or its roles change."""
        key = (token, seen)
        watch = self._watches.get(key)
        if watch is None:
            watch = _Watch(asyncio.get_running_loop().create_future())
            watch.task = asyncio.create_task(self._poll(token, seen, watch))
            self._watches[key] = watch
        watch.sockets += 1
        try:
            return await asyncio.shield(watch.ended)
        finally:
            watch.sockets -= 1
            if watch.sockets == 0 and self._watches.get(key) is watch:
                del self._watches[key]
                if watch.task is not None:
                    watch.task.cancel()

    async def _poll(self, token: str, seen: Seen, watch: _Watch) -> None:
        while True:
            await asyncio.sleep(self.every_s)
            with contextlib.suppress(Exception):  # a store hiccup: ask again next time
                ended = verdict(await self._check(token), seen)
                if ended is not None:
                    self._watches.pop((token, seen), None)
                    watch.ended.set_result(ended)
                    return
