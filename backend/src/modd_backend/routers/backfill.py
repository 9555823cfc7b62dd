"""Backfill through the workbench (docs/backend.md, "Backfill"): the SubBroker's
``modd/<drone>/backfill`` queryable behind role checks.

- ``POST /api/drones/{drone}/backfill`` (scientist, operator): start filling a
  subscriber's gaps (``gaps``) or a time range (``from_ns``, ``to_ns``); a
  scientist may only lower the pace, and a dynamic subscription is backfilled
  for its owner only (the SubBroker checks ``owner``).
- ``GET .../backfill/{id}``: the job's progress (windows done / total,
  bytes/s against the pace, seconds left) and the SubBroker's view of its queue
  (each job's state, windows and seconds at the measured pace).
- ``POST .../backfill/{id}/cap`` (operator): set the pace of a running job.
- ``DELETE .../backfill/{id}`` (operator, or the scientist who started it): cancel.
"""

from __future__ import annotations

import json
import threading
from typing import Annotated, Any

from fastapi import APIRouter, Depends, HTTPException, Path
from modd_contracts.keys import backfill_key
from pydantic import BaseModel, Field
from starlette.concurrency import run_in_threadpool

from ..deps import StateDep, UserDep, has_role, require, zenoh_session_of
from ..roles import Role
from ..zenoh_session import ZenohSession

router = APIRouter(prefix="/api/drones", tags=["backfill"])
Drone = Annotated[str, Path(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]
JobId = Annotated[int, Path(ge=1, le=2**31)]
Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]
MAX_RATE = 1_000_000_000
TIMEOUT_S = 5.0

# who started which job (drone, id) -> username, so that a scientist cancels only their own
_started: dict[tuple[str, int], str] = {}
_lock = threading.Lock()


class BackfillIn(BaseModel):
    subscriber: Name
    gaps: bool = False
    from_ns: int | None = Field(default=None, ge=0)
    to_ns: int | None = Field(default=None, ge=0)
    rate_bps: int | None = Field(default=None, ge=1, le=MAX_RATE)


class CapIn(BaseModel):
    rate_bps: int = Field(ge=1, le=MAX_RATE)


class Progress(BaseModel):
    """The SubBroker's progress document (docs/subbroker.md, "Backfill"; its contract:
    modd_contracts/schemas/backfill.schema.json, ``BackfillProgress``); ``queue`` (the
    SubBroker's view of its backfill queue, ``BackfillQueue``) is relayed as it is."""

    status: str
    reason: str | None = None
    id: int | None = None
    subscriber: str | None = None
    windows: int = 0
    windows_done: int = 0
    windows_total: int = 0
    duplicates: int = 0
    bytes: int = 0
    rate_bps: int = 0
    seconds: float = 0.0
    bytes_per_s: float = 0.0
    seconds_left: float | None = None
    requests: int = 0
    resumes: int = 0
    queue: dict[str, Any] | None = None


def _ask(zenoh_session: ZenohSession, drone: str, request: dict[str, Any]) -> Progress:
    key = backfill_key(drone)
    result = zenoh_session.query(key, json.dumps(request).encode(), TIMEOUT_S)
    if not result.ok:
        return Progress(status="NO_REPLY", reason=result.error)
    reply = result.json()
    if not isinstance(reply, dict):
        return Progress(status="ERROR", reason="the SubBroker's reply is not a JSON object")
    return Progress.model_validate(reply)


Either = Depends(require(Role.scientist, Role.operator))
Operator = Depends(require(Role.operator))


@router.post("/{drone}/backfill", dependencies=[Either])
async def start(drone: Drone, body: BackfillIn, state: StateDep, user: UserDep) -> Progress:
    if not body.gaps and (body.from_ns is None or body.to_ns is None):
        raise HTTPException(422, "give gaps: true, or from_ns and to_ns")
    request: dict[str, Any] = {
        "op": "start",
        **body.model_dump(exclude_none=True),
        "owner": user.username,
    }
    reply = await run_in_threadpool(_ask, zenoh_session_of(state), drone, request)
    if reply.id is not None:
        with _lock:
            _started[(drone, reply.id)] = user.username
            for old in list(_started)[:-1024]:  # bounded: the last 1024 jobs
                del _started[old]
    return reply


@router.get("/{drone}/backfill/{job_id}", dependencies=[Either])
async def progress(drone: Drone, job_id: JobId, state: StateDep) -> Progress:
    return await run_in_threadpool(
        _ask, zenoh_session_of(state), drone, {"op": "progress", "id": job_id}
    )


@router.post("/{drone}/backfill/{job_id}/cap", dependencies=[Operator])
async def cap(drone: Drone, job_id: JobId, body: CapIn, state: StateDep) -> Progress:
    return await run_in_threadpool(
        _ask, zenoh_session_of(state), drone, {"op": "cap", "id": job_id, "rate_bps": body.rate_bps}
    )


@router.delete("/{drone}/backfill/{job_id}", dependencies=[Either])
async def cancel(drone: Drone, job_id: JobId, state: StateDep, user: UserDep) -> Progress:
    with _lock:
        starter = _started.get((drone, job_id))
    if not has_role(user, Role.operator) and starter != user.username:
        raise HTTPException(403, "only the operator or who started it may cancel a backfill")
    return await run_in_threadpool(
        _ask, zenoh_session_of(state), drone, {"op": "cancel", "id": job_id}
    )
