"""Dynamic subscriptions (paper §III-B2) behind ``modd/<drone>/subscribe``.

A request (JSON) asks for a topic, a period and an aggregation while the
mission runs. The schedule does not change: the request is accepted when the
stream is sent or derivable from what is sent (:func:`modd_plan.check_dynamic`),
and its values start with the next complete window. Replies are JSON objects
with a ``status``; docs/subbroker.md lists them.

Only the backend may ask (zenoh access control, docs/security.md); it names
the user it asks for in ``owner``. Each owner may hold at most
``per_owner`` subscriptions (``total`` in all), and lists and cancels only
its own.

>>> reg = DynamicSubscriptions("usv")
>>> reg.handle({"action": "cancel", "subscriber": "dyn_x"}, None)["status"]
'ERROR'
"""

from __future__ import annotations

import logging
import secrets
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from modd_plan import Accepted, Plan, check_dynamic
from modd_plan.streams import Source, StreamKey

from .keys import check_name, sub_key

log = logging.getLogger("modd.subbroker")


class Router(Protocol):
    """What the running state offers: the plan, and routes in the fan-out."""

    plan: Plan

    def route(self, stream: StreamKey, sources: tuple[Source, ...], subscriber: str) -> None: ...

    def unroute(self, subscriber: str) -> bool: ...


#: Dynamic subscriptions one owner may hold, and all owners together.
PER_OWNER = 32
TOTAL = 256
MAX_FIELD = 256  # characters of a topic, period or aggregation
MAX_NAME = 64  # characters of a dynamic subscriber's name (the status lists them all)


@dataclass(frozen=True)
class Dynamic:
    """One accepted dynamic subscription."""

    name: str
    topic: str
    period_s: str
    aggregation: str
    owner: str = ""


def _owner(request: Mapping[str, Any]) -> str | None:
    owner = request.get("owner", "")
    if not isinstance(owner, str) or len(owner) > MAX_FIELD:
        return None
    return owner


def _period_text(value: Any) -> str | None:
    if isinstance(value, str):
        return value
    if isinstance(value, int | float) and not isinstance(value, bool):
        return repr(value)
    return None


