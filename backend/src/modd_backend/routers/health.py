"""``GET /api/health``: liveness and readiness for supervisors and container
healthchecks, without a login (it tells nothing about the missions)."""

from __future__ import annotations

from typing import Literal

from fastapi import APIRouter
from pydantic import BaseModel
from sqlalchemy import text

from ..deps import DbDep, StateDep

router = APIRouter(prefix="/api", tags=["health"])


class HealthOut(BaseModel):
    status: Literal["ok"]
    database: Literal["ok"]
    zenoh: Literal["connected", "disabled"]
    scene: bool


@router.get("/health")
def health(db: DbDep, state: StateDep) -> HealthOut:
    """200 when the service answers and its database does; the zenoh session
    and the 3D scene are reported, not required (the workbench works without)."""
    db.execute(text("SELECT 1"))
    return HealthOut(status="ok", database="ok",
                     zenoh="connected" if state.bridge is not None else "disabled",
                     scene=state.scene is not None)
