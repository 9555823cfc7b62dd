"""The live plan: post a model (JSON or .modd text) and get the planning
engine's output (schedule, buffer sizes, delays, predicted link bytes/s,
infeasibilities) with the model's diagnostics."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.concurrency import run_in_threadpool
from pydantic import BaseModel

from ..deps import DbDep, UserDep
from ..planning import Method, guarded_plan
from ..schemas import DiagnosticOut, Id, ModelInput
from ..versions import get_version, model_of

router = APIRouter(prefix="/api", tags=["plan"])


class PlanOut(BaseModel):
    """``plan`` is Plan.to_json() of modd_plan (docs/planning.md), null when the
    model has errors; ``diagnostics`` then says where."""

    ok: bool
    plan: dict[str, Any] | None
    diagnostics: list[DiagnosticOut]
    elapsed_ms: float


@router.post("/plan", responses={503: {"description": "the planner is busy; retry"}})
async def plan_model(body: ModelInput, _user: UserDep, method: Method = "exact") -> PlanOut:
    """Parsing, validation and planning run in a worker process within a time
    and memory budget (modd_backend.planning), never on the event loop."""
    return PlanOut.model_validate(await guarded_plan(body.model, body.text, body.format, method))


@router.get("/projects/{project_id}/plan", responses={
    404: {"description": "no such revision"}, 503: {"description": "the planner is busy; retry"}})
async def plan_version(
    project_id: Id,
    db: DbDep,
    _user: UserDep,
    revision: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    method: Method = "exact",
) -> PlanOut:
    model = await run_in_threadpool(lambda: model_of(get_version(db, project_id, revision)))
    return PlanOut.model_validate(await guarded_plan(model, None, "json", method))
