"""The ``modd/<drone>/backfill`` queryable (docs/subbroker.md, "Backfill"):
JSON requests to start a backfill, follow its progress, or cancel it.

``{"op": "start", "subscriber": S, "gaps": true}`` fills every window of S's
subscriptions the link missed since the mission began (every config that ran
since, across SubBroker and PubBroker restarts and redeploys);
``{"op": "start", "subscriber": S, "from_ns": T0, "to_ns": T1}`` the windows
of ``[T0, T1)`` not delivered yet. ``"rate_bps"`` caps the pace (default: the
spare budget of the link, its ``rateBps`` minus the plan's live bytes/s).
The job is queued fairly among every user's jobs (``"owner"``) and its
progress document says what it waits for (``reason``).
``{"op": "progress", "id": N}``, ``{"op": "cancel", "id": N}`` and
``{"op": "cap", "id": N, "rate_bps": R}`` answer the job's progress document
(``status`` RUNNING, DONE, CANCELLED or FAILED). ``"owner"`` (set by the
backend to the asking user) must own a dynamic subscription to start its
backfill.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .backfill import BackfillManager, Job
from .request import MAX_SMALL_BYTES, read_request

if TYPE_CHECKING:
    from .running import Running

MAX_RATE_BPS = 1_000_000_000


def spare_budget(running: Running) -> int:
    """The link's bytes/s minus the plan's live bytes/s (0: no budget known)."""
    budget = running.plan.budget
    if budget is None or budget.settings.rate_bps is None:
        return 0
    return max(1, int(budget.settings.rate_bps - budget.drone_to_base))


def _int(request: dict[str, Any], name: str) -> int | None:
    v = request.get(name)
    if v is None:
        return None
    if not isinstance(v, int) or isinstance(v, bool) or v < 0:
        raise ValueError(f"{name} must be a non-negative integer")
    return v


def handle(
    payload: bytes,
    manager: BackfillManager,
    running: Callable[[], Running | None],
    covered_until: Callable[[Running], int],
    owner_of: Callable[[str], str | None] = lambda _name: None,
) -> dict[str, Any]:
    request, problem = read_request(payload, MAX_SMALL_BYTES)
    if request is None:
        return {"status": "ERROR", "reason": problem}
    op = request.get("op", "start")
    try:
        if op in ("progress", "cancel", "cap"):
            job_id = _int(request, "id") or 0
            if op == "cap":
                rate = _int(request, "rate_bps")
                if rate is None or not 1 <= rate <= MAX_RATE_BPS:
                    raise ValueError(f"rate_bps must be in 1..{MAX_RATE_BPS}")
                job = manager.cap(job_id, rate)
            else:
                job = manager.job(job_id) if op == "progress" else manager.cancel(job_id)
            if job is None:
                return {"status": "UNKNOWN", "reason": f"no backfill {job_id}"}
            return manager.progress(job)
        if op != "start":
            return {
                "status": "ERROR",
                "reason": f"unknown op {str(op)[:32]!r} (start, progress, cancel, cap)",
            }
        owner = owner_of(str(request.get("subscriber")))
        if owner is not None and request.get("owner") not in (None, owner):
            return {
                "status": "UNAUTHORISED",
                "reason": "a dynamic subscription is backfilled for its owner only",
            }
        return _start(request, manager, running(), covered_until)
    except ValueError as exc:
        return {"status": "ERROR", "reason": str(exc)}


def _start(
    request: dict[str, Any],
    manager: BackfillManager,
    running: Running | None,
    covered_until: Callable[[Running], int],
) -> dict[str, Any]:
    if running is None:
        return {"status": "ERROR", "reason": "no config runs: nothing to backfill"}
    subscriber = request.get("subscriber")
    if not isinstance(subscriber, str) or not manager.knows(running, subscriber):
        return {
            "status": "ERROR",
            "reason": f"no subscriber {subscriber!r} in the plans of this mission",
        }
    until = covered_until(running)
    began = manager.mission_start(running)
    if request.get("gaps"):
        from_ns, to_ns = began, until
    else:
        f, t = _int(request, "from_ns"), _int(request, "to_ns")
        if f is None or t is None:
            raise ValueError("give gaps: true, or from_ns and to_ns")
        if t <= f:
            raise ValueError("to_ns must be after from_ns")
        from_ns, to_ns = max(f, began), min(t, until)
    rate = _int(request, "rate_bps")
    if rate is not None and not 1 <= rate <= MAX_RATE_BPS:
        raise ValueError(f"rate_bps must be in 1..{MAX_RATE_BPS}")
    spare = spare_budget(running)
    pace = min(rate, spare) if rate and spare else (rate or spare)
    runs = manager.gaps(running, subscriber, from_ns, to_ns) if to_ns > from_ns else []
    owner = request.get("owner")
    job: Job = manager.start(subscriber, runs, pace, owner if isinstance(owner, str) else "")
    out = manager.progress(job)
    out["from_ns"], out["to_ns"] = from_ns, to_ns
    return out
