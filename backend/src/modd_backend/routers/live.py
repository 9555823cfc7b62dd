"""Live data: one WebSocket per browser and drone multiplexing the
subscriptions the page asks for (docs/backend.md, "Live relay"), and dynamic
subscriptions over REST.

Client messages: ``{"op": "auth", "token": T}`` first (API clients
without the session cookie), ``{"op": "subscribe"|"unsubscribe", "subscriber": NAME}``,
``{"op": "dynamic", "topic", "period_s", "aggregation", ["subscriber"]}``,
``{"op": "cancel", "subscriber": NAME}``, ``{"op": "ping"}``,
``{"op": "watch"|"unwatch", "project": ID}`` (saves of a project); an optional
``"id"`` is echoed. Server messages carry a ``type``: value, status, dropped,
subscribed, unsubscribed, dynamic, pong, watching, unwatched, saved, error. A
socket opened with ``?batch=1`` gets what is queued at each wake-up of its
sender as one ``{"type": "batch", "messages": [...]}`` frame (in order; a lone
message as itself)."""

from __future__ import annotations

import asyncio
import contextlib
import json
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, WebSocket, WebSocketDisconnect
from modd_contracts.keys import check_name
from modd_model.jsondepth import loads_bounded
from pydantic import BaseModel, Field
from starlette.concurrency import run_in_threadpool

from ..accounts import user_for_token
from ..deps import (
    SESSION_COOKIE,
    AppState,
    StateDep,
    UserDep,
    has_role,
    require,
    roles_of,
    ws_state,
    zenoh_session_of,
)
from ..live import CapReached, LiveRelay, dynamic_request
from ..liveqc import live_tests
from ..project_events import ProjectWatches
from ..roles import Role
from ..sessionwatch import watch_session
from ..settings import Settings
from ..socketcaps import CAP_CLOSE, SocketFull
from ..tables import User

router = APIRouter(prefix="/api/drones", tags=["streams"])
Drone = Annotated[str, Path(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]
Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]


class DynamicIn(BaseModel):
    topic: str = Field(max_length=200)
    period_s: str = Field(pattern=r"^[0-9]+(\.[0-9]+)?$", max_length=32)
    aggregation: str = Field(max_length=16)
    subscriber: Name | None = None


class DynamicOut(BaseModel):
    """The SubBroker's answer: ``status`` ACCEPTED (with ``key``),
    NOT_AVAILABLE (with ``reason``), CANCELLED, ERROR or NO_REPLY."""

    status: str
    reason: str | None = None
    subscriber: str | None = None
    key: str | None = None
    stream: str | None = None
    derived_from: str | None = None
    factor: int | None = None


Scientist = Depends(require(Role.scientist))


@router.post("/{drone}/subscriptions", dependencies=[Scientist])
def add_dynamic(drone: Drone, body: DynamicIn, state: StateDep, user: UserDep) -> DynamicOut:
    # the SubBroker scopes quotas, listing and cancelling to the owner
    request = {"action": "subscribe", **body.model_dump(exclude_none=True), "owner": user.username}
    reply = dynamic_request(
        zenoh_session_of(state), drone, request, state.settings.subscribe_timeout_s
    )
    return DynamicOut.model_validate(reply)


@router.delete("/{drone}/subscriptions/{subscriber}", dependencies=[Scientist])
def cancel_dynamic(drone: Drone, subscriber: Name, state: StateDep, user: UserDep) -> DynamicOut:
    request = {"action": "cancel", "subscriber": subscriber, "owner": user.username}
    reply = dynamic_request(
        zenoh_session_of(state), drone, request, state.settings.subscribe_timeout_s
    )
    return DynamicOut.model_validate(reply)


#: Largest WebSocket message a client may send (a subscribe op is ~60 bytes).
MAX_MESSAGE = 64 * 1024
#: Seconds a client without the session cookie has to send ``{"op": "auth"}``.


def _session(state: AppState, token: str) -> tuple[User, str] | None:
    with state.store.session() as db:
        user = user_for_token(db, token)
        return None if user is None else (user, user.roles)


def origin_allowed(websocket: WebSocket, settings: Settings) -> bool:
    """A browser's WebSocket names its page's origin: it must be this
    service's own, scheme included (``http://HOST`` for ``ws://``,
    ``https://HOST`` for ``wss://``), or a configured CORS origin. Clients
    without an Origin (API clients, not browsers) pass; they cannot use the
    cookie (below)."""
    origin = websocket.headers.get("origin")
    if origin is None:
        return True
    if origin in settings.cors_origins:
        return True
    host = websocket.headers.get("host", "")
    scheme = "https" if websocket.url.scheme in ("wss", "https") else "http"
    return origin.rstrip("/").lower() == f"{scheme}://{host}".lower()


def _parse(text: str) -> Any:
    if len(text) > MAX_MESSAGE:
        raise ValueError(f"a message is at most {MAX_MESSAGE} bytes")
    return loads_bounded(text, 16)


