"""The checks that make a model's data a dataset scientists can use: every
unit a UDUNITS-2 unit, every CF standard name in the CF table with a unit that
converts to the name's, valid ranges in order, and a platform position.
Registered into ``validate.CHECKS``; each yields located diagnostics."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from .diagnostics import Diagnostic
from .numbers import to_fraction
from .position import platform_position
from .query import topic_name
from .standard_names import canonical_units, current_name
from .units import PAPER_UNITS, convertible, unit_problem

Doc = dict[str, Any]


def _variables(doc: Doc) -> Iterator[tuple[str, str, dict[str, Any]]]:
    """(pointer, topic, variable) of every measured variable."""
    drone = doc["drone"]["name"]
    for i, s in enumerate(doc["drone"]["sensors"]):
        for j, v in enumerate(s["variables"]):
            yield f"/drone/sensors/{i}/variables/{j}", topic_name(drone, s["name"], v["name"]), v


def units_are_udunits(doc: Doc) -> Iterator[Diagnostic]:
    for ptr, _topic, v in _variables(doc):
        unit = v["unit"]
        if not isinstance(unit, str):
            continue  # the schema error names it
        problem = unit_problem(unit)
        if problem is not None:
            hint = ""
            if unit.isupper() and "_" in unit:
                hint = f"; or one of the paper's names: {', '.join(PAPER_UNITS)}"
            yield Diagnostic(problem + hint, ptr + "/unit")


def standard_names_known(doc: Doc) -> Iterator[Diagnostic]:
    for ptr, _topic, v in _variables(doc):
        name = v.get("standardName")
        if not isinstance(name, str):
            continue
        canonical = canonical_units(name)
        if canonical is None:
            yield Diagnostic(
                f"{name!r} is not a CF standard name (CF standard name table)",
                ptr + "/standardName",
            )
            continue
        if (renamed := current_name(name)) is not None:
            yield Diagnostic(
                f"{name!r} is an alias of the CF standard name {renamed!r}",
                ptr + "/standardName",
                "warning",
            )
        if unit_problem(v["unit"]) is None and not convertible(v["unit"], canonical):
            yield Diagnostic(
                f"unit {v['unit']!r} does not convert to {canonical!r}, the unit "
                f"of the standard name {name!r}",
                ptr + "/unit",
            )


def valid_range_ordered(doc: Doc) -> Iterator[Diagnostic]:
    for ptr, _topic, v in _variables(doc):
        lo, hi = v.get("validMin"), v.get("validMax")
        if isinstance(lo, int | float) and isinstance(hi, int | float) and lo > hi:
            yield Diagnostic(f"validMin {lo:g} is above validMax {hi:g}", ptr + "/validMin")


#: What each position topic must convert to.
_POSITION_UNITS = {"latitude": "degree_north", "longitude": "degree_east", "altitude": "m"}


def no_position(doc: Doc) -> Diagnostic | None:
    """A warning when datasets of this model would have no position (``modd
    validate`` prints it; not a validation finding, so that models that never
    export, like the paper's scenarios, validate clean)."""
    if platform_position(doc) is not None:
        return None
    return Diagnostic(
        "no platform position: datasets (modd dataset) will have no latitude or "
        'longitude; declare Position { latitude = "..."; longitude = "..."; } '
        "in the Drone block, or map the autopilot's GLOBAL_POSITION_INT lat and "
        "lon",
        "/drone",
        "warning",
    )


def position_resolves(doc: Doc) -> Iterator[Diagnostic]:
    """The declared position names published topics in position units."""
    declared = doc["drone"].get("position")
    if declared is None:
        return
    units = {t: v["unit"] for _p, t, v in _variables(doc)}
    published = {t for p in doc["publishers"] for t in p["topics"]}
    for role, want in _POSITION_UNITS.items():
        topic = declared.get(role)
        ptr = f"/drone/position/{role}"
        if topic is None:
            continue
        if topic not in units:
            yield Diagnostic(f"unknown topic {topic!r}", ptr)
        elif not convertible(units[topic], want):
            yield Diagnostic(
                f"the {role} topic {topic!r} is in {units[topic]!r}, which does "
                f"not convert to {want!r}",
                ptr,
            )
        elif topic not in published:
            yield Diagnostic(
                f"no publisher publishes {topic!r}: datasets will have no {role}", ptr, "warning"
            )
    gap = declared.get("maxGapS")
    if isinstance(gap, str) and to_fraction(gap) <= 0:
        yield Diagnostic("maxGap must be greater than zero", "/drone/position/maxGapS")


CHECKS: tuple[Callable[[Doc], Iterator[Diagnostic]], ...] = (
    units_are_udunits,
    standard_names_known,
    valid_range_ordered,
    position_resolves,
)
