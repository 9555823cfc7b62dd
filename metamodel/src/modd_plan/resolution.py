"""The resolution each sent stream goes with (docs/planning.md, "Declared
resolution"): the finest of what the subscriptions it serves need, directly or
through the streams derived from it; None (unquantised) as soon as one of them
needs full precision. A subscription needs its own ``resolution``, else its
variable's. A SUM source of k windows is sent k times finer, so that the sum of
k errors of half a step stays within half of the subscriber's step (the other
derivations, MIN, MAX, an AVERAGE of AVERAGEs, keep the error of their sources).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from modd_model.query import topic_name

from .streams import PlannedStream


def needed(model: Mapping[str, Any]) -> dict[str, float | None]:
    """Each subscriber's resolution: its own, else its variable's, else None."""
    drone = model["drone"]["name"]
    declared = {topic_name(drone, s["name"], v["name"]): v.get("resolution")
                for s in model["drone"]["sensors"] for v in s["variables"]}
    return {sub["name"]: sub.get("resolution", declared.get(sub["topic"]))
            for sub in model.get("subscribers", [])}


def stream_resolutions(model: Mapping[str, Any], sent: Sequence[PlannedStream],
                       streams: Sequence[PlannedStream]) -> list[float | None]:
    """One resolution per sent stream, in ``sent``'s order."""
    need = needed(model)
    # by identity, as plan._budget: a derived stream's sources hold its source's key
    asks: dict[int, list[float | None]] = {id(s.stream): [need.get(n) for n in s.subscribers]
                                          for s in sent}
    for s in streams:
        if s.id is not None:
            continue
        for src in s.sources:
            into = asks.get(id(src.stream))
            if into is None:
                continue
            divide = src.factor if src.stream.aggregation == "SUM" else 1
            into += [None if need.get(n) is None else need[n] / divide  # type: ignore[operator]
                     for n in s.subscribers]
    return [None if not asks[id(s.stream)] or None in asks[id(s.stream)]
            else min(r for r in asks[id(s.stream)] if r is not None) for s in sent]
