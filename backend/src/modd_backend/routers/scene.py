"""The 3D scene (viser): where to embed it, which drones it draws, and which
subscribed value colours a drone's track."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Request
from pydantic import BaseModel, Field

from ..deps import StateDep, UserDep, roles_of
from ..errors import ApiError
from ..scene import SceneService

router = APIRouter(prefix="/api/scene", tags=["scene"])
Drone = Annotated[str, Path(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]


class DroneScene(BaseModel):
    drone: str
    points: int
    colour_by: str | None
    roles: dict[str, str]


class SceneOut(BaseModel):
    """``url`` is the viser client to embed (an iframe)."""

    url: str
    drones: list[DroneScene]


class ColourIn(BaseModel):
    subscriber: str | None = Field(default=None, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$",
                                   max_length=64)


def _scene(state: StateDep) -> SceneService:
    if state.scene is None:
        raise ApiError(404, "this backend runs no 3D scene (settings: scene_port)")
    return state.scene


@router.get("", responses={404: {"description": "no scene configured"}})
def read_scene(request: Request, state: StateDep, _user: UserDep) -> SceneOut:
    scene = _scene(state)
    drones = [
        DroneScene(drone=d, points=len(t.points), colour_by=t.colour_by, roles=t.roles)
        for d, t in sorted(scene.tracks.items())
    ]
    return SceneOut(url=scene.server.url_for(request.url.hostname), drones=drones)


@router.put("/{drone}/colour", status_code=204,
            responses={403: {"description": "a user without any role"},
                       404: {"description": "no scene configured"}})
def set_colour(drone: Drone, body: ColourIn, state: StateDep, user: UserDep) -> None:
    """Colour the drone's track by this subscriber's values (null: plain);
    the scene is shared, so a user holding no role may not change it."""
    if not roles_of(user):
        raise ApiError(403, "colouring the shared 3D scene needs a role")
    _scene(state).colour_by(drone, body.subscriber)
