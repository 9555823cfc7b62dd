"""Downloads: a model revision's generated artefacts for one role, as a zip.
Each role downloads its own target (admin any)."""

from __future__ import annotations

import json
import re
from typing import Annotated, Literal

from fastapi import APIRouter, Query
from fastapi.responses import Response
from modd.zenoh_auth import remade_notes

from ..deps import DbDep, StateDep, UserDep, has_role
from ..downloads import as_run, role_zip, station_of
from ..errors import ApiError
from ..layouts import foxglove_layout
from ..modelio import require_valid
from ..roles import Role
from ..schemas import Id, Responses
from ..versions import get_project, get_version, model_of

router = APIRouter(prefix="/api/projects", tags=["downloads"])
credentials_router = APIRouter(prefix="/api/credentials", tags=["downloads"])
Target = Literal["integrator", "operator", "scientist"]
RESPONSES: Responses = {
    200: {"content": {"application/zip": {}}},
    403: {"description": "the target is another role's"},
    404: {"description": "no such project or revision"},
    422: {"description": "the revision has errors"},
}


@router.get("/{project_id}/downloads/{target}", response_class=Response, responses=RESPONSES)
def download(
    project_id: Id,
    target: Target,
    db: DbDep,
    user: UserDep,
    state: StateDep,
    revision: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
) -> Response:
    """integrator: C++ driver projects (naming the ingress socket and archive
    directory of the run this backend watches, e.g. ``make run``'s, when there
    is one); operator: PubBroker and SubBroker configs; scientist: Python and
    C++ subscriber stubs (connecting to the SubBroker this backend connects to,
    and naming the viewer's credentials file beside the backend's)."""
    if not has_role(user, Role(target)):
        raise ApiError(403, f"the {target} downloads need the role {target}")
    project = get_project(db, project_id)
    version = get_version(db, project_id, revision)
    model = model_of(version)
    require_valid(model, version.revision)
    folder = f"{project.name}-r{version.revision}-{target}".replace(" ", "_")
    try:
        if target == "integrator":
            model = as_run(model, state.settings.archive_dir)
        settings = state.settings
        station = (
            station_of(settings.zenoh_connect, settings.zenoh_credentials)
            if target == "scientist" and settings.zenoh_enabled
            else None
        )
        data = role_zip(model, target, folder, station)
    except ValueError as exc:
        raise ApiError(422, f"the generators cannot handle this model: {exc}") from None
    return Response(
        data,
        media_type="application/zip",
        headers={"Content-Disposition": f'attachment; filename="{folder}.zip"'},
    )


@router.get(
    "/{project_id}/foxglove-layout",
    responses={
        200: {"content": {"application/json": {}}},
        403: {"description": "not a scientist"},
        404: {"description": "no such project or revision"},
        422: {"description": "the revision has errors"},
    },
)
def foxglove_layout_download(
    project_id: Id,
    db: DbDep,
    user: UserDep,
    revision: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
) -> Response:
    """A Foxglove/Lichtblick layout for the project's live mission (a plot per
    subscriber grouped by topic, a map of the position, the link status);
    docs/ecosystem.md."""
    if not has_role(user, Role.scientist):
        raise ApiError(403, "the Foxglove layout is a scientist's download")
    project = get_project(db, project_id)
    version = get_version(db, project_id, revision)
    model = model_of(version)
    require_valid(model, version.revision)  # an invalid one may lack any part the layout reads
    safe = re.sub(r"[^A-Za-z0-9_.-]", "_", project.name)
    name = f"{safe}-r{version.revision}-foxglove-layout"
    body = json.dumps(foxglove_layout(model), indent=1).encode()
    return Response(
        body,
        media_type="application/json",
        headers={"Content-Disposition": f'attachment; filename="{name}.json"'},
    )


@credentials_router.get("/remade")
def credentials_remade(user: UserDep, state: StateDep) -> dict[str, list[dict[str, str]]]:
    """The credential files of the base station this backend connects to
    (beside its own, ``make run``'s ``data/credentials``) that were made anew
    with a new secret after the first start (deleted by hand), with when (UTC):
    copies handed out before, in downloads among them, no longer work. Names
    and times only; no secret is read."""
    creds = state.settings.zenoh_credentials
    notes = remade_notes(creds.parent) if creds is not None else {}
    return {"remade": [{"file": f, "at": at} for f, at in sorted(notes.items())]}