@router.websocket("/{drone}/stream")
async def stream(websocket: WebSocket, drone: str) -> None:
    """Authenticated by the session cookie (the workbench; same origin
    only) or, for API clients, by ``{"op": "auth", "token": ...}`` as the
    first message. Never by a token in the URL (URLs end up in logs)."""
    state = ws_state(websocket)
    if "token" in websocket.query_params:
        await websocket.close(
            code=4400,
            reason="no token in a URL: send "
            '{"op": "auth", "token": ...} first, or use the session cookie',
        )
        return
    if not origin_allowed(websocket, state.settings):
        await websocket.close(code=4403, reason="Origin not allowed")
        return
    cookie = websocket.cookies.get(SESSION_COOKIE)
    if cookie is not None and websocket.headers.get("origin") is None:
        cookie = None  # a cookie is honoured only with a checked Origin
    if state.zenoh_session is None or state.hub is None:
        await websocket.close(code=4503, reason="zenoh is disabled")
        return
    try:
        check_name("drone", drone)
    except ValueError as exc:
        await websocket.close(code=4400, reason=str(exc)[:120])
        return
    session = None
    if cookie is not None:
        session = await run_in_threadpool(_session, state, cookie)
        if session is None:
            await websocket.close(code=4401, reason="missing or invalid token")
            return
    address = websocket.client.host if websocket.client is not None else "unknown"
    token = cookie
    if session is None:
        token, session = await _unauthenticated(websocket, state, address)
        if session is None or token is None:
            return
    else:
        await websocket.accept()
    user, roles = session
    assert token is not None
    try:
        with state.socket_caps.slot(user.id, address):
            await _serve_stream(websocket, state, drone, token, user, roles)
    except SocketFull as exc:
        with contextlib.suppress(Exception):
            await websocket.close(code=CAP_CLOSE, reason=str(exc)[:120])


async def _serve_stream(
    websocket: WebSocket, state: AppState, drone: str, token: str, user: User, roles: str
) -> None:
    assert state.hub is not None
    settings = state.settings
    relay = LiveRelay(
        state.hub,
        drone,
        settings.stream_queue_size,
        user_id=user.id,
        per_socket=settings.ws_subscriptions_per_socket,
        per_user=settings.ws_subscriptions_per_user,
        per_user_counts=state.ws_counts,
    )
    relay.queue.bind(asyncio.get_running_loop())
    relay.start()
    watches = ProjectWatches(state.project_events, relay.queue.put)
    tasks: set[asyncio.Task[Any]] = {
        asyncio.create_task(
            _send_loop(websocket, relay, websocket.query_params.get("batch") == "1")
        ),
        asyncio.create_task(_receive_loop(websocket, relay, state, user, watches)),
    }
    watcher = asyncio.create_task(watch_session(state, token, (user.id, roles)))
    tasks.add(watcher)
    try:
        done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
        for task in tasks - done:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        ended = watcher.result() if watcher in done and not watcher.cancelled() else None
        if ended is not None:
            with contextlib.suppress(Exception):
                await websocket.close(code=ended[0], reason=ended[1])
    finally:
        watches.close()
        relay.close()


async def _unauthenticated(
    websocket: WebSocket, state: AppState, address: str
) -> tuple[str | None, tuple[User, str] | None]:
    """A socket without a cookie session: refused before the accept (a 403,
    no task, no timer) when its address already has
    ``ws_unauthenticated_per_address`` waiting; else accepted and given
    ``ws_auth_timeout_s`` for its auth message, closed with 4401 without one."""
    waiting = state.ws_unauthenticated
    if waiting[address] >= state.settings.ws_unauthenticated_per_address:
        await websocket.close(code=CAP_CLOSE, reason="too many sockets waiting to authenticate")
        return None, None
    waiting[address] += 1
    try:
        await websocket.accept()
        token, session = await _first_message_auth(websocket, state)
    finally:
        waiting[address] -= 1
        if waiting[address] <= 0:
            del waiting[address]
    if session is None or token is None:
        await websocket.close(code=4401, reason="missing or invalid token")
        return None, None
    return token, session


async def _first_message_auth(
    websocket: WebSocket, state: AppState
) -> tuple[str | None, tuple[User, str] | None]:
    try:
        timeout = state.settings.ws_auth_timeout_s
        text = await asyncio.wait_for(websocket.receive_text(), timeout)
        message = _parse(text)
    except (TimeoutError, ValueError, KeyError, WebSocketDisconnect, RuntimeError):
        return None, None
    if not isinstance(message, dict) or message.get("op") != "auth":
        return None, None
    token = message.get("token")
    if not isinstance(token, str) or not token or len(token) > 256:
        return None, None
    session = await run_in_threadpool(_session, state, token)
    if session is not None:
        reply: dict[str, Any] = {"type": "authenticated", "user": session[0].username}
        if message.get("id") is not None:
            reply["id"] = message.get("id")
        await websocket.send_json(reply)
    return token, session


