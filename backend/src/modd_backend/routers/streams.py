"""Live data: one WebSocket per browser and drone multiplexing the
subscriptions the page asks for (docs/backend.md, "Streams"), and dynamic
subscriptions over REST.

Client messages: ``{"op": "subscribe"|"unsubscribe", "subscriber": NAME}``,
``{"op": "dynamic", "topic", "period_s", "aggregation", ["subscriber"]}``,
``{"op": "cancel", "subscriber": NAME}``, ``{"op": "ping"}``; an optional
``"id"`` is echoed. Server messages carry a ``type``: value, status, dropped,
subscribed, unsubscribed, dynamic, pong, error."""

from __future__ import annotations

import asyncio
import contextlib
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Path, WebSocket, WebSocketDisconnect
from pydantic import BaseModel, Field
from starlette.concurrency import run_in_threadpool

from ..accounts import user_for_token
from ..deps import AppState, StateDep, bridge_of, has_role, require, ws_state
from ..roles import Role
from ..streams import StreamRelay, dynamic_request
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
def add_dynamic(drone: Drone, body: DynamicIn, state: StateDep) -> DynamicOut:
    request = {"action": "subscribe", **body.model_dump(exclude_none=True)}
    reply = dynamic_request(bridge_of(state), drone, request, state.settings.subscribe_timeout_s)
    return DynamicOut.model_validate(reply)


@router.delete("/{drone}/subscriptions/{subscriber}", dependencies=[Scientist])
def cancel_dynamic(drone: Drone, subscriber: Name, state: StateDep) -> DynamicOut:
    request = {"action": "cancel", "subscriber": subscriber}
    reply = dynamic_request(bridge_of(state), drone, request, state.settings.subscribe_timeout_s)
    return DynamicOut.model_validate(reply)


def _authenticate(state: AppState, token: str | None) -> User | None:
    if not token:
        return None
    with state.store.session() as db:
        return user_for_token(db, token)


@router.websocket("/{drone}/stream")
async def stream(websocket: WebSocket, drone: str, token: str | None = None) -> None:
    """Browsers cannot set headers on a WebSocket: the token is a query parameter."""
    state = ws_state(websocket)
    user = await run_in_threadpool(_authenticate, state, token)
    if user is None:
        await websocket.close(code=4401, reason="missing or invalid token")
        return
    if state.bridge is None:
        await websocket.close(code=4503, reason="zenoh is disabled")
        return
    try:
        relay = StreamRelay(state.bridge, drone, state.settings.stream_queue_size)
    except ValueError as exc:
        await websocket.close(code=4400, reason=str(exc))
        return
    await websocket.accept()
    relay.queue.bind(asyncio.get_running_loop())
    relay.start()
    sender = asyncio.create_task(_send_loop(websocket, relay))
    try:
        while True:
            message = await websocket.receive_json()
            reply = await _handle(message, relay, state, user)
            relay.queue.put(reply)
    except (WebSocketDisconnect, RuntimeError):
        pass
    except ValueError:  # not JSON: say so and close
        await websocket.close(code=4400, reason="messages are JSON objects")
    finally:
        sender.cancel()
        with contextlib.suppress(asyncio.CancelledError, Exception):
            await sender
        relay.close()


async def _send_loop(websocket: WebSocket, relay: StreamRelay) -> None:
    while True:
        batch = await relay.queue.get_batch()
        dropped = relay.queue.take_dropped()
        if dropped:
            await websocket.send_json({"type": "dropped", "count": dropped})
        for item in batch:
            await websocket.send_json(item)


async def _handle(
    message: Any, relay: StreamRelay, state: AppState, user: User
) -> dict[str, Any]:
    if not isinstance(message, dict):
        return {"type": "error", "message": "a message is a JSON object with an 'op'"}
    op, ident = message.get("op"), message.get("id")
    try:
        if op == "subscribe":
            out = relay.subscribe(message.get("subscriber"))
        elif op == "unsubscribe":
            out = relay.unsubscribe(message.get("subscriber"))
        elif op == "ping":
            out = {"type": "pong", "subscribers": relay.subscribers}
        elif op in ("dynamic", "cancel"):
            out = await _dynamic(op, message, relay, state, user)
        else:
            out = {"type": "error", "message": f"unknown op {op!r}"}
    except ValueError as exc:
        out = {"type": "error", "message": str(exc)}
    if ident is not None:
        out["id"] = ident
    return out


async def _dynamic(
    op: str, message: dict[str, Any], relay: StreamRelay, state: AppState, user: User
) -> dict[str, Any]:
    if not has_role(user, Role.scientist):
        return {"type": "error", "message": "dynamic subscriptions need the role scientist"}
    if op == "dynamic":
        fields = ("topic", "period_s", "aggregation", "subscriber")
        request = {"action": "subscribe", **{k: message[k] for k in fields if k in message}}
    else:
        request = {"action": "cancel", "subscriber": message.get("subscriber")}
    reply = await run_in_threadpool(
        dynamic_request, relay.bridge, relay.drone, request, state.settings.subscribe_timeout_s
    )
    if reply.get("status") == "ACCEPTED" and isinstance(reply.get("subscriber"), str):
        relay.subscribe(reply["subscriber"])  # values start at the next slot
    if reply.get("status") == "CANCELLED":
        relay.unsubscribe(reply.get("subscriber"))
    return {"type": "dynamic", "reply": reply}
