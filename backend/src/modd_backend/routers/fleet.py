"""A project's drones (issue 44): a campaign's vehicles, or the project's one
drone; a deploy to several of them at once, each with its own
acknowledgement (and a rollback per drone: a deploy of an older revision to
that drone alone); a live subscription to one variable of every drone in one
step; what each drone reports now, for the fleet view.

Each drone gets its own model, expanded from the project's mission model
(modd_model.campaign): its deploy is the one-drone deploy (signed, acked,
recorded), sent to every drone at once (at most ``PARALLEL`` in flight)."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Annotated, Any

from fastapi import APIRouter, Depends
from modd_model import validate
from modd_model.campaign import channel_members, expand, vehicles
from pydantic import BaseModel, Field
from sqlalchemy import select

from ..deployments import record_json
from ..deps import DbDep, Heavy, StateDep, UserDep, require, zenoh_session_of
from ..errors import ApiError
from ..live import dynamic_request
from ..modelio import diagnostics_json
from ..roles import Role
from ..schemas import Id, InvalidModelOut
from ..tables import Deployment, ModelVersion
from ..versions import get_version, model_of
from .deploy import DeploymentOut, deploy_model
from .live import DynamicOut

router = APIRouter(prefix="/api/projects", tags=["fleet"])
Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", max_length=64)]

#: Deploys in flight at once (each waits for its drone's ack, up to the deploy timeout).
PARALLEL = 8


class DroneOut(BaseModel):
    """One drone of the project. ``status``: its last status document when it
    reported lately (link state, last data, instruments), else null;
    ``deployment``: this project's last deployment to it."""

    name: str
    description: str | None = None
    channel: str | None = None
    pub_broker: dict[str, Any]
    sub_broker: dict[str, Any]
    deployment: DeploymentOut | None = None
    status: dict[str, Any] | None = None


class FleetOut(BaseModel):
    campaign: str | None
    drones: list[DroneOut]
    channels: dict[str, list[str]]


class FleetDeployIn(BaseModel):
    revision: int | None = Field(
        default=None, ge=1, le=2**31 - 1, description="the head when absent"
    )
    drones: list[Name] | None = Field(
        default=None,
        min_length=1,
        max_length=100,
        description="every drone of the project when absent",
    )


class FleetSubscribeIn(BaseModel):
    """``variable``: ``sensor.variable`` of the mission model; each drone is
    asked for ``<drone>.sensor.variable``."""

    variable: str = Field(
        pattern=r"^[A-Za-z_][A-Za-z0-9_]*\.[A-Za-z_][A-Za-z0-9_]*$", max_length=129
    )
    period_s: str = Field(pattern=r"^[0-9]+(\.[0-9]+)?$", max_length=32)
    aggregation: str = Field(max_length=16)
    subscriber: Name | None = None
    drones: list[Name] | None = Field(default=None, min_length=1, max_length=100)


class FleetSubscriptionOut(DynamicOut):
    drone: str
    topic: str


def _description(model: dict[str, Any], name: str) -> str | None:
    for v in vehicles(model):
        if v.get("name") == name:
            return v.get("description")
    return (model.get("drone") or {}).get("description") if not vehicles(model) else None


@router.get(
    "/{project_id}/drones",
    responses={
        404: {"description": "no project or no model"},
        422: {"description": "the model is too broken to list its drones"},
    },
)
def list_drones(project_id: Id, db: DbDep, _user: UserDep, state: StateDep) -> FleetOut:
    """The project's drones as its head model expands them (a campaign's
    vehicles, or its one drone), with their last deployment and status."""
    model = model_of(get_version(db, project_id))
    channel_of = {v: c for c, members in channel_members(model).items() for v in members}
    out: list[DroneOut] = []
    for name, doc in _drones(model).items():
        last = db.scalar(
            select(Deployment)
            .where(Deployment.project_id == project_id, Deployment.drone == name)
            .order_by(Deployment.id.desc())
            .limit(1)
        )
        out.append(
            DroneOut(
                name=name,
                description=_description(model, name),
                channel=channel_of.get(name),
                pub_broker=doc["pubBroker"],
                sub_broker=doc["subBroker"],
                deployment=DeploymentOut.model_validate(record_json(last)) if last else None,
                status=state.statuses.latest(name) if state.statuses else None,
            )
        )
    campaign = model.get("campaign")
    return FleetOut(
        campaign=campaign.get("name") if isinstance(campaign, dict) else None,
        drones=out,
        channels=channel_members(model),
    )


