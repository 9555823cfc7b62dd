"""``GET /api/health``: liveness and readiness for supervisors and container
healthchecks, without a login (it tells nothing about the missions).

It answers from the event loop: no worker thread and no database connection
is waited for, so heavy requests never delay it. The database is pinged in
the background (app.py) and its last result reported."""

from __future__ import annotations

from typing import Literal

from fastapi import APIRouter, Request, Response
from pydantic import BaseModel

from ..deps import AppState

router = APIRouter(prefix="/api", tags=["health"])


class HealthOut(BaseModel):
    """``ready``: the database answered its last ping and heavy requests have
    free slots (``heavy_in_flight`` of ``heavy_limit``)."""

    status: Literal["ok", "degraded"]
    database: Literal["ok", "error", "unknown"]
    zenoh: Literal["connected", "disabled"]
    scene: bool
    ready: bool
    saturated: bool
    heavy_in_flight: int
    heavy_limit: int


@router.get("/health", responses={503: {"model": HealthOut}})
async def health(request: Request, response: Response) -> HealthOut:
    """200 when the service answers and its database did at the last ping
    (503 otherwise); zenoh and the 3D scene are reported, not required."""
    state: AppState = request.app.state.modd
    database = state.database
    heavy = state.heavy
    saturated = heavy is not None and heavy.saturated
    if database == "error":
        response.status_code = 503
    return HealthOut(
        status="ok" if database != "error" else "degraded",
        database=database,
        zenoh="connected" if state.zenoh_session is not None else "disabled",
        scene=state.scene is not None,
        ready=database == "ok" and not saturated,
        saturated=saturated,
        heavy_in_flight=heavy.in_flight if heavy is not None else 0,
        heavy_limit=heavy.total if heavy is not None else 0,
    )
