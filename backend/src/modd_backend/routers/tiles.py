"""Map tiles from a local folder (``--tiles DIR``, laid out ``<z>/<x>/<y>.png``
as tile downloaders and ``gdal2tiles --xyz`` write it): a basemap offline,
served by the workbench itself, so the page's policy needs no foreign origin.
None is served without the option; a tile outside the folder (a link out of
it) or not there is a 404. Any signed-in user."""

from __future__ import annotations

from pathlib import Path as FsPath
from typing import Annotated, Literal

from fastapi import APIRouter, Path
from fastapi.responses import FileResponse

from ..deps import StateDep, UserDep
from ..errors import ApiError

router = APIRouter(prefix="/api/tiles", tags=["map"])
Coord = Annotated[int, Path(ge=0, le=2**30)]
TYPES = {"png": "image/png", "jpg": "image/jpeg", "jpeg": "image/jpeg", "webp": "image/webp"}


@router.get("")
def tiles_info(state: StateDep, _user: UserDep) -> dict[str, object]:
    """Whether this workbench serves a tile folder, and the tile URL template the Map takes."""
    root = state.settings.tile_dir
    on = root is not None and root.is_dir()
    return {"available": on, "url": "/api/tiles/{z}/{x}/{y}.png" if on else None}


def tile_path(root: FsPath, z: int, x: int, y: int, ext: str) -> FsPath:
    """``<root>/<z>/<x>/<y>.<ext>``, a regular file inside ``root`` once links are resolved."""
    if z > 30 or x >= 2**z or y >= 2**z:
        raise ApiError(404, f"no tile {z}/{x}/{y}: x and y run to {2**z - 1} at zoom {z}")
    path = root / str(z) / str(x) / f"{y}.{ext}"
    real = path.resolve()
    if not real.is_relative_to(root.resolve()) or not real.is_file():
        raise ApiError(404, f"no tile {z}/{x}/{y}.{ext} in the tile folder")
    return real


@router.get(
    "/{z}/{x}/{y}.{ext}",
    response_class=FileResponse,
    responses={200: {"content": {t: {} for t in sorted(set(TYPES.values()))}}, 404: {}},
)
def tile(
    z: Coord,
    x: Coord,
    y: Coord,
    ext: Literal["png", "jpg", "jpeg", "webp"],
    state: StateDep,
    _user: UserDep,
) -> FileResponse:
    root = state.settings.tile_dir
    if root is None:
        raise ApiError(404, "this workbench serves no tile folder (modd-backend --tiles DIR)")
    return FileResponse(
        tile_path(root, z, x, y, ext),
        media_type=TYPES[ext],
        headers={"Cache-Control": "private, max-age=3600"},
    )
