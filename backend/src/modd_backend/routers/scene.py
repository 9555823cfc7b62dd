"""The 3D scene (viser): where to embed it, which drones it draws, which
subscribed value colours a drone's track, and the scene itself, proxied at
``/scene/`` (HTTP and WebSocket) behind the session (sceneproxy.py)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Request, Response, WebSocket
from pydantic import BaseModel, Field
from starlette.concurrency import run_in_threadpool

from ..deps import StateDep, UserDep, roles_of, ws_state
from ..errors import ApiError
from ..scene import SceneService
from ..sceneproxy import PagePolicies, fetch, relay_socket, scene_csp

router = APIRouter(prefix="/api/scene", tags=["scene"])
#: The scene itself, same origin as the workbench (no prefix: ``/scene/``).
proxy = APIRouter(tags=["scene"])
#: Where the workbench frames the scene.
SCENE_URL = "/scene/"
_policies = PagePolicies()
Drone = Annotated[str, Path(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]


class DroneScene(BaseModel):
    drone: str
    points: int
    colour_by: str | None
    roles: dict[str, str]


class SceneOut(BaseModel):
    """``url`` is the viser client to embed (an iframe), on this origin."""

    url: str
    drones: list[DroneScene]


class ColourIn(BaseModel):
    subscriber: str | None = Field(default=None, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)


def _scene(state: StateDep) -> SceneService:
    if state.scene is None:
        raise ApiError(404, "this backend runs no 3D scene (settings: scene_port)")
    return state.scene


@router.get("", responses={404: {"description": "no scene configured"}})
def read_scene(state: StateDep, _user: UserDep) -> SceneOut:
    scene = _scene(state)
    drones = [
        DroneScene(drone=d, points=len(t.points), colour_by=t.colour_by, roles=t.roles)
        for d, t in sorted(scene.tracks.items())
    ]
    return SceneOut(url=SCENE_URL, drones=drones)


@router.put(
    "/{drone}/colour",
    status_code=204,
    responses={
        403: {"description": "a user without any role"},
        404: {"description": "no scene configured"},
    },
)
def set_colour(drone: Drone, body: ColourIn, state: StateDep, user: UserDep) -> None:
    """Colour the drone's track by this subscriber's values (null: plain);
    the scene is shared, so a user holding no role may not change it."""
    if not roles_of(user):
        raise ApiError(403, "colouring the shared 3D scene needs a role")
    _scene(state).colour_by(drone, body.subscriber)


_SCENE_ERRORS: dict[int | str, dict[str, Any]] = {
    401: {"description": "no session"},
    403: {"description": "a user without any role"},
    404: {"description": "no scene configured, or no such file"},
    502: {"description": "the scene server did not answer"},
}


@proxy.get("/scene/{path:path}", responses=_SCENE_ERRORS, include_in_schema=False)
async def scene_page(path: str, request: Request, state: StateDep, user: UserDep) -> Response:
    """viser's web client, relayed from its loopback port. Its HTML page
    carries its own CSP: the page's inline scripts by hash (sceneproxy.py)."""
    if not roles_of(user):
        raise ApiError(403, "the 3D scene needs a role")
    scene = _scene(state)
    if ".." in path.split("/") or "\\" in path or len(path) > 256:
        raise ApiError(404, "no such file in the 3D scene")
    try:
        got = await fetch(scene.server.port, "/" + path, scene.server.secret)
    except (OSError, ValueError, TimeoutError) as exc:
        raise ApiError(502, f"the 3D scene server did not answer: {exc}") from exc
    if got.status != 200:
        raise ApiError(404, "no such file in the 3D scene")
    ctype = got.headers.get("content-type", "application/octet-stream")
    headers = {"Cache-Control": "no-store"}
    if ctype.startswith("text/html"):
        hashes = await run_in_threadpool(_policies.hashes, got.body)
        host = request.headers.get("host", "localhost")  # allow-listed by the Guard
        headers["Content-Security-Policy"] = scene_csp(hashes, host)
    return Response(got.body, media_type=ctype, headers=headers)


@proxy.websocket("/scene")
async def scene_socket(websocket: WebSocket) -> None:
    """viser's WebSocket, behind the session and the Origin check."""
    state = ws_state(websocket)
    if state.scene is None:
        await websocket.close(code=4404, reason="this backend runs no 3D scene")
        return
    await relay_socket(websocket, state, state.scene.server.port, state.scene.server.secret)
