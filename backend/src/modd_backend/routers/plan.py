"""The live plan: post a model (JSON or .modd text) and get the planning
engine's output (schedule, buffer sizes, delays, predicted link bytes/s,
infeasibilities) with the model's diagnostics."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Response
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel

from ..archives import archive_path
from ..bodies import BodyDep, documented, read_as
from ..deps import DbDep, StateDep, UserDep
from ..planning import Method, guarded_call, plan_request
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


def plan_response_json(
    model: dict[str, Any] | None,
    text: str | None,
    fmt: str,
    method: Method,
    calibrate: str | None,
    timeout_s: float,
) -> bytes:
    """In a worker: :func:`plan_request`, and its answer as :class:`PlanOut`
    JSON (pydantic's serialiser: 0.1 s for a plan of 10 MB, where FastAPI's
    encoder on the event loop took 2 s and stalled every other request)."""
    return (
        PlanOut.model_validate(plan_request(model, text, fmt, method, timeout_s, calibrate))
        .model_dump_json()
        .encode()
    )


def plan_body_json(
    body: bytes, is_json: bool, method: Method, calibrate: str | None, timeout_s: float
) -> bytes | list[dict[str, Any]]:
    """In a worker: the raw request body read as :class:`ModelInput` (the
    JSON parse and the check FastAPI would have made on the event loop: 0.1 s
    of CPU for a 4 MiB model, and the parsed model then pickled to the
    worker), then :func:`plan_response_json`. A body that is not a
    ModelInput gives FastAPI's validation errors (``loc`` from ``body``),
    which the route answers with 422 as FastAPI does."""
    parsed = read_as(body, is_json, ModelInput)
    if isinstance(parsed, list):
        return parsed
    return plan_response_json(
        parsed.model, parsed.text, parsed.format, method, calibrate, timeout_s
    )


async def _plan_response(
    model: dict[str, Any] | None, text: str | None, fmt: str, method: Method
) -> Response:
    out = await guarded_call(plan_response_json, model, text, fmt, method, None)
    if isinstance(out, dict):  # the worker's failure (over time or memory)
        out = PlanOut.model_validate(out).model_dump_json().encode()
    return Response(out, media_type="application/json")


@router.post(
    "/plan",
    response_model=PlanOut,
    openapi_extra=documented(ModelInput),
    responses={503: {"description": "the planner is busy; retry"}},
)
async def plan_model(
    body: BodyDep,
    state: StateDep,
    _user: UserDep,
    method: Method = "exact",
    calibrate: Annotated[
        str | None,
        Query(
            description="an archive the backend holds, DRONE/NAME.mcap: its samples size "
            "the quantised values (docs/planning.md, 'Bounds and estimates')",
            max_length=300,
        ),
    ] = None,
) -> Response:
    """The body is a :class:`ModelInput`. Its parse, its validation, the
    planning and the answer's JSON all run in a worker process within a time
    and memory budget (modd_backend.planning), never on the event loop:
    the route hands the worker the body's bytes (and the path of the
    ``calibrate`` archive, checked to be one of the archive directory's)."""
    path = None
    if calibrate is not None:
        drone, _, name = calibrate.partition("/")
        root = state.settings.effective_archive_dir
        path = str(archive_path(root, drone, name))
    out = await guarded_call(plan_body_json, body.data, body.is_json, method, path)
    if isinstance(out, list):
        raise RequestValidationError(out)
    if isinstance(out, dict):  # the worker's failure (over time or memory)
        out = PlanOut.model_validate(out).model_dump_json().encode()
    return Response(out, media_type="application/json")


@router.get(
    "/projects/{project_id}/plan",
    response_model=PlanOut,
    responses={
        404: {"description": "no such revision"},
        503: {"description": "the planner is busy; retry"},
    },
)
async def plan_version(
    project_id: Id,
    db: DbDep,
    _user: UserDep,
    revision: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    method: Method = "exact",
) -> Response:
    model = await run_in_threadpool(lambda: model_of(get_version(db, project_id, revision)))
    return await _plan_response(model, None, "json", method)
