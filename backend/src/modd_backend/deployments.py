"""Deploying a model version to a drone: the zenoh query to the SubBroker's
``modd/<drone>/deploy`` (docs/subbroker.md), and the record of how it ended.

The SubBroker replies ``{"status": "ACKED", ...}`` only after the PubBroker's
CONFIG_ACK; any other status, an error reply, a timeout or no reply at all is
a failure, recorded with its reason.

Every request is signed (modd_model.signing) with the deploy key shared with
the SubBroker, over the model, the revision, who deployed and a fresh nonce:
the SubBroker applies nothing else (docs/security.md, "Signed deploys").

The record is written ``pending`` with the request's nonce before the query
goes out; the drone's status names the nonce of what it runs, so a record
left pending by a backend that stopped mid-deploy is settled against what the
drone runs (:mod:`.reconcile`)."""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

from modd_contracts.keys import deploy_key
from modd_model.signing import sign_request
from sqlalchemy import select
from sqlalchemy.orm import Session as Db

from .tables import Deployment, ModelVersion, utcnow
from .zenoh_session import ZenohSession, read_secret

#: Extra seconds the backend waits beyond the SubBroker's own deploy timeout: 2 s, and
#: the 2 s the SubBroker may wait after the ack for the on-board processes' answers
#: (modd.onboard.RESULT_WAIT_S).
QUERY_MARGIN_S = 4.0

#: Deployment ids whose query this process is waiting for (reconcile skips them).
_in_flight: set[int] = set()
_in_flight_lock = threading.Lock()


def in_flight() -> set[int]:
    with _in_flight_lock:
        return set(_in_flight)


def signing_key(path: Path | None) -> bytes | None:
    """The deploy key (the SubBroker's ``deploy.key``), or None when not
    configured: the SubBroker then refuses the deploy, UNAUTHORISED."""
    return read_secret(path, "deploy key").encode() if path is not None else None


def deploy(
    db: Db,
    zenoh_session: ZenohSession,
    version: ModelVersion,
    model: dict[str, Any],
    user: str,
    timeout_s: float,
    key: bytes | None = None,
) -> Deployment:
    """Send ``model`` to its drone's SubBroker and record the outcome."""
    drone = str(model["drone"]["name"])
    body: dict[str, Any] = {
        "model": model,
        "timeout_s": timeout_s,
        "revision": version.revision,
        "project_id": version.project_id,
        "deployed_by": user,
    }
    if key is not None:
        body = sign_request(key, body)
    record = Deployment(
        project_id=version.project_id,
        revision=version.revision,
        drone=drone,
        requested_by=user,
        status="pending",
        nonce=body.get("nonce"),
    )
    db.add(record)
    db.commit()
    request = json.dumps(body).encode()
    with _in_flight_lock:
        _in_flight.add(record.id)
    try:
        result = zenoh_session.query(deploy_key(drone), request, timeout_s + QUERY_MARGIN_S)
    finally:
        with _in_flight_lock:
            _in_flight.discard(record.id)
    reply = result.json() if result.ok else None
    if isinstance(reply, dict) and reply.get("status") == "ACKED":
        record.status = "acked"
        record.ack_json = json.dumps(reply)
    else:
        record.status = "failed"
        record.error = _reason(result.error, reply)
        if isinstance(reply, dict):
            record.ack_json = json.dumps(reply)
    record.finished_at = utcnow()
    db.commit()
    return record


def _reason(error: str | None, reply: Any) -> str:
    if error is not None:
        return error
    if isinstance(reply, dict):
        status = reply.get("status", "no status")
        return f"{status}: {reply.get('reason', 'no reason given')}"
    return "the SubBroker's reply is not a JSON object"


def record_json(d: Deployment) -> dict[str, Any]:
    return {
        "id": d.id,
        "project_id": d.project_id,
        "revision": d.revision,
        "drone": d.drone,
        "requested_by": d.requested_by,
        "requested_at": d.requested_at,
        "finished_at": d.finished_at,
        "status": d.status,
        "reply": json.loads(d.ack_json) if d.ack_json else None,
        "error": d.error,
    }


def last_acked(db: Db, drone: str) -> Deployment | None:
    """What runs on ``drone``: its latest acknowledged deployment, any project."""
    return db.scalar(
        select(Deployment)
        .where(Deployment.drone == drone, Deployment.status == "acked")
        .order_by(Deployment.id.desc())
        .limit(1)
    )
