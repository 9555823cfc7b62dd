"""A project's model: read any revision, save a new one on top of the head
(409 when stale, 403 when a changed part is another role's), list versions,
export as .modd, JSON or the original tool's .collector form, validate without saving."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query
from fastapi.responses import Response
from modd_model import dumps
from modd_model.collector import print_collector
from pydantic import BaseModel, Field, TypeAdapter
from sqlalchemy import select
from sqlalchemy.orm import Session as Db

from ..bodies import Body, BodyDep, documented, parse_as
from ..deps import AppState, CredsDep, DbDep, StateDep, UserDep, in_store
from ..errors import ApiError
from ..modelio import diagnostics_json, read_input, require_document
from ..roles import EDITORS
from ..schemas import (
    ConflictOut,
    DiagnosticOut,
    Format,
    Id,
    InvalidModelOut,
    ModelInput,
    ModelOut,
    Responses,
    VersionOut,
)
from ..tables import ModelVersion, User
from ..versions import get_project, get_version, model_of, save_version, version_json
from .projects import DENIED, check_edit

router = APIRouter(prefix="/api", tags=["models"])
NOT_FOUND: Responses = {404: {"description": "no such project or revision"}}
Revision = Annotated[int | None, Query(ge=1, le=2**31 - 1)]
EDITING = tuple(sorted(EDITORS))


class SaveIn(ModelInput):
    """A new revision: the model (JSON or text) and the revision it was edited from."""

    base_revision: int = Field(ge=0, le=2**31 - 1)
    message: str = Field(default="", max_length=10_000)


class ValidateOut(BaseModel):
    ok: bool
    model: dict[str, Any] | None
    diagnostics: list[DiagnosticOut]


def answer_bytes(out: BaseModel | list[VersionOut]) -> bytes:
    """The JSON FastAPI would answer for ``out`` (its response model), built
    in the store's hop: the event loop only sends the bytes."""
    return _VERSIONS.dump_json(out) if isinstance(out, list) else out.model_dump_json().encode()


def json_bytes(data: bytes) -> Response:
    return Response(data, media_type="application/json")


_VERSIONS = TypeAdapter(list[VersionOut])


@router.get("/projects/{project_id}/model", response_model=ModelOut, responses=NOT_FOUND)
async def read_model(
    project_id: Id, state: StateDep, creds: CredsDep, revision: Revision = None
) -> Response:
    """(async: the whole request is one hop to the store, deps.in_store)"""
    return json_bytes(await in_store(state, creds, (), _read, project_id, revision))


def _read(db: Db, _user: User, project_id: int, revision: int | None) -> bytes:
    version = get_version(db, project_id, revision)
    return answer_bytes(ModelOut.model_validate(version_json(version)))


@router.put(
    "/projects/{project_id}/model",
    response_model=ModelOut,
    responses={**NOT_FOUND, **DENIED, 409: {"model": ConflictOut}, 422: {"model": InvalidModelOut}},
    openapi_extra=documented(SaveIn),
)
async def save_model(project_id: Id, raw: BodyDep, creds: CredsDep, state: StateDep) -> Response:
    """Save a new revision (the body is a :class:`SaveIn`, read and
    validated in the store's hop, not on the event loop:
    modd_backend.bodies, deps.in_store). Text input keeps the current diagram
    layout (the .modd text has none). Everyone watching the project over a
    stream WebSocket hears of it (``{"type": "saved", ...}``)."""
    data, event = await in_store(state, creds, EDITING, _save, project_id, raw)
    state.project_events.publish(project_id, event)
    return json_bytes(data)


def _save(db: Db, user: User, project_id: int, raw: Body) -> tuple[bytes, dict[str, Any]]:
    """The saved revision's answer and the event its watchers hear."""
    body = parse_as(raw, SaveIn)
    # a JSON model is stored as it is (its diagnostics come with the saved
    # revision, versions.diagnostics_of); text is read into one first
    model = body.model
    if model is None:
        model = require_document(read_input(body, f"project-{project_id}.{body.format}"))
    get_project(db, project_id)
    from_text = body.text is not None

    def check(before: dict[str, Any], after: dict[str, Any]) -> dict[str, Any]:
        if from_text and "layout" in before and "layout" not in after:
            after = {**after, "layout": before["layout"]}
        check_edit(user, before, after)
        return after

    version = save_version(
        db, project_id, body.base_revision, model, user.username, body.message, check
    )
    return answer_bytes(ModelOut.model_validate(version_json(version))), saved_event(version)


