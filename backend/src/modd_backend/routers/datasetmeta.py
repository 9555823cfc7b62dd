"""A project's dataset metadata (what ``dataset.yaml`` holds: the ACDD/IOOS
attributes, the platform, each sensor's instrument, the QARTOD tests): read any
revision, save a new one on top of the head (409 when stale, 422 located:
``{"detail", "key"}``), list revisions. Archives → Export dataset uses the
head when the request names the project (docs/user-guide/datasets.md)."""

from __future__ import annotations

import json
from datetime import datetime
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query
from pydantic import BaseModel, Field
from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session as Db

from ..deps import DbDep, UserDep, require
from ..errors import ApiError
from ..roles import EDITORS
from ..schemas import Id, Responses
from ..tables import DatasetMetadataVersion
from ..versions import get_project, head_version, model_of, stale

router = APIRouter(prefix="/api/projects", tags=["dataset metadata"])
NOT_FOUND: Responses = {404: {"description": "no such project or revision"}}
Revision = Annotated[int | None, Query(ge=1, le=2**31 - 1)]
#: What a metadata document may hold, in bytes of its JSON (a dataset.yaml is a few kB).
MAX_METADATA_BYTES = 256_000
WHAT = "the dataset metadata"


class MetadataIn(BaseModel):
    """A new revision: the document and the revision it was edited from (0: the first)."""

    base_revision: int = Field(ge=0, le=2**31 - 1)
    metadata: dict[str, Any]


class MetadataOut(BaseModel):
    project_id: int
    revision: int  # 0: none saved yet (``metadata`` is then empty)
    metadata: dict[str, Any]
    author: str | None
    created_at: datetime | None
    #: The attributes ACDD 1.3 / IOOS 1.2 ask for that the document does not give.
    missing: list[str]


def head_metadata(
    db: Db, project_id: int, revision: int | None = None
) -> DatasetMetadataVersion | None:
    """The given revision (404 when absent) or the head (None when none was saved)."""
    get_project(db, project_id)
    query = select(DatasetMetadataVersion).where(DatasetMetadataVersion.project_id == project_id)
    if revision is not None:
        row = db.scalar(query.where(DatasetMetadataVersion.revision == revision))
        if row is None:
            raise ApiError(404, f"project {project_id} has no dataset metadata revision {revision}")
        return row
    return db.scalar(query.order_by(DatasetMetadataVersion.revision.desc()).limit(1))


def checked(db: Db, project_id: int, doc: dict[str, Any]) -> list[str]:
    """The ACDD/IOOS attributes ``doc`` leaves out; 422 ``{detail, key}`` for a fault
    (the runtime's own rules: modd.dataset.metadata), or an instrument of no sensor."""
    from modd.dataset.metadata import ASKED, MetadataError, parse_metadata

    if len(json.dumps(doc)) > MAX_METADATA_BYTES:
        raise ApiError(413, f"dataset metadata over {MAX_METADATA_BYTES:,} bytes")
    try:
        meta = parse_metadata(doc, "metadata")
    except MetadataError as exc:
        raise ApiError(422, str(exc), key=exc.key) from None
    drone = model_of(head_version(db, project_id)).get("drone") or {}
    sensors = {s.get("name") for s in drone.get("sensors") or [] if isinstance(s, dict)}
    for name in meta.instruments:
        if sensors and name not in sensors:
            raise ApiError(
                422,
                f"metadata: instruments.{name}: the model has no sensor {name!r} "
                f"(one of {', '.join(sorted(str(s) for s in sensors))})",
                key=f"instruments.{name}",
            )
    return [k for k in ASKED if k not in meta.attributes]


def metadata_out(project_id: int, row: DatasetMetadataVersion | None, db: Db) -> MetadataOut:
    doc: dict[str, Any] = json.loads(row.metadata_json) if row is not None else {}
    return MetadataOut(
        project_id=project_id,
        revision=row.revision if row is not None else 0,
        metadata=doc,
        author=row.author if row is not None else None,
        created_at=row.created_at if row is not None else None,
        missing=checked(db, project_id, doc),
    )


@router.get("/{project_id}/dataset-metadata", responses=NOT_FOUND)
def read_metadata(
    project_id: Id, db: DbDep, _user: UserDep, revision: Revision = None
) -> MetadataOut:
    return metadata_out(project_id, head_metadata(db, project_id, revision), db)


@router.put(
    "/{project_id}/dataset-metadata",
    dependencies=[Depends(require(*EDITORS))],
    responses={
        **NOT_FOUND,
        409: {"description": "saved meanwhile: the body's base_revision is not the head"},
        422: {"description": "a fault in the document, located: detail and key"},
    },
)
def save_metadata(project_id: Id, body: MetadataIn, db: DbDep, user: UserDep) -> MetadataOut:
    """Store the document as the next revision (checked first, 422 located)."""
    checked(db, project_id, body.metadata)
    head = head_metadata(db, project_id)
    current = head.revision if head is not None else 0
    if body.base_revision != current:
        raise stale(body.base_revision, current, WHAT)
    row = DatasetMetadataVersion(
        project_id=project_id,
        revision=current + 1,
        metadata_json=json.dumps(body.metadata, sort_keys=True),
        author=user.username,
    )
    db.add(row)
    try:
        db.commit()
    except IntegrityError:
        db.rollback()
        raise stale(body.base_revision, _head_number(db, project_id), WHAT) from None
    return metadata_out(project_id, row, db)


@router.get("/{project_id}/dataset-metadata/versions", responses=NOT_FOUND)
def list_metadata_versions(project_id: Id, db: DbDep, _user: UserDep) -> list[dict[str, Any]]:
    """Every revision, newest first: its number, author and time."""
    get_project(db, project_id)
    rows = db.scalars(
        select(DatasetMetadataVersion)
        .where(DatasetMetadataVersion.project_id == project_id)
        .order_by(DatasetMetadataVersion.revision.desc())
    )
    return [{"revision": r.revision, "author": r.author, "created_at": r.created_at} for r in rows]


def _head_number(db: Db, project_id: int) -> int:
    rev = db.scalar(
        select(func.max(DatasetMetadataVersion.revision)).where(
            DatasetMetadataVersion.project_id == project_id
        )
    )
    return int(rev or 0)
