"""Projects: list, create (empty, from a JSON/text model, or by importing a
raw .modd or JSON file), read, delete."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query
from pydantic import BaseModel, Field
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session as Db

from ..bodies import BodyDep, documented, parse_as
from ..deps import DbDep, RawBody, UserDep, require, roles_of
from ..errors import ApiError
from ..modelio import decode_body, read_input, require_document
from ..roles import EDITORS, Role, may_edit, owners_of_changes
from ..schemas import Format, Id, ModelInput, Responses
from ..tables import Project, User
from ..versions import get_project, head_revision, save_version

router = APIRouter(prefix="/api/projects", tags=["projects"])
Editor = Depends(require(*EDITORS))
NAME = r"^[A-Za-z0-9_][A-Za-z0-9_. -]*$"
DENIED: Responses = {403: {"description": "a role owning a changed part is missing"}}


class ProjectIn(BaseModel):
    name: str = Field(min_length=1, max_length=128, pattern=NAME)
    model: ModelInput | None = None
    message: str = Field(default="created", max_length=10_000)


class ProjectOut(BaseModel):
    id: int
    name: str
    created_at: datetime
    created_by: str
    head_revision: int


def project_out(db: Db, project: Project) -> ProjectOut:
    return ProjectOut(
        id=project.id,
        name=project.name,
        created_at=project.created_at,
        created_by=project.created_by,
        head_revision=head_revision(db, project.id),
    )


def check_edit(user: User, before: dict[str, Any], after: dict[str, Any]) -> None:
    """403 naming every changed part whose owning role the user lacks."""
    changes = owners_of_changes(before, after)
    denied = may_edit(roles_of(user), changes)
    if denied:
        parts = [{"part": p, "role": changes[p] or "any editor"} for p in denied]
        listing = ", ".join(f"{d['part']} ({d['role']})" for d in parts)
        raise ApiError(403, f"you may not change {listing}", denied=parts)


def create_project(
    db: Db, user: User, name: str, model: dict[str, Any] | None, message: str
) -> ProjectOut:
    if model is not None:
        check_edit(user, {}, model)
    project = Project(name=name, created_by=user.username)
    db.add(project)
    try:
        db.flush()
    except IntegrityError:
        db.rollback()
        raise ApiError(409, f"a project named {name!r} exists") from None
    if model is not None:
        save_version(db, project.id, 0, model, user.username, message)
    db.commit()
    return project_out(db, project)


@router.get("")
def list_projects(db: DbDep, _user: UserDep) -> list[ProjectOut]:
    return [project_out(db, p) for p in db.scalars(select(Project).order_by(Project.id))]


@router.post(
    "",
    status_code=201,
    dependencies=[Editor],
    openapi_extra=documented(ProjectIn),
    responses={**DENIED, 409: {"description": "name taken"}},
)
def add_project(raw: BodyDep, db: DbDep, user: UserDep) -> ProjectOut:
    """Create a project, empty or with a model (the body is a
    :class:`ProjectIn`, read in the thread pool: modd_backend.bodies)."""
    body = parse_as(raw, ProjectIn)
    model = require_document(read_input(body.model)) if body.model is not None else None
    return create_project(db, user, body.name, model, body.message)


_RAW_BODY = {
    "requestBody": {
        "required": True,
        "content": {
            "text/plain": {"schema": {"type": "string"}},
            "application/json": {"schema": {"type": "object"}},
        },
    }
}


@router.post(
    "/import",
    status_code=201,
    dependencies=[Editor],
    openapi_extra=_RAW_BODY,
    responses={**DENIED, 409: {"description": "name taken"}},
)
def import_project(
    raw: RawBody,
    db: DbDep,
    user: UserDep,
    name: Annotated[str, Query(min_length=1, max_length=128, pattern=NAME)],
    format: Format = "modd",
) -> ProjectOut:
    """Create a project from a raw .modd or JSON file sent as the body."""
    model = require_document(decode_body(raw, format, f"{name}.{format}"))
    return create_project(db, user, name, model, f"imported {name}.{format}")


@router.get("/{project_id}", responses={404: {"description": "no such project"}})
def read_project(project_id: Id, db: DbDep, _user: UserDep) -> ProjectOut:
    return project_out(db, get_project(db, project_id))


@router.delete(
    "/{project_id}",
    status_code=204,
    dependencies=[Depends(require(Role.admin))],
    responses={404: {"description": "no such project"}},
)
def delete_project(project_id: Id, db: DbDep) -> None:
    db.delete(get_project(db, project_id))
    db.commit()
