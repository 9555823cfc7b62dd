"""The base-station records (docs/subbroker.md, "Base-station record"): every
value a SubBroker delivered, live and backfilled, one MCAP per drone and
mission. Listed and downloaded like the drone's archives (any signed-in user);
paths are confined to ``<record_dir>/<drone>/``."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query
from fastapi.responses import FileResponse, Response

from ..archives import archive_path, file_info, list_files
from ..deps import Heavy, StateDep, UserDep
from ..filesnapshot import file_snapshot
from ..tables import User
from ..track import MAX_POINTS, mission_track
from .archives import (
    BUSY,
    NOT_FOUND,
    REPLAYERS,
    ArchiveOut,
    Drone,
    Name,
    ReplayIn,
    ReplayOut,
    serve_replay,
)
from .foxglove import ViewerLinks

router = APIRouter(prefix="/api/drones/{drone}/records", tags=["archives"])
track_router = APIRouter(prefix="/api/drones/{drone}", tags=["archives"])
Subscriber = Annotated[str, Query(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]


@track_router.get("/track", dependencies=[Heavy])
def track(
    drone: Drone,
    lat: Subscriber,
    lon: Subscriber,
    state: StateDep,
    _user: UserDep,
    points: Annotated[int, Query(ge=2, le=MAX_POINTS)] = 2000,
    colour: Annotated[str | None, Query(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)] = None,
) -> dict[str, object]:
    """The drone's track since its mission began (the Map after a reload): the
    windows of the subscribers ``lat`` and ``lon`` in the newest base-station
    record, paired by time and thinned evenly to at most ``points`` fixes
    (``total``: how many there were); times in seconds since the Unix epoch.
    With ``colour``, each fix carries that subscriber's value then (the Map's colour-by)."""
    root = state.settings.effective_record_dir
    return mission_track(root, drone, lat, lon, points, colour)


@router.get("")
def list_records(drone: Drone, state: StateDep, _user: UserDep) -> list[ArchiveOut]:
    root = state.settings.effective_record_dir
    return [ArchiveOut.model_validate(file_info(p).to_json()) for p in list_files(root, drone)]


@router.get(
    "/{name}",
    response_class=FileResponse,
    responses={**NOT_FOUND, 200: {"content": {"application/octet-stream": {}}}},
)
def download_record(drone: Drone, name: Name, state: StateDep, _user: UserDep) -> Response:
    path = archive_path(state.settings.effective_record_dir, drone, name)
    return file_snapshot(path)  # a file still being written: what it held at the start


@router.post(
    "/{name}/replay",
    responses={
        **NOT_FOUND,
        **BUSY,
        409: {"description": "replay is off (--foxglove-replay-port 0)"},
        422: {"description": "nothing in the range, or more than a replay holds"},
    },
    dependencies=[Heavy],
)
def replay_record(
    drone: Drone,
    name: Name,
    body: ReplayIn,
    state: StateDep,
    user: Annotated[User, Depends(REPLAYERS)],
    link: ViewerLinks,
) -> ReplayOut:
    """The base-station record of a mission (what was delivered, live and
    backfilled) in Foxglove/Lichtblick: seek, play, pause; the same replay
    server as the drone's archives."""
    return serve_replay(state, state.settings.effective_record_dir, drone, name, body, user, link)
