"""A WebSocket relayed to a server the backend runs on loopback (the 3D
scene's viser, the Foxglove live and replay servers), behind the workbench's
rules, checked at the upgrade (docs/security.md):

- the ``Origin`` must be this service's own or a configured CORS origin (a
  desktop viewer sends none, or with a ticket an opaque one: ``null``);
- a session: an ``Authorization: Bearer`` header, the session cookie (only
  with an Origin: a browser), or, where the route allows it, a viewer ticket
  in the URL (tickets.py, spent on use);
- a role, and a free socket slot of the user and address (socketcaps.py,
  4429 otherwise); then frames flow both ways until either side closes, and
  the socket is closed (4401/4403) within ``ws_recheck_s`` of a logout,
  expiry or role change (sessionwatch.py: one shared check per session)."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable
from typing import Any

from starlette.concurrency import run_in_threadpool
from starlette.websockets import WebSocket, WebSocketDisconnect
from websockets.asyncio.client import ClientConnection
from websockets.exceptions import ConnectionClosed, InvalidHandshake

from .accounts import session_state
from .deps import SESSION_COOKIE, AppState
from .roles import parse_roles
from .sessionwatch import watch_session
from .socketcaps import CAP_CLOSE, SocketFull

Seen = tuple[int, str]
#: Origins of desktop viewers (an Electron page loaded from a file), allowed
#: with a ticket only: a ticket comes from a signed-in user, never a cookie.
OPAQUE_ORIGINS = frozenset({"null", "file://"})


def socket_token(websocket: WebSocket) -> str | None:
    """The session of a WebSocket upgrade: an ``Authorization: Bearer``
    header, or the cookie when the browser named an Origin (checked before)."""
    auth = websocket.headers.get("authorization", "")
    if auth.lower().startswith("bearer ") and len(auth) < 300:
        return auth[7:].strip()
    if websocket.headers.get("origin") is not None:
        return websocket.cookies.get(SESSION_COOKIE)
    return None


def _session(state: AppState, token: str) -> Seen | None:
    with state.store.session() as db:
        return session_state(db, token)


async def admit(
    websocket: WebSocket, state: AppState, what: str, *, ticket_kind: str | None = None
) -> tuple[str, Seen] | None:
    """The session and roles of an upgrade, or None once it is refused
    (closed with 4403 for an Origin or a missing role, 4401 without a session).
    ``ticket_kind``: the route takes viewer tickets of that kind (tickets.py)."""
    from .routers.live import origin_allowed

    ticket = websocket.query_params.get("ticket") if ticket_kind is not None else None
    opaque = ticket is not None and websocket.headers.get("origin") in OPAQUE_ORIGINS
    if not (opaque or origin_allowed(websocket, state.settings)):
        await websocket.close(code=4403, reason="Origin not allowed")
        return None
    token = (
        state.tickets.redeem(ticket, ticket_kind or "")
        if ticket is not None
        else socket_token(websocket)
    )
    seen = None if token is None else await run_in_threadpool(_session, state, token)
    if token is None or seen is None:
        await websocket.close(code=4401, reason=f"{what} needs a session or a fresh ticket")
        return None
    if not parse_roles(seen[1]):
        await websocket.close(code=4403, reason=f"{what} needs a role")
        return None
    return token, seen


async def relay(
    websocket: WebSocket,
    state: AppState,
    admitted: tuple[str, Seen],
    connect: Callable[[], Awaitable[ClientConnection]],
    what: str,
) -> None:
    """Take a socket slot of the user (socketcaps.py), connect upstream,
    accept ``websocket`` with the upstream's subprotocol and relay frames
    both ways until either side closes or the session ends."""
    token, seen = admitted
    address = websocket.client.host if websocket.client is not None else "unknown"
    try:
        with state.socket_caps.slot(seen[0], address):
            try:
                upstream = await connect()
            except (OSError, TimeoutError, ConnectionClosed, InvalidHandshake) as exc:
                await websocket.close(code=1011, reason=f"{what} did not answer: {exc}"[:120])
                return
            try:
                await _pump(websocket, upstream, state, token, seen)
            finally:
                await upstream.close()
    except SocketFull as exc:
        await websocket.close(code=CAP_CLOSE, reason=str(exc)[:120])


async def _pump(
    websocket: WebSocket, upstream: ClientConnection, state: AppState, token: str, seen: Seen
) -> None:
    await websocket.accept(subprotocol=upstream.subprotocol)
    tasks = {
        asyncio.create_task(_down(upstream, websocket)),
        asyncio.create_task(_up(websocket, upstream)),
        asyncio.create_task(watch_session(state, token, seen)),
    }
    done, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
    for task in pending:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError, Exception):
            await task
    ended: Any = None
    for task in done:
        if not task.cancelled() and task.exception() is None:
            ended = task.result() or ended
    code, reason = ended if isinstance(ended, tuple) else (1000, "")
    with contextlib.suppress(Exception):
        await websocket.close(code=code, reason=reason)


async def _down(upstream: ClientConnection, websocket: WebSocket) -> None:
    with contextlib.suppress(ConnectionClosed, RuntimeError, WebSocketDisconnect):
        async for message in upstream:
            if isinstance(message, bytes):
                await websocket.send_bytes(message)
            else:
                await websocket.send_text(message)


async def _up(websocket: WebSocket, upstream: ClientConnection) -> None:
    with contextlib.suppress(ConnectionClosed, RuntimeError, WebSocketDisconnect):
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                return
            if message.get("bytes") is not None:
                await upstream.send(message["bytes"])
            elif message.get("text") is not None:
                await upstream.send(message["text"])