async def _receive_loop(
    websocket: WebSocket, relay: LiveRelay, state: AppState, user: User, watches: ProjectWatches
) -> None:
    try:
        while True:
            text = await websocket.receive_text()
            try:
                message = _parse(text)
            except ValueError as exc:
                relay.queue.put({"type": "error", "message": f"not a JSON message: {exc}"})
                continue
            reply = await _handle(message, relay, state, user, watches)
            relay.queue.put(reply)
            # Messages already buffered are received without a suspension:
            # yield once per op, so a flooding socket cannot starve the others
            # (or /api/health) of the event loop.
            await asyncio.sleep(0)
    except (WebSocketDisconnect, RuntimeError, KeyError):
        return


#: Messages in one batched frame at most (the queue holds stream_queue_size).
BATCH_LIMIT = 512


def _dumps(message: Any) -> str:
    return json.dumps(message, separators=(",", ":"), ensure_ascii=False)


async def _send_loop(websocket: WebSocket, relay: LiveRelay, batched: bool = False) -> None:
    """Everything queued since the last wake-up goes out in order: one frame
    per message, or with ``?batch=1`` one ``{"type": "batch", "messages":
    [...]}`` frame per wake-up (one JSON encoding, one compression and one
    write for all the values of a slot instead of one each: the 20-drone
    fleet's stream proxy spent its time there)."""
    while True:
        batch = await relay.queue.get_batch()
        dropped = relay.queue.take_dropped()
        if dropped:
            batch.insert(0, {"type": "dropped", "count": dropped})
        if batched and len(batch) > 1:
            for k in range(0, len(batch), BATCH_LIMIT):
                await websocket.send_text(
                    _dumps({"type": "batch", "messages": batch[k : k + BATCH_LIMIT]})
                )
                await asyncio.sleep(0)
            continue
        for item in batch:
            await websocket.send_text(_dumps(item))
            await asyncio.sleep(0)  # writes do not suspend: let others run


async def _handle(
    message: Any, relay: LiveRelay, state: AppState, user: User, watches: ProjectWatches
) -> dict[str, Any]:
    """One op, with the role it needs: values and status need any role;
    dynamic subscriptions need the role scientist."""
    if not isinstance(message, dict):
        return {"type": "error", "message": "a message is a JSON object with an 'op'"}
    op, ident = message.get("op"), message.get("id")
    if not isinstance(ident, str | int | None) or (isinstance(ident, str) and len(ident) > 64):
        ident = None
    out: dict[str, Any]
    try:
        if not roles_of(user) and op != "ping":
            out = {"type": "error", "message": "live values need a role"}
        elif op == "subscribe":
            tests = await run_in_threadpool(_live_tests, state, relay.drone)
            out = relay.subscribe(message.get("subscriber"), tests)
        elif op == "unsubscribe":
            out = relay.unsubscribe(message.get("subscriber"))
        elif op == "ping":
            out = {"type": "pong", "subscribers": relay.subscribers}
        elif op in ("watch", "unwatch"):
            out = watches.handle(op, message.get("project"))
        elif op in ("dynamic", "cancel"):
            out = await _dynamic(op, message, relay, state, user)
        elif op == "auth":
            out = {"type": "error", "message": "already authenticated"}
        else:
            out = {"type": "error", "message": f"unknown op {str(op)[:40]!r}"}
    except CapReached as exc:
        out = {"type": "error", "code": "cap", "message": str(exc)}
    except ValueError as exc:
        out = {"type": "error", "message": str(exc)}
    if ident is not None:
        out["id"] = ident
    return out


def _live_tests(state: AppState, drone: str) -> dict[str, Any]:
    """The QARTOD tests of each subscriber of what runs on ``drone`` (liveqc.py)."""
    with state.store.session() as db:
        return live_tests(db, drone)


async def _dynamic(
    op: str, message: dict[str, Any], relay: LiveRelay, state: AppState, user: User
) -> dict[str, Any]:
    if not has_role(user, Role.scientist):
        return {"type": "error", "message": "dynamic subscriptions need the role scientist"}
    if op == "dynamic":
        fields = ("topic", "period_s", "aggregation", "subscriber")
        request = {"action": "subscribe", **{k: message[k] for k in fields if k in message}}
    else:
        request = {"action": "cancel", "subscriber": message.get("subscriber")}
    request["owner"] = user.username  # the SubBroker scopes quotas and cancels to it
    reply = await run_in_threadpool(
        dynamic_request,
        zenoh_session_of(state),
        relay.drone,
        request,
        state.settings.subscribe_timeout_s,
    )
    if reply.get("status") == "ACCEPTED" and isinstance(reply.get("subscriber"), str):
        relay.subscribe(reply["subscriber"])  # values start at the next slot
    if reply.get("status") == "CANCELLED":
        relay.unsubscribe(reply.get("subscriber"))
    return {"type": "dynamic", "reply": reply}
