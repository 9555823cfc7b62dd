"""Projects and their model versions: every save is a new revision, saved
only on top of the current one (optimistic concurrency)."""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

from modd_model import validate
from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session as Db

from .errors import ApiError
from .modelio import canonical_json, diagnostics_json
from .tables import ModelVersion, Project


def get_project(db: Db, project_id: int) -> Project:
    project = db.get(Project, project_id)
    if project is None:
        raise ApiError(404, f"no project {project_id}")
    return project


def head_revision(db: Db, project_id: int) -> int:
    rev = db.scalar(
        select(func.max(ModelVersion.revision)).where(ModelVersion.project_id == project_id)
    )
    return int(rev or 0)


def get_version(db: Db, project_id: int, revision: int | None = None) -> ModelVersion:
    """The given revision, or the head; 404 when there is none. One query
    when found (every editor reads its head all the time, issue 41)."""
    if revision is None:
        version = head_version(db, project_id)
    else:
        version = db.scalar(
            select(ModelVersion).where(
                ModelVersion.project_id == project_id, ModelVersion.revision == revision
            )
        )
    if version is None:
        get_project(db, project_id)  # 404 for the project first
        what = f"revision {revision}" if revision is not None else "model yet"
        raise ApiError(404, f"project {project_id} has no {what}")
    return version


def model_of(version: ModelVersion | None) -> dict[str, Any]:
    if version is None:
        return {}
    doc: dict[str, Any] = json.loads(version.model_json)
    return doc


def head_version(db: Db, project_id: int) -> ModelVersion | None:
    """The head row itself, read in one statement (revision and model agree)."""
    return db.scalar(
        select(ModelVersion)
        .where(ModelVersion.project_id == project_id)
        .order_by(ModelVersion.revision.desc())
        .limit(1)
    )


#: Checks a save against the model it replaces; may return the model to store
#: (e.g. with the replaced layout kept) or raise ApiError (403 ...).
SaveCheck = Callable[[dict[str, Any], dict[str, Any]], dict[str, Any]]


def save_version(
    db: Db,
    project_id: int,
    base_revision: int,
    model: dict[str, Any],
    author: str,
    message: str,
    check: SaveCheck | None = None,
) -> ModelVersion:
    """Store ``model`` as revision base+1; 409 with the current revision when
    ``base_revision`` is not the head (also when a concurrent save won).

    ``check(before, after)`` runs against the revision this save actually
    replaces, read in the same transaction as the insert: revision numbers are
    unique per project, so the insert of head+1 fails (409) unless the head
    checked is still the head. A stale base is a 409 before any role check."""
    head = head_version(db, project_id)
    current = head.revision if head is not None else 0
    if base_revision != current:
        db.rollback()
        raise stale(base_revision, current)
    if check is not None:
        model = check(model_of(head), model)
    version = ModelVersion(
        project_id=project_id,
        revision=current + 1,
        model_json=(stored := canonical_json(model)),
        valid=not any(d["severity"] == "error" for d in diagnostics_of(stored)),
        author=author,
        message=message,
    )
    db.add(version)
    try:
        db.commit()
    except IntegrityError:
        db.rollback()
        raise stale(base_revision, head_revision(db, project_id)) from None
    return version


def stale(base: int, current: int, what: str = "the model") -> ApiError:
    """409: ``what`` was saved on top of ``base`` meanwhile (the head is ``current``)."""
    return ApiError(
        409,
        f"{what} was saved meanwhile: you edited revision {base}, the current one is "
        f"{current}; reload and merge",
        current_revision=current,
    )


def version_json(version: ModelVersion, with_model: bool = True) -> dict[str, Any]:
    out: dict[str, Any] = {
        "project_id": version.project_id,
        "revision": version.revision,
        "valid": version.valid,
        "author": version.author,
        "message": version.message,
        "created_at": version.created_at,
    }
    if with_model:
        out["model"] = model_of(version)
        out["diagnostics"] = diagnostics_of(version.model_json)
    return out


#: Diagnostics of the models last saved or read, by their stored JSON: a
#: revision never changes, and every editor reads the head it just saved
#: (issue 41: validation was a third of a save's thread time, twice per save
#: and once per read). Models up to ``_CACHED_CHARS`` long, ``_CACHED`` of them.
_CACHED, _CACHED_CHARS = 128, 1 << 18
_diagnostics: OrderedDict[str, list[dict[str, object]]] = OrderedDict()
_diagnostics_lock = threading.Lock()


def diagnostics_of(model_json: str) -> list[dict[str, object]]:
    """The diagnostics (JSON) of a stored model (its ``model_json``)."""
    with _diagnostics_lock:
        found = _diagnostics.get(model_json)
        if found is not None:
            _diagnostics.move_to_end(model_json)
            return list(found)
    diags = diagnostics_json(validate(json.loads(model_json)))
    if len(model_json) <= _CACHED_CHARS:
        with _diagnostics_lock:
            _diagnostics[model_json] = diags
            while len(_diagnostics) > _CACHED:
                _diagnostics.popitem(last=False)
    return list(diags)
