"""The re-check of an open WebSocket's session, for the live streams, the 3D
scene and the Foxglove proxies alike (docs/security.md, "Revocation").

One check per session, not per socket: every socket open on the same session
(and roles) awaits one shared watch, which asks the store every
``ws_recheck_s`` and hands its verdict to all of them at once. So a thousand
sockets of one user cost what one does (before: a store query per socket
every 0.4 s in the shared thread pool, which slowed every save)."""

from __future__ import annotations

from starlette.concurrency import run_in_threadpool

from .accounts import session_state
from .deps import AppState
from .sessionwatches import Seen, SessionWatches, Verdict


def _recheck(state: AppState, token: str) -> Seen | None:
    with state.store.session() as db:
        return session_state(db, token)


def watches_for(state: AppState) -> SessionWatches:
    """The state's shared watches (made on first use, on the event loop)."""
    if state.session_watches is None:

        async def check(token: str) -> Seen | None:
            return await run_in_threadpool(_recheck, state, token)

        state.session_watches = SessionWatches(check, state.settings.ws_recheck_s)
    watches: SessionWatches = state.session_watches
    return watches


async def watch_session(state: AppState, token: str, seen: Seen) -> Verdict:
    """The close code and reason once the session ends (logout, expiry, a
    password change, deletion: 4401) or the user's roles change (4403)."""
    return await watches_for(state).wait(token, seen)
