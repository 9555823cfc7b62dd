"""A deployed model applied to a running ``modd-mavlink``: the mapped variables
change in place, between two reads of the autopilot, with no reconnection; the
autopilot is asked for the new message rates (docs/mavlink.md, "Deploying").

Example::

    result = replan(bridge, plan_bridge(model), lambda name: Publisher(name, ingress))
    result["added"], result["removed"], result["changed"]
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .bridge import Bridge, Sink
from .guard import RateBound
from .mapping import BridgePlan, FieldMapping


def _topics(plan: BridgePlan) -> dict[str, tuple[str, FieldMapping]]:
    return {m.topic: (p.name, m) for p in plan.publishers for m in p.mappings}


def replan(bridge: Bridge, plan: BridgePlan, make_sink: Callable[[str], Sink]) -> dict[str, Any]:
    """Switches ``bridge`` to ``plan`` (call it from the bridge's own thread); what changed."""
    before, after = _topics(bridge.plan), _topics(plan)
    for pub in plan.publishers:
        if pub.name not in bridge.sinks:
            bridge.sinks[pub.name] = make_sink(pub.name)
        for m in pub.mappings:
            bridge.sinks[pub.name].declare(m.topic, m.type)
    bridge.plan = plan
    bridge.rate = RateBound(plan.intervals_us)
    ap = bridge.autopilot
    if plan.intervals_us != ap.intervals_us:
        ap.intervals_us = dict(plan.intervals_us)
        ap.ask_all()
    result: dict[str, Any] = {
        "ok": True,
        "added": sorted(after.keys() - before.keys()),
        "removed": sorted(before.keys() - after.keys()),
        "changed": sorted(t for t in after.keys() & before.keys() if after[t] != before[t]),
        "autopilot": "lost" if ap.lost else "heard" if ap.known else "not heard yet",
        "warnings": plan.warnings,
    }
    bridge.log(
        f"deploy: {len(result['added'])} topics added, {len(result['removed'])} removed, "
        f"{len(result['changed'])} changed"
    )
    return result
