"""Checks of declared resolutions (docs/dsl.md, "Resolution"): a variable's and a
subscription's ``resolution`` is a positive finite number, a subscription's is
at least its variable's (coarser still), and the variable's valid range in
steps fits the link's integer coding (docs/protocol.md, "Quantised values").

>>> doc = {"drone": {"name": "d", "sensors": [{"name": "s", "variables": [
...     {"name": "v", "unit": "m", "resolution": 1e-12, "validMax": 1e6}]}]},
...     "subscribers": [{"name": "a", "topic": "d.s.v", "resolution": 1e-13}]}
>>> [d.message[:40] for d in CHECKS[0](doc)]
['resolution 1e-12 over the valid range ne', "subscriber 'a': resolution 1e-13 is fine"]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

from modd_contracts.quantised import MAX_STEPS_BITS

from .diagnostics import Diagnostic
from .query import topic_name

#: The largest step count the link codes exactly (docs/protocol.md, "Quantised values").
MAX_STEPS = 1 << MAX_STEPS_BITS


def _bad(value: Any) -> bool:
    return (
        not isinstance(value, int | float)
        or isinstance(value, bool)
        or not math.isfinite(value)
        or value <= 0
    )


def _variable(ptr: str, v: dict[str, Any]) -> Iterator[Diagnostic]:
    r = v.get("resolution")
    if r is None:
        return
    if _bad(r):
        yield Diagnostic(f"resolution {r!r} is not a positive number", ptr + "/resolution")
        return
    bounds = [b for b in (v.get("validMin"), v.get("validMax")) if isinstance(b, int | float)]
    widest = max((abs(b) for b in bounds if math.isfinite(b)), default=0.0)
    if widest / r > MAX_STEPS:
        yield Diagnostic(
            f"resolution {r:g} over the valid range needs {widest / r:.3g} steps: "
            f"more than the link's integer coding holds (2^53); declare a coarser "
            f"resolution or a narrower validMin/validMax",
            ptr + "/resolution",
        )


def resolutions_valid(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    drone = doc["drone"]["name"]
    declared: dict[str, dict[str, Any]] = {}
    for i, s in enumerate(doc["drone"]["sensors"]):
        for j, v in enumerate(s["variables"]):
            declared[topic_name(drone, s["name"], v["name"])] = v
            yield from _variable(f"/drone/sensors/{i}/variables/{j}", v)
    for i, sub in enumerate(doc["subscribers"]):
        r = sub.get("resolution")
        if r is None:
            continue
        ptr = f"/subscribers/{i}/resolution"
        if _bad(r):
            yield Diagnostic(
                f"subscriber {sub['name']!r}: resolution {r!r} is not a positive number", ptr
            )
            continue
        finest = declared.get(sub.get("topic", ""), {}).get("resolution")
        if not _bad(finest) and r < finest:
            yield Diagnostic(
                f"subscriber {sub['name']!r}: resolution {r:g} is finer than its "
                f"variable's ({finest:g}); a subscription may only be coarser",
                ptr,
            )


CHECKS: tuple[Callable[[dict[str, Any]], Iterator[Diagnostic]], ...] = (resolutions_valid,)
