"""The base-station records (docs/subbroker.md, "Base-station record"): every
value a SubBroker delivered, live and backfilled, one MCAP per drone and
mission. Listed and downloaded like the drone's archives (any signed-in user);
paths are confined to ``<record_dir>/<drone>/``."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends
from fastapi.responses import FileResponse, Response

from ..archives import archive_path, file_info, list_files
from ..deps import Heavy, StateDep, UserDep
from ..filesnapshot import file_snapshot
from ..tables import User
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
