"""The re-check of an open WebSocket's session, for the live streams and the
3D scene's proxy alike (docs/security.md, "Revocation")."""

from __future__ import annotations

import asyncio

from starlette.concurrency import run_in_threadpool

from .accounts import session_state
from .deps import AppState


def _recheck(state: AppState, token: str) -> tuple[int, str] | None:
    with state.store.session() as db:
        return session_state(db, token)


async def watch_session(state: AppState, token: str, seen: tuple[int, str]) -> tuple[int, str]:
    """Re-check the session every ``ws_recheck_s``; the close code and reason once
    it ends (logout, expiry, a password change, deletion: 4401) or the user's
    roles change (4403)."""
    while True:
        await asyncio.sleep(state.settings.ws_recheck_s)
        now = await run_in_threadpool(_recheck, state, token)
        if now is None:
            return 4401, "the session ended"
        if now != seen:
            return 4403, "your roles changed; reconnect"
