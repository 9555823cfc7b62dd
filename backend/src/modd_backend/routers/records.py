"""The base-station records (docs/subbroker.md, "Base-station record"): every
value a SubBroker delivered, live and backfilled, one MCAP per drone and
mission. Listed and downloaded like the drone's archives (any signed-in user);
paths are confined to ``<record_dir>/<drone>/``."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import FileResponse

from ..archives import archive_path, file_info, list_files
from ..deps import StateDep, UserDep
from .archives import NOT_FOUND, ArchiveOut, Drone, Name

router = APIRouter(prefix="/api/drones/{drone}/records", tags=["archives"])


@router.get("")
def list_records(drone: Drone, state: StateDep, _user: UserDep) -> list[ArchiveOut]:
    root = state.settings.effective_record_dir
    return [ArchiveOut.model_validate(file_info(p).to_json()) for p in list_files(root, drone)]


@router.get("/{name}", response_class=FileResponse,
            responses={**NOT_FOUND, 200: {"content": {"application/octet-stream": {}}}})
def download_record(drone: Drone, name: Name, state: StateDep, _user: UserDep) -> FileResponse:
    path = archive_path(state.settings.effective_record_dir, drone, name)
    return FileResponse(path, media_type="application/octet-stream", filename=path.name)