def saved_event(version: ModelVersion) -> dict[str, Any]:
    """What a project's watchers hear of a saved revision."""
    return {
        "type": "saved",
        "project": version.project_id,
        "revision": version.revision,
        "author": version.author,
        "message": version.message[:200],
    }


def announce_save(state: AppState, version: ModelVersion) -> None:
    """Tell the project's watchers that a revision was saved."""
    state.project_events.publish(version.project_id, saved_event(version))


@router.get("/projects/{project_id}/versions", response_model=list[VersionOut], responses=NOT_FOUND)
async def list_versions(project_id: Id, state: StateDep, creds: CredsDep) -> Response:
    return json_bytes(await in_store(state, creds, (), _versions, project_id))


def _versions(db: Db, _user: User, project_id: int) -> bytes:
    get_project(db, project_id)
    rows = db.scalars(
        select(ModelVersion)
        .where(ModelVersion.project_id == project_id)
        .order_by(ModelVersion.revision.desc())
    )
    return answer_bytes([VersionOut.model_validate(version_json(v, False)) for v in rows])


@router.get(
    "/projects/{project_id}/export",
    responses={
        **NOT_FOUND,
        200: {"content": {"text/plain": {}, "application/json": {}}},
        422: {"description": "an invalid revision cannot be printed as .modd"},
    },
)
def export_model(
    project_id: Id,
    db: DbDep,
    _user: UserDep,
    format: Format | Literal["collector"] = "modd",
    revision: Revision = None,
) -> Response:
    """The model as a file: canonical .modd text, JSON (layout kept in JSON only)
    or the original MoDD tool's .collector form, which opens with a comment per
    thing that form cannot hold."""
    version = get_version(db, project_id, revision)
    try:
        if format == "collector":
            text = print_collector(model_of(version), note_omissions=True)[0]
        else:
            text = dumps(model_of(version), format)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ApiError(
            422, f"revision {version.revision} is not valid enough to print as .modd: {exc!r}"
        ) from None
    media = "application/json" if format == "json" else "text/plain; charset=utf-8"
    name = f"project-{project_id}-r{version.revision}.{format}"
    return Response(
        text, media_type=media, headers={"Content-Disposition": f'attachment; filename="{name}"'}
    )


@router.post(
    "/validate", responses={422: {"model": InvalidModelOut}}, openapi_extra=documented(ModelInput)
)
def validate_model(raw: BodyDep, _user: UserDep) -> ValidateOut:
    """Parse and validate without saving; ``model`` is the parsed JSON
    document. The body (a :class:`ModelInput`) is read in the thread pool,
    not on the event loop (modd_backend.bodies)."""
    result = read_input(parse_as(raw, ModelInput))
    return ValidateOut(
        ok=result.ok,
        model=result.model,
        diagnostics=[DiagnosticOut.model_validate(d) for d in diagnostics_json(result.diagnostics)],
    )


class PrintIn(BaseModel):
    """A model document (possibly unsaved) to print as canonical .modd text."""

    model: dict[str, Any]


@router.post(
    "/print",
    responses={
        200: {"content": {"text/plain": {}}},
        422: {"description": "not valid enough to print as .modd"},
    },
)
def print_modd(body: PrintIn, _user: UserDep) -> Response:
    """The .modd text of a model as the diagram holds it, saved or not, so the
    text view can follow diagram edits before a save."""
    try:
        text = dumps(body.model, "modd")
    except Exception as exc:  # any shape may arrive from an editor mid-edit: never a 500
        raise ApiError(422, f"the model is not valid enough to print as .modd: {exc!r}") from None
    return Response(text, media_type="text/plain; charset=utf-8")