class DynamicSubscriptions:
    """The registry of dynamic subscriptions of one drone."""

    def __init__(
        self,
        drone: str,
        reserved: Callable[[], set[str]] = set,
        per_owner: int = PER_OWNER,
        total: int = TOTAL,
    ) -> None:
        self._drone = drone
        self._per_owner = per_owner
        self._total = total
        self._reserved = reserved  # the model's subscriber names
        self._subs: dict[str, Dynamic] = {}
        self._lock = threading.Lock()
        #: called with every subscription after each change (the state directory)
        self.persist: Callable[[list[dict[str, str]]], None] | None = None

    def restore(self, saved: list[dict[str, str]]) -> None:
        """Take back subscriptions kept by an earlier run (their owner and
        the quotas as when they were made); routed by the next :meth:`reroute`."""
        with self._lock:
            for d in saved[: self._total]:
                name = d["name"]
                try:
                    check_name("subscriber", name)
                except ValueError:
                    continue
                if len(name) <= MAX_NAME:
                    self._subs[name] = Dynamic(
                        name, d["topic"], d["period_s"], d["aggregation"], d["owner"]
                    )

    def _changed(self) -> None:
        if self.persist is None:
            return
        with self._lock:
            subs = [vars(d).copy() for d in self._subs.values()]
        try:
            self.persist(subs)
        except OSError as exc:  # the subscription still works in this run
            log.error("cannot keep the dynamic subscriptions: %s", exc)

    def names(self) -> list[str]:
        with self._lock:
            return sorted(self._subs)

    def owner_of(self, name: str) -> str | None:
        """The owner of a dynamic subscription (None: not a dynamic one)."""
        with self._lock:
            d = self._subs.get(name)
            return d.owner if d is not None else None

    def handle(self, request: Mapping[str, Any], running: Router | None) -> dict[str, Any]:
        """Serve one request; never raises for bad input."""
        action = request.get("action", "subscribe")
        owner = _owner(request)
        if owner is None:
            return {"status": "ERROR", "reason": f"owner: a string of at most {MAX_FIELD}"}
        if action == "subscribe":
            return self.subscribe(request, running)
        if action == "cancel":
            return self.cancel(str(request.get("subscriber", ""))[:MAX_FIELD], running, owner)
        if action == "list":
            with self._lock:
                mine = [vars(d) for d in self._subs.values() if d.owner == owner]
            return {"status": "OK", "subscriptions": mine}
        return {"status": "ERROR", "reason": f"unknown action {str(action)[:MAX_FIELD]!r}"}

    def subscribe(self, request: Mapping[str, Any], running: Router | None) -> dict[str, Any]:
        topic, agg = request.get("topic"), request.get("aggregation")
        period = _period_text(request.get("period_s"))
        if not isinstance(topic, str) or not isinstance(agg, str) or period is None:
            return {"status": "ERROR", "reason": "expected topic, period_s and aggregation"}
        if max(len(topic), len(agg), len(period)) > MAX_FIELD:
            return {
                "status": "ERROR",
                "reason": f"topic, period_s and aggregation: at most {MAX_FIELD} characters",
            }
        owner = _owner(request) or ""
        if running is None:
            return {"status": "NOT_AVAILABLE", "reason": "no plan is running on the link yet"}
        verdict = check_dynamic(running.plan, topic, period, agg)
        if not isinstance(verdict, Accepted):
            return {"status": "NOT_AVAILABLE", "reason": verdict.reason}
        name = request.get("subscriber") or f"dyn_{secrets.token_hex(4)}"
        if not isinstance(name, str):
            return {"status": "ERROR", "reason": "subscriber: expected a name"}
        if len(name) > MAX_NAME:
            return {
                "status": "ERROR",
                "reason": f"subscriber name of {len(name)} characters: at most {MAX_NAME}",
            }
        try:
            check_name("subscriber", name)
        except ValueError as exc:
            return {"status": "ERROR", "reason": str(exc)}
        with self._lock:
            if name in self._subs or name in self._reserved():
                return {"status": "ERROR", "reason": f"subscriber {name!r} already exists"}
            held = sum(1 for d in self._subs.values() if d.owner == owner)
            if held >= self._per_owner or len(self._subs) >= self._total:
                limit = (
                    f"{self._per_owner} per owner"
                    if held >= self._per_owner
                    else f"{self._total} in all"
                )
                return {
                    "status": "QUOTA",
                    "reason": f"too many dynamic subscriptions ({limit}); cancel one first",
                }
            self._subs[name] = Dynamic(name, topic, period, agg, owner)
        target = StreamKey.parse(verdict.stream)
        running.route(target, verdict.sources, name)
        self._changed()
        return {
            "status": "ACCEPTED",
            "subscriber": name,
            "key": sub_key(self._drone, name),
            "stream": verdict.stream,
            "derived_from": verdict.derived_from,
            "factor": verdict.factor,
        }

    def cancel(self, name: str, running: Router | None, owner: str = "") -> dict[str, Any]:
        with self._lock:
            found = self._subs.get(name)
            if found is not None and found.owner == owner:
                del self._subs[name]
            else:
                found = None  # another owner's is answered as absent: no probing of names
        if found is None:
            return {"status": "ERROR", "reason": f"no dynamic subscription named {name!r}"}
        if running is not None:
            running.unroute(name)
        self._changed()
        return {"status": "CANCELLED", "subscriber": name}

    def reroute(self, running: Router) -> list[tuple[str, str]]:
        """Route every dynamic subscription in a new plan (after a deploy);
        drop and return ``(name, reason)`` for those it cannot serve."""
        dropped: list[tuple[str, str]] = []
        with self._lock:
            subs = list(self._subs.values())
        for d in subs:
            verdict = check_dynamic(running.plan, d.topic, d.period_s, d.aggregation)
            if isinstance(verdict, Accepted):
                running.route(StreamKey.parse(verdict.stream), verdict.sources, d.name)
            else:
                with self._lock:
                    self._subs.pop(d.name, None)
                dropped.append((d.name, verdict.reason))
        if dropped:
            self._changed()
        return dropped
