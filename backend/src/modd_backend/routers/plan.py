"""The live plan: post a model (JSON or .modd text) and get the planning
engine's output (schedule, buffer sizes, delays, predicted link bytes/s,
infeasibilities) with the model's diagnostics."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from modd_model import LoadResult, validate
from pydantic import BaseModel

from ..deps import DbDep, UserDep
from ..modelio import read_input
from ..planning import Method, live_plan
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


@router.post("/plan")
def plan_model(body: ModelInput, _user: UserDep, method: Method = "exact") -> PlanOut:
    return PlanOut.model_validate(live_plan(read_input(body), method).to_json())


@router.get("/projects/{project_id}/plan", responses={404: {"description": "no such revision"}})
def plan_version(
    project_id: Id,
    db: DbDep,
    _user: UserDep,
    revision: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    method: Method = "exact",
) -> PlanOut:
    model = model_of(get_version(db, project_id, revision))
    result = LoadResult(model, validate(model), {})
    return PlanOut.model_validate(live_plan(result, method).to_json())
