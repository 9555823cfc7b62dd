"""Deployments: an operator deploys a model version to its drone; everyone
can list them and see what is deployed against what is edited (a diff)."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query
from modd_model import validate
from modd_model.campaign import drone_names, expand, vehicles
from pydantic import BaseModel, Field
from sqlalchemy import select
from sqlalchemy.orm import Session as Db

from ..deployments import deploy, last_acked, record_json, signing_key
from ..deps import AppState, DbDep, Heavy, StateDep, UserDep, require, zenoh_session_of
from ..errors import ApiError
from ..modeldiff import diff
from ..modelio import diagnostics_json
from ..roles import Role
from ..schemas import Id, InvalidModelOut
from ..tables import Deployment, ModelVersion
from ..versions import get_project, get_version, model_of

router = APIRouter(prefix="/api", tags=["deploy"])


class DeployIn(BaseModel):
    revision: int | None = Field(
        default=None, ge=1, le=2**31 - 1, description="the head when absent"
    )


class DeploymentOut(BaseModel):
    """``status``: acked (the PubBroker took the config) or failed (``error``
    says why). ``reply`` is the SubBroker's answer as it came."""

    id: int
    project_id: int
    revision: int
    drone: str
    requested_by: str
    requested_at: datetime
    finished_at: datetime | None
    status: str
    reply: dict[str, Any] | None
    error: str | None


class DeployedDiffOut(BaseModel):
    """``source``: ``drone`` when the drone's status said what it runs (its
    ``drone_reports``; ``deployed`` is then that deployment's record, None for
    its configured model or a deploy this store does not hold), ``record``
    when the drone does not report and the last acked record stands in."""

    drone: str
    head_revision: int
    deployed: DeploymentOut | None
    same_project: bool
    changes: list[dict[str, Any]]
    source: str = "record"
    drone_reports: dict[str, Any] | None = None


@router.post(
    "/projects/{project_id}/deployments",
    status_code=201,
    dependencies=[Depends(require(Role.operator)), Heavy],
    responses={
        404: {"description": "no such project or revision"},
        409: {"description": "a campaign: POST .../fleet/deployments deploys to its drones"},
        422: {"model": InvalidModelOut, "description": "the version is not valid"},
    },
)
def deploy_version(
    project_id: Id, body: DeployIn, db: DbDep, user: UserDep, state: StateDep
) -> DeploymentOut:
    """Deploy and wait for the drone's answer (up to the deploy timeout); the
    record is created either way and says acked or failed."""
    version = get_version(db, project_id, body.revision)
    model = model_of(version)
    if vehicles(model):
        drones = drone_names(model)
        raise ApiError(
            409,
            f"revision {version.revision} is a campaign of {len(drones)} drones "
            f"({', '.join(drones)}): deploy it with POST "
            f"/api/projects/{project_id}/fleet/deployments",
        )
    if not version.valid:
        diags = diagnostics_json(validate(model))
        raise ApiError(
            422,
            f"revision {version.revision} has errors: fix them before deploying",
            diagnostics=diags,
        )
    record = deploy_model(state, db, version, model, user.username)
    return DeploymentOut.model_validate(record_json(record))


def deploy_model(
    state: AppState, db: Db, version: ModelVersion, model: dict[str, Any], username: str
) -> Deployment:
    """Deploy ``model`` (one drone's) as ``version``, signed, and wait for its ack."""
    record = deploy(
        db,
        zenoh_session_of(state),
        version,
        model,
        username,
        state.settings.deploy_timeout_s,
        signing_key(state.settings.deploy_key_file),
    )
    if record.status == "acked" and state.scene is not None:
        state.scene.forget(record.drone)  # the 3D scene re-reads the drone's model
    return record


@router.get("/projects/{project_id}/deployments", responses={404: {"description": "no project"}})
def list_deployments(project_id: Id, db: DbDep, _user: UserDep) -> list[DeploymentOut]:
    get_project(db, project_id)
    rows = db.scalars(
        select(Deployment).where(Deployment.project_id == project_id).order_by(Deployment.id.desc())
    )
    return [DeploymentOut.model_validate(record_json(d)) for d in rows]


@router.get(
    "/projects/{project_id}/deployed-diff",
    responses={404: {"description": "no project or no model"}},
)
def deployed_diff(
    project_id: Id,
    db: DbDep,
    _user: UserDep,
    state: StateDep,
    drone: Annotated[str | None, Query(max_length=64)] = None,
) -> DeployedDiffOut:
    """Changes from what runs on the drone (what its status reports; its last
    acked deployment when it does not report) to this project's head;
    everything is an addition when nothing known is deployed."""
    head = get_version(db, project_id)
    drones = expand(model_of(head))  # a campaign's drones; a one-drone model itself
    name = drone or next(iter(drones))
    edited = drones.get(name, model_of(head))
    reports = state.statuses.deployment(name) if state.statuses and name else None
    running: Deployment | None = None
    if reports is not None:
        nonce = reports.get("nonce")
        if isinstance(nonce, str):
            running = db.scalar(
                select(Deployment)
                .where(Deployment.drone == name, Deployment.nonce == nonce)
                .limit(1)
            )
    elif name:
        running = last_acked(db, name)
    deployed: dict[str, Any] = {}
    if running is not None:
        deployed = model_of(get_version(db, running.project_id, running.revision))
    return DeployedDiffOut(
        drone=name,
        head_revision=head.revision,
        deployed=DeploymentOut.model_validate(record_json(running)) if running else None,
        same_project=running is not None and running.project_id == project_id,
        changes=diff(deployed, edited),
        source="drone" if reports is not None else "record",
        drone_reports=reports,
    )


class RunningDroneOut(BaseModel):
    """A drone that reports its status now, and the link ends of the model last
    deployed to it (null when no deployment of this workbench is known)."""

    drone: str
    project_id: int | None
    revision: int | None
    pub_broker: dict[str, Any] | None
    sub_broker: dict[str, Any] | None


@router.get("/running-drones")
def running_drones(db: DbDep, _user: UserDep, state: StateDep) -> list[RunningDroneOut]:
    """The drones reporting lately, with the PubBroker and SubBroker endpoints
    of what they run: a new project starts from those (`make run` moves them
    with MODD_PORT)."""
    statuses = state.statuses
    out: list[RunningDroneOut] = []
    for name in sorted(statuses.drones() if statuses is not None else []):
        if statuses is None or statuses.latest(name) is None:
            continue
        record = last_acked(db, name)
        model = model_of(get_version(db, record.project_id, record.revision)) if record else {}
        ends = {p: (model.get(p) or {}).get("endpoint") for p in ("pubBroker", "subBroker")}
        out.append(
            RunningDroneOut(
                drone=name,
                project_id=record.project_id if record else None,
                revision=record.revision if record else None,
                pub_broker=ends["pubBroker"],
                sub_broker=ends["subBroker"],
            )
        )
    return out
