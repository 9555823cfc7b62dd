"""Foxglove and Lichtblick through the backend's own port: ``/foxglove/live``
(every delivered value, live) and ``/foxglove/replay`` (the replay the user
started in the Archives panel), relayed to the ``foxglove-sdk`` servers the
backend runs on loopback behind TLS (loopback_tls.py), under the rules of
wsrelay.py: an allowed Origin (or none: a desktop viewer), a session with a
role, closed within ``ws_recheck_s`` of a logout or role change.

A viewer can carry a credential only in its URL: ``POST /api/foxglove/links``
(and the replay's answer) hands out ``ws://HOST/foxglove/live?ticket=T``, a
ticket spent on use and good for 5 minutes (tickets.py)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Annotated

from fastapi import APIRouter, Depends, Request, WebSocket
from pydantic import BaseModel
from websockets.asyncio.client import ClientConnection
from websockets.asyncio.client import connect as ws_connect
from websockets.typing import Subprotocol

from ..deps import AppState, CredsDep, StateDep, UserDep, roles_of, ws_state
from ..errors import ApiError
from ..wsrelay import admit, relay

router = APIRouter(tags=["foxglove"])
#: The subprotocols of the Foxglove WebSocket protocol a viewer may ask for.
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")


def viewer_link(request: Request, state: AppState, token: str, kind: str, user: int) -> str:
    """``ws(s)://HOST/foxglove/<kind>?ticket=T`` for the session ``token``
    (HOST as the request named it: allow-listed by the Guard); the ticket
    opens only ``kind`` and counts among ``user``'s (tickets.py)."""
    scheme = "wss" if request.url.scheme == "https" else "ws"
    host = request.headers.get("host", "127.0.0.1")
    return f"{scheme}://{host}/foxglove/{kind}?ticket={state.tickets.issue(token, kind, user)}"


def viewer_links(
    request: Request, state: StateDep, creds: CredsDep, user: UserDep
) -> Callable[[str], str]:
    """A dependency: makes the links of the requesting session."""
    return lambda kind: viewer_link(request, state, creds.token, kind, user.id)


ViewerLinks = Annotated[Callable[[str], str], Depends(viewer_links)]


class LinksOut(BaseModel):
    """Viewer URLs, each with its own single-use ticket; null: not served."""

    live: str | None
    replay: str | None
    ticket_ttl_s: float


@router.post("/api/foxglove/links", responses={403: {"description": "needs a role"}})
def links(state: StateDep, user: UserDep, link: ViewerLinks) -> LinksOut:
    """The URLs to open in Foxglove or Lichtblick (Open connection → Foxglove
    WebSocket); each ticket works once, within ``ticket_ttl_s``."""
    if not roles_of(user):
        raise ApiError(403, "live values need a role")
    replay = state.replay.serving_port() if state.replay is not None else None
    return LinksOut(
        live=link("live") if state.foxglove is not None else None,
        replay=link("replay") if replay is not None else None,
        ticket_ttl_s=state.tickets.ttl_s,
    )


async def _relay(
    websocket: WebSocket, state: AppState, port: int | None, what: str, kind: str
) -> None:
    admitted = await admit(websocket, state, what, ticket_kind=kind)
    if admitted is None:
        return
    if port is None or state.loopback_tls is None:
        await websocket.close(code=4404, reason=f"{what} is not running")
        return
    offered = [Subprotocol(p) for p in websocket.scope.get("subprotocols", []) if p in SUBPROTOCOLS]
    tls = state.loopback_tls.client_context()

    def connect() -> Awaitable[ClientConnection]:
        return ws_connect(
            f"wss://127.0.0.1:{port}",
            ssl=tls,
            subprotocols=offered or [Subprotocol(SUBPROTOCOLS[0])],
            compression=None,
            max_size=64 * 1024 * 1024,
            open_timeout=5,
        )

    await relay(websocket, state, admitted, connect, what)


@router.websocket("/foxglove/live")
async def live_socket(websocket: WebSocket) -> None:
    state = ws_state(websocket)
    port = state.foxglove.port if state.foxglove is not None else None
    await _relay(websocket, state, port, "the Foxglove live server", "live")


@router.websocket("/foxglove/replay")
async def replay_socket(websocket: WebSocket) -> None:
    state = ws_state(websocket)
    port = state.replay.serving_port() if state.replay is not None else None
    await _relay(websocket, state, port, "the Foxglove replay", "replay")
