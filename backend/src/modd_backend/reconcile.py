"""Deploy records that match the drone. Every SubBroker's status
(``modd/<drone>/status``, once a second and at once on a CONFIG_ACK) names
the deployment it runs: project, revision and the nonce of the signed
request (docs/subbroker.md, "Status"). This module keeps the last status of
each drone and settles the records with it:

- a record whose nonce the drone runs is ``acked`` (also one that said
  ``failed`` because the acknowledgement came after the deploy's timeout);
- a record still ``pending`` that no process is waiting for (its backend
  stopped mid-deploy) is settled once its deploy can no longer be under way
  (the deploy timeout and the query margin have passed): ``acked`` when the
  drone runs it, else ``failed`` naming what the drone runs;
- when the drone has not reported for :data:`SILENT_S` after that, the record
  is ``failed`` ("interrupted"); it turns ``acked`` if the drone later reports it.

Several backends may share the store: each settles the same way, so their
updates agree. ``deployed-diff`` compares with what the drone reports.

>>> statuses = DroneStatuses()
>>> statuses.on_status("modd/usv/status", b'{"deployment": {"nonce": "n"}}')
>>> statuses.deployment("usv")["nonce"]
'n'
"""

from __future__ import annotations

import json
import logging
import threading
import time
from datetime import datetime, timedelta
from typing import Any

from modd_contracts.keys import match_status_key
from sqlalchemy import select
from sqlalchemy.orm import Session as Db

from .deployments import QUERY_MARGIN_S, in_flight
from .tables import Deployment, utcnow

log = logging.getLogger("modd_backend.reconcile")

#: A status older than this does not say what the drone runs now.
FRESH_S = 5.0
#: How long after a pending record's deadline a silent drone leaves it pending.
SILENT_S = 5.0
#: Status documents kept (drones), bounding memory.
MAX_DRONES = 4096


class DroneStatuses:
    """The last status of each drone, with when it came."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._last: dict[str, tuple[float, datetime, dict[str, Any]]] = {}

    def on_status(self, key: str, payload: bytes) -> None:
        """The hub's callback (a zenoh thread): parse, keep, never raise."""
        drone = match_status_key(key)
        if drone is None or len(payload) > 1 << 20:
            return
        try:
            doc = json.loads(payload)
        except (ValueError, UnicodeDecodeError, RecursionError):
            return
        if not isinstance(doc, dict):
            return
        with self._lock:
            if drone not in self._last and len(self._last) >= MAX_DRONES:
                return
            self._last[drone] = (time.monotonic(), utcnow(), doc)

    def drones(self) -> list[str]:
        with self._lock:
            return list(self._last)

    def latest(self, drone: str, after: datetime | None = None) -> dict[str, Any] | None:
        """The drone's status if it came within FRESH_S (and after ``after``)."""
        with self._lock:
            found = self._last.get(drone)
        if found is None or time.monotonic() - found[0] > FRESH_S:
            return None
        if after is not None and found[1] <= after:
            return None
        return found[2]

    def deployment(self, drone: str) -> dict[str, Any] | None:
        """What the drone reports it runs (the status' ``deployment``), if it
        reported lately."""
        status = self.latest(drone)
        found = status.get("deployment") if status is not None else None
        return found if isinstance(found, dict) else None


def _describe(meta: dict[str, Any] | None) -> str:
    if not meta or meta.get("source") == "configured":
        return "its configured model"
    return (
        f"revision {meta.get('revision')} of project {meta.get('project_id')} "
        f"(deployed by {meta.get('deployed_by')})"
    )


def _acked(record: Deployment, status: dict[str, Any], how: str) -> None:
    record.status = "acked"
    record.error = None
    record.ack_json = json.dumps(
        {
            "status": "ACKED",
            "reconciled": how,
            "config_id": status.get("config_id"),
            "epoch_ns": status.get("epoch_ns"),
            "deployment": status.get("deployment"),
        }
    )
    record.finished_at = record.finished_at or utcnow()


def reconcile(db: Db, statuses: DroneStatuses, timeout_s: float) -> list[int]:
    """Settle the records with what the drones report; the ids changed."""
    changed: list[int] = []
    for drone in statuses.drones():
        status = statuses.latest(drone)
        meta = statuses.deployment(drone)
        nonce = meta.get("nonce") if meta else None
        if status is None or not isinstance(nonce, str):
            continue
        # the drone runs this one: whatever its record says, it is acked
        for record in db.scalars(
            select(Deployment).where(
                Deployment.drone == drone, Deployment.nonce == nonce, Deployment.status != "acked"
            )
        ):
            how = "was pending" if record.status == "pending" else "acknowledged late"
            _acked(record, status, f"the drone reports it runs it ({how})")
            changed.append(record.id)
    busy = in_flight()
    now = utcnow()
    deadline = timedelta(seconds=timeout_s + QUERY_MARGIN_S)
    for record in db.scalars(select(Deployment).where(Deployment.status == "pending")):
        due = record.requested_at + deadline
        if record.id in busy or record.id in changed or now < due:
            continue
        status = statuses.latest(record.drone, after=due)
        if status is not None:
            record.error = (
                "interrupted before its answer (the backend stopped mid-deploy); "
                f"the drone runs {_describe(statuses.deployment(record.drone))}"
            )
        elif now >= due + timedelta(seconds=SILENT_S):
            record.error = (
                "interrupted before its answer (the backend stopped mid-deploy), "
                "and the drone's SubBroker does not report: unknown whether it "
                "runs it (the record turns acked if it reports it)"
            )
        else:
            continue
        record.status = "failed"
        record.finished_at = now
        changed.append(record.id)
    if changed:
        db.commit()
        log.info("deploy records settled with what the drones report: %s", changed)
    return changed
