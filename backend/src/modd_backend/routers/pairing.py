"""Pairing: an operator makes the bundle that pairs a project's drone with this
base station (modd_backend.pairing). The bundle and its one-time code come in
the body of a POST, never in a URL, are not stored by any cache (no-store) and
are never logged; the code is shown once."""

from __future__ import annotations

from datetime import UTC, datetime

from fastapi import APIRouter, Depends
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field

from ..deps import DbDep, StateDep, UserDep, require
from ..errors import ApiError
from ..modelio import require_valid
from ..pairing import make_bundle
from ..roles import Role
from ..schemas import Id
from ..versions import get_version, model_of

router = APIRouter(prefix="/api/projects", tags=["pairing"])
NO_STORE = {"Cache-Control": "no-store", "Pragma": "no-cache"}


class PairingIn(BaseModel):
    revision: int | None = Field(
        default=None, ge=1, le=2**31 - 1, description="the head when absent"
    )


class PairingOut(BaseModel):
    """``bundle``: the file's text (save it as ``filename``); ``code``: the one-time
    code that opens it, shown once; ``fingerprint``: the station's key, which the
    drone pins; ``link_key_file``: where this station keeps the drone's link key
    (its SubBroker's ``[link] key = "file:..."``)."""

    drone: str
    revision: int
    filename: str
    bundle: str
    code: str
    fingerprint: str
    expires_at: datetime
    link_key_file: str


@router.post(
    "/{project_id}/pairing",
    dependencies=[Depends(require(Role.operator))],
    response_model=PairingOut,
    responses={
        404: {"description": "no such project or revision"},
        422: {"description": "the revision has errors"},
    },
)
def make_pairing(
    project_id: Id, body: PairingIn, db: DbDep, user: UserDep, state: StateDep
) -> JSONResponse:
    """A pairing bundle for the drone of the project's revision (the head when absent)."""
    version = get_version(db, project_id, body.revision)
    model = model_of(version)
    require_valid(model, version.revision, "before pairing")
    settings = state.settings
    try:
        made = make_bundle(model, settings.effective_pairing_key, settings.effective_link_keys)
    except ValueError as exc:
        raise ApiError(422, f"cannot make the pairing bundle: {exc}") from None
    out = PairingOut(
        drone=made.drone,
        revision=version.revision,
        filename=made.filename,
        bundle=made.data.decode("ascii"),
        code=made.code,
        fingerprint=made.bundle.fingerprint,
        expires_at=datetime.fromtimestamp(made.bundle.expires_ns / 1e9, UTC),
        link_key_file=str(made.link_key_file),
    )
    return JSONResponse(out.model_dump(mode="json"), headers=NO_STORE)
