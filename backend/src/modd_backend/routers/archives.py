"""A drone's on-board archives: list the MCAP files, read a time range of a
topic (reduced for plotting), export it as CSV, download a file. Any signed-in
user may read; paths are confined to ``<archive_dir>/<drone>/``."""

from __future__ import annotations

import datetime as dt
import json
import os
import tempfile
from collections import Counter
from collections.abc import Callable
from pathlib import Path as FsPath
from typing import Annotated, Any, Literal, TypeVar

from fastapi import APIRouter, Depends, HTTPException, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import FileResponse, Response
from pydantic import BaseModel, Field
from starlette.background import BackgroundTask

from .. import archive_work
from ..archive_work import (
    EXPORT_TIME_S,
    MAX_EXPORT_SAMPLES,
    TOPIC_TIME_S,
    Refused,
    check_bytes,
    csv_text,
    dataset_file,
    series,
)
from ..archives import archive_path, file_info, list_files
from ..deps import AppState, Heavy, StateDep, UserDep, require
from ..downloads import content_disposition
from ..errors import ApiError
from ..filesnapshot import file_snapshot
from ..roles import Role
from ..schemas import Responses
from ..tables import User
from .datasetmeta import head_metadata
from .foxglove import ViewerLinks

router = APIRouter(prefix="/api/drones/{drone}/archives", tags=["archives"])
Drone = Annotated[str, Path(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]
Name = Annotated[str, Path(max_length=255)]
Topic = Annotated[str, Query(max_length=200)]
Nanos = Annotated[int | None, Query(ge=0, le=2**63 - 1)]
NOT_FOUND: Responses = {404: {"description": "no such archive file"}}
BUSY: Responses = {
    413: {"description": "more bytes or samples than one request reads"},
    429: {"description": "this user's heavy requests are running; Retry-After"},
    503: {
        "description": "all heavy slots are taken, or no archive worker within 30 s "
        "(Retry-After); or the work ran over its time"
    },
}
T = TypeVar("T")


async def in_worker(
    request: Request, state: AppState, user: User, fn: Callable[..., T], *args: Any, time_s: float
) -> T:
    """``fn(*args)`` in an archive worker, in this user's fair turn
    (archive_pool.py), given up when the client goes away; a bound refused
    there (archive_work.Refused, MemoryError) is its 413 or 422."""
    pool = state.archive_pool
    if pool is None:
        raise HTTPException(503, "the archive workers are not running")
    since = getattr(request.state, "heavy_since", None)
    try:
        return await pool.run(
            user.id, fn, *args, time_s=time_s, since=since, gone=request.is_disconnected
        )
    except Refused as exc:
        if exc.extra:  # the model's diagnostics, as the route always gave them
            raise HTTPException(exc.status, {"message": str(exc), **exc.extra}) from None
        raise ApiError(exc.status, str(exc)) from None
    except MemoryError as exc:
        raise ApiError(413, f"{exc}: choose a shorter range, fewer topics or files") from None


class TopicCount(BaseModel):
    topic: str
    messages: int


class ArchiveOut(BaseModel):
    """``complete`` is false for a file still being written or cut short."""

    name: str
    size: int
    complete: bool
    start_ns: int | None
    end_ns: int | None
    topics: list[TopicCount]


#: Who may start or stop the replay server (it changes what a port serves):
#: a user holding a role that works with the data.
REPLAYERS = require(Role.scientist, Role.operator, Role.designer, Role.integrator)


class ReplayIn(BaseModel):
    """The range to play (log time, ns); the whole file when left out."""

    start_ns: int | None = None
    end_ns: int | None = None
    #: Play once from the start when a viewer subscribes: for viewers without
    #: playback controls (Lichtblick 1.28's WebSocket player).
    autoplay: bool = False


class ReplayOut(BaseModel):
    """Where Foxglove or Lichtblick connects (Open connection > Foxglove
    WebSocket) to seek, play and pause the range: the backend's
    ``/foxglove/replay`` with a single-use ticket (routers/foxglove.py)."""

    url: str
    drone: str
    file: str
    start_ns: int
    end_ns: int
    messages: int
    topics: list[str]
    started_by: str
    autoplay: bool


class SeriesOut(BaseModel):
    """``points`` are [log time ns, value]; ``total`` counts the samples in
    the range before the min/max reduction to ``max_points``."""

    topic: str
    total: int
    reduced: bool
    points: list[tuple[int, Any]]


@router.get("")
def list_archives(drone: Drone, state: StateDep, _user: UserDep) -> list[ArchiveOut]:
    root = state.settings.effective_archive_dir
    return [ArchiveOut.model_validate(file_info(p).to_json()) for p in list_files(root, drone)]


@router.get("/{name}/series", responses={**NOT_FOUND, **BUSY}, dependencies=[Heavy])
async def read_series(
    drone: Drone,
    name: Name,
    topic: Topic,
    state: StateDep,
    user: UserDep,
    request: Request,
    start_ns: Nanos = None,
    end_ns: Nanos = None,
    max_points: Annotated[int, Query(ge=2, le=100_000)] = 2000,
) -> SeriesOut:
    (path,) = _bounded([archive_path(state.settings.effective_archive_dir, drone, name)])
    total, points = await in_worker(
        request,
        state,
        user,
        series,
        path,
        topic,
        start_ns,
        end_ns,
        max_points,
        time_s=TOPIC_TIME_S,
    )
    return SeriesOut(topic=topic, total=total, reduced=len(points) < total, points=points)


@router.get(
    "/{name}/csv",
    responses={**NOT_FOUND, **BUSY, 200: {"content": {"text/csv": {}}}},
    dependencies=[Heavy],
)
async def export_csv(
    drone: Drone,
    name: Name,
    topic: Topic,
    state: StateDep,
    user: UserDep,
    request: Request,
    start_ns: Nanos = None,
    end_ns: Nanos = None,
) -> Response:
    """Every sample of the range, unreduced: ``log_time_ns,topic,value``
    (read in a worker process: archive_work.py)."""
    (path,) = _bounded([archive_path(state.settings.effective_archive_dir, drone, name)])
    text = await in_worker(
        request, state, user, csv_text, path, topic, start_ns, end_ns, time_s=TOPIC_TIME_S
    )
    stem = f"{name.removesuffix('.mcap')}-{topic}.csv"
    return Response(
        text,
        media_type="text/csv; charset=utf-8",
        headers={"Content-Disposition": content_disposition(stem)},
    )


class ExportIn(BaseModel):
    """A dataset of the drone's archive (``modd dataset``, docs/user-guide/datasets.md):
    the model the archive was made with (the workbench's), the format, and what to
    keep. ``source``: ``archive`` for the samples archived on board, ``received``
    for the windows the subscribers received (the base-station records; ``topics``
    then names subscribers or their topics). ``files``: the files to read (all the
    drone's archives, or records, when empty)."""

    model: dict[str, Any]
    format: Literal["netcdf", "parquet", "csv", "geojson", "gpx"]
    files: list[Annotated[str, Field(max_length=255)]] = Field(default=[], max_length=1000)
    start_ns: int | None = Field(default=None, ge=0, le=2**63 - 1)
    end_ns: int | None = Field(default=None, ge=0, le=2**63 - 1)
    topics: list[Annotated[str, Field(max_length=200)]] | None = Field(
        default=None, max_length=1000
    )
    resample_s: float | None = Field(default=None, ge=archive_work.MIN_RESAMPLE_S, le=86_400)
    source: Literal["archive", "received"] = "archive"
    #: The dataset's metadata (ACDD/IOOS attribute names, ``platform``,
    #: ``instruments``: what a project's dataset.yaml holds; docs/user-guide/datasets.md).
    metadata: dict[str, Any] | None = None
    #: The project whose saved dataset metadata (its head revision) the file
    #: carries when ``metadata`` is not given (Archives → Dataset metadata).
    project: int | None = Field(default=None, ge=1, le=2**31 - 1)


def _metadata(body: ExportIn, state: AppState) -> dict[str, Any] | None:
    """The body's metadata, else the named project's saved one (None: neither)."""
    if body.metadata is not None or body.project is None:
        return body.metadata
    with state.store.session() as db:  # read and closed before the long export
        row = head_metadata(db, body.project)
        doc: dict[str, Any] | None = json.loads(row.metadata_json) if row is not None else None
    return doc


def _compact(ns: int) -> str:
    return dt.datetime.fromtimestamp(ns // 1_000_000_000, dt.UTC).strftime("%Y%m%dT%H%M%SZ")


def export_name(drone: str, received: bool, first_ns: int | None, last_ns: int | None) -> str:
    """A download's name: the drone, what it holds and the time span written.

    >>> export_name("usv", False, 1_790_000_000 * 10**9, 1_790_003_600 * 10**9)
    'usv-dataset-20260921T141320Z-20260921T151320Z'
    """
    base = f"{drone}-{'received' if received else 'dataset'}"
    if first_ns is None or last_ns is None:
        return base
    return f"{base}-{_compact(first_ns)}-{_compact(last_ns)}"


EXPORT_TYPES = {
    "netcdf": ("application/x-netcdf", ".nc"),
    "parquet": ("application/vnd.apache.parquet", ".parquet"),
    "csv": ("text/csv", ".csv"),
    "geojson": ("application/geo+json", ".geojson"),
    "gpx": ("application/gpx+xml", ".gpx"),
}


@router.post(
    "/export",
    response_class=FileResponse,
    dependencies=[Heavy],
    responses={
        **NOT_FOUND,
        **BUSY,
        200: {"content": {t: {} for t, _ in EXPORT_TYPES.values()}},
        413: {"description": f"more than {MAX_EXPORT_SAMPLES:,} samples in the range"},
        422: {"description": "an invalid model, or nothing to export"},
    },
)
async def export_dataset(
    drone: Drone, body: ExportIn, state: StateDep, user: UserDep, request: Request
) -> FileResponse:
    """The archive (or the windows the subscribers received) as a dataset file,
    streamed as a download (made in a worker process in this user's fair turn,
    bounded in bytes, samples and time: docs/backend.md; notes in ``X-Modd-Notes``)."""
    from modd.dataset.build import DatasetError

    metadata = await run_in_threadpool(_metadata, body, state)
    received = body.source == "received"
    root = state.settings.effective_record_dir if received else state.settings.effective_archive_dir
    paths = _export_paths(root, drone, body.files, received)
    media, suffix = EXPORT_TYPES[body.format]
    fd, tmp = tempfile.mkstemp(prefix="modd-export-", suffix=suffix)
    os.close(fd)
    out = FsPath(tmp)
    hide = _hider(root, "<records>" if received else "<archives>")
    try:
        notes, first_ns, last_ns = await in_worker(
            request,
            state,
            user,
            dataset_file,
            paths,
            body.model,
            body.format,
            out,
            body.start_ns,
            body.end_ns,
            body.topics,
            body.resample_s,
            archive_work.MAX_EXPORT_SAMPLES,
            received,
            metadata,
            time_s=EXPORT_TIME_S,
        )
    except DatasetError as exc:
        out.unlink(missing_ok=True)  # the next clause does not see what this one raises
        text = hide(str(exc))
        raise HTTPException(
            413 if "more than" in text and "samples" in text else 422, text
        ) from None
    except BaseException:
        out.unlink(missing_ok=True)
        raise
    name = export_name(drone, received, first_ns, last_ns) + suffix
    headers = {"X-Modd-Notes": json.dumps([hide(n) for n in notes[:20]], ensure_ascii=True)}
    return FileResponse(
        out,
        media_type=media,
        filename=name,
        headers=headers,
        background=BackgroundTask(out.unlink, missing_ok=True),
    )


def _export_paths(root: FsPath, drone: str, files: list[str], received: bool) -> list[FsPath]:
    """The files an export reads: each named once (422 for a repeat, also
    through a link), within MAX_ARCHIVE_BYTES (413); all of them when none is named."""
    repeated = sorted(n for n, k in Counter(files).items() if k > 1)
    if repeated:
        raise HTTPException(422, f"files name {repeated[0]!r} more than once: name each file once")
    paths = [archive_path(root, drone, n) for n in files] if files else list_files(root, drone)
    if len(set(paths)) != len(paths):
        raise HTTPException(422, "two of the files named are the same file: name each once")
    if not paths:
        raise HTTPException(404, f"no {'records' if received else 'archives'} for drone {drone!r}")
    return _bounded(paths)


def _bounded(paths: list[FsPath]) -> list[FsPath]:
    """``paths``, refused with 413 beyond MAX_ARCHIVE_BYTES in all."""
    try:
        check_bytes(paths)
    except Refused as exc:
        raise ApiError(exc.status, str(exc)) from None
    return paths


def _hider(root: FsPath, label: str) -> Callable[[str], str]:
    """A text with the server's own paths replaced (notes and errors say no server path)."""
    real = str(root.resolve())

    def hide(text: str) -> str:
        return text.replace(real, label).replace(str(root), label)

    return hide


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
def start_replay(
    drone: Drone,
    name: Name,
    body: ReplayIn,
    state: StateDep,
    user: Annotated[User, Depends(REPLAYERS)],
    link: ViewerLinks,
) -> ReplayOut:
    """Serves the range to Foxglove/Lichtblick with seek, play and pause
    (replacing the replay running now). A file still being written plays up
    to its last complete record."""
    return serve_replay(state, state.settings.effective_archive_dir, drone, name, body, user, link)


def serve_replay(
    state: AppState,
    root: FsPath,
    drone: str,
    name: str,
    body: ReplayIn,
    user: User,
    link: Callable[[str], str],
) -> ReplayOut:
    """The replay of ``<root>/<drone>/<name>`` (an archive or a base-station record)."""
    if state.replay is None:
        raise HTTPException(409, "replay is off on this backend (--foxglove-replay-port 0)")
    (path,) = _bounded([archive_path(root, drone, name)])
    try:
        info = state.replay.start(
            drone, path, body.start_ns, body.end_ns, user.username, autoplay=body.autoplay
        )
    except ValueError as exc:
        raise HTTPException(422, f"{name}: {exc}".replace(str(path), name)) from None
    except OSError as exc:
        raise HTTPException(409, f"the replay server cannot start: {exc.strerror or exc}") from None
    return ReplayOut.model_validate({**info.__dict__, "url": link("replay")})


@router.get(
    "/{name}",
    response_class=FileResponse,
    responses={**NOT_FOUND, 200: {"content": {"application/octet-stream": {}}}},
)
def download(drone: Drone, name: Name, state: StateDep, _user: UserDep) -> Response:
    path = archive_path(state.settings.effective_archive_dir, drone, name)
    return file_snapshot(path)  # a file still being written: what it held at the start


replay_router = APIRouter(prefix="/api/replay", tags=["archives"])


@replay_router.get("")
def current_replay(state: StateDep, _user: UserDep, link: ViewerLinks) -> ReplayOut | None:
    """The replay being served now (with a fresh ticket), or null."""
    info = state.replay.info if state.replay is not None else None
    return (
        None if info is None else ReplayOut.model_validate({**info.__dict__, "url": link("replay")})
    )


@replay_router.delete("", status_code=204)
def stop_replay(state: StateDep, _user: Annotated[User, Depends(REPLAYERS)]) -> None:
    if state.replay is not None:
        state.replay.stop()