#: What every drone's model needs before it is listed or deployed.
PARTS = ("drone", "pubBroker", "subBroker")


def _drones(model: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The model's drones; 422 when it is too broken to say (a revision with errors)."""
    try:
        drones = expand(model)
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ApiError(
            422, f"the model cannot be read as drones ({exc!r}): fix its errors"
        ) from exc
    if not all(isinstance(d.get(p), dict) for d in drones.values() for p in PARTS):
        raise ApiError(422, "the model has no PubBroker or SubBroker: fix its errors")
    return drones


def _chosen(model: dict[str, Any], asked: list[str] | None) -> dict[str, dict[str, Any]]:
    drones = _drones(model)
    if asked is None:
        return drones
    unknown = [d for d in asked if d not in drones]
    if unknown:
        raise ApiError(
            404, f"no drone {', '.join(unknown)} in this project (it has {', '.join(drones)})"
        )
    return {d: drones[d] for d in dict.fromkeys(asked)}


@router.post(
    "/{project_id}/fleet/deployments",
    status_code=201,
    dependencies=[Depends(require(Role.operator)), Heavy],
    responses={
        404: {"description": "no such project, revision or drone"},
        422: {"model": InvalidModelOut, "description": "the version is not valid"},
    },
)
def deploy_fleet(
    project_id: Id, body: FleetDeployIn, db: DbDep, user: UserDep, state: StateDep
) -> list[DeploymentOut]:
    """Deploy a revision to several drones at once, each its own model, and
    wait for every answer: one record per drone, acked or failed. A rollback
    of one drone is this with an older revision and that drone alone."""
    version = get_version(db, project_id, body.revision)
    model = model_of(version)
    if not version.valid:
        raise ApiError(
            422,
            f"revision {version.revision} has errors: fix them before deploying",
            diagnostics=diagnostics_json(validate(model)),
        )
    chosen = _chosen(model, body.drones)
    version_id = version.id

    def one(doc: dict[str, Any]) -> dict[str, Any]:
        with state.store.session() as own:
            row = own.get(ModelVersion, version_id)
            assert row is not None
            return record_json(deploy_model(state, own, row, doc, user.username))

    with ThreadPoolExecutor(max_workers=min(PARALLEL, len(chosen))) as pool:
        records = list(pool.map(one, chosen.values()))
    return [DeploymentOut.model_validate(r) for r in records]


@router.post(
    "/{project_id}/fleet/subscriptions",
    dependencies=[Depends(require(Role.scientist))],
    responses={
        404: {"description": "no project, no model or no such drone"},
        422: {"description": "the model is too broken to list its drones"},
    },
)
def subscribe_fleet(
    project_id: Id, body: FleetSubscribeIn, db: DbDep, user: UserDep, state: StateDep
) -> list[FleetSubscriptionOut]:
    """One live subscription (as ``POST /api/drones/{drone}/subscriptions``)
    to the same variable of every drone of the project, in one step: one
    answer per drone."""
    chosen = _chosen(model_of(get_version(db, project_id)), body.drones)
    base = body.model_dump(exclude_none=True, exclude={"variable", "drones"})

    def one(drone: str) -> FleetSubscriptionOut:
        topic = f"{drone}.{body.variable}"
        request = {"action": "subscribe", **base, "topic": topic, "owner": user.username}
        reply = dynamic_request(
            zenoh_session_of(state), drone, request, state.settings.subscribe_timeout_s
        )
        return FleetSubscriptionOut.model_validate({**reply, "drone": drone, "topic": topic})

    with ThreadPoolExecutor(max_workers=min(PARALLEL, len(chosen))) as pool:
        return list(pool.map(one, chosen))
