"""Model → what the bridge does: which MAVLink message field feeds which topic
(``value = raw * scale + offset``, typed per the topic), which model publisher
publishes each topic, and the interval to ask the autopilot for each message
(the fastest period among the publishers that carry that message's topics).

Example::

    plan = plan_bridge(model)
    plan.intervals_us["GLOBAL_POSITION_INT"]        # 200000 for a 0.2 s publisher
    for publisher, m in plan.by_message["ATTITUDE"]:
        value = m.convert(msg.roll)                  # None if it does not fit the topic type
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from modd_model.numbers import to_fraction
from modd_model.query import DEFAULT_VALUE_TYPE, topic_name

from .dialect import message_class

Number = float | int | bool
_INT64 = 2**63


@dataclass(frozen=True)
class FieldMapping:
    """One measured variable of a mavlink sensor: a topic read from a message field."""

    topic: str
    type: str  # float32 | float64 | int | bool
    message: str
    field: str
    scale: float = 1.0
    offset: float = 0.0

    def convert(self, raw: Any) -> Number | None:
        """The topic's value for a raw field value; None when it does not fit the type
        (a NaN or an out-of-range number for an int topic, a non-number)."""
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            return None
        value = raw * self.scale + self.offset
        if self.type in ("float32", "float64"):
            return float(value)
        if not math.isfinite(value):
            return None
        if self.type == "bool":
            return value != 0
        rounded = round(value)
        return rounded if -_INT64 <= rounded < _INT64 else None


@dataclass(frozen=True)
class PublisherPlan:
    """A model publisher as the bridge runs it: its name, period and mavlink topics."""

    name: str
    period_s: float
    mappings: tuple[FieldMapping, ...]


@dataclass
class BridgePlan:
    publishers: list[PublisherPlan] = field(default_factory=list)
    #: message name → (publisher name, mapping) for every topic read from it
    by_message: dict[str, list[tuple[str, FieldMapping]]] = field(default_factory=dict)
    #: message name → the interval to ask for, in microseconds
    intervals_us: dict[str, int] = field(default_factory=dict)
    #: things worth telling the operator (topics no publisher carries, ...)
    warnings: list[str] = field(default_factory=list)


class MappingError(ValueError):
    """The model maps a variable to a message or field the dialect does not have;
    each entry of ``problems`` starts with the JSON pointer of the offending source."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems))
        self.problems = problems


def _check_source(src: dict[str, Any], pointer: str) -> str | None:
    cls = message_class(src["message"])
    if cls is None:
        return f"{pointer}/message: unknown MAVLink message {src['message']}"
    if src["field"] not in cls.fieldnames:
        return (
            f"{pointer}/field: {src['message']} has no field {src['field']} "
            f"(fields: {', '.join(cls.fieldnames)})"
        )
    i = cls.fieldnames.index(src["field"])
    if cls.array_lengths[i] or cls.fieldtypes[i] == "char":
        return f"{pointer}/field: {src['message']}.{src['field']} is not a single number"
    return None


def mavlink_mappings(model: dict[str, Any]) -> dict[str, FieldMapping]:
    """Every topic of the model's mavlink sensors, by topic name; raises MappingError
    naming the JSON pointer of each source the dialect cannot read."""
    drone = model["drone"]["name"]
    out: dict[str, FieldMapping] = {}
    problems: list[str] = []
    for i, sensor in enumerate(model["drone"]["sensors"]):
        if sensor.get("kind", "generic") != "mavlink":
            continue
        for j, var in enumerate(sensor["variables"]):
            pointer = f"/drone/sensors/{i}/variables/{j}/source"
            src = var.get("source")
            if src is None:
                problems.append(f"{pointer}: a variable of a mavlink sensor needs a source")
                continue
            if (problem := _check_source(src, pointer)) is not None:
                problems.append(problem)
                continue
            name = topic_name(drone, sensor["name"], var["name"])
            out[name] = FieldMapping(
                topic=name,
                type=var.get("type", DEFAULT_VALUE_TYPE),
                message=src["message"],
                field=src["field"],
                scale=float(src.get("scale", 1)),
                offset=float(src.get("offset", 0)),
            )
    if problems:
        raise MappingError(problems)
    return out


def plan_bridge(model: dict[str, Any]) -> BridgePlan:
    """What the bridge publishes and which message rates it asks for."""
    mappings = mavlink_mappings(model)
    plan = BridgePlan()
    carried: set[str] = set()
    for pub in model.get("publishers", []):
        mine = tuple(mappings[t] for t in pub["topics"] if t in mappings and t not in carried)
        if not mine:
            continue
        carried.update(m.topic for m in mine)
        period = float(to_fraction(pub["periodS"]))
        plan.publishers.append(PublisherPlan(pub["name"], period, mine))
        for m in mine:
            plan.by_message.setdefault(m.message, []).append((pub["name"], m))
            interval = max(1, round(period * 1e6))
            plan.intervals_us[m.message] = min(plan.intervals_us.get(m.message, interval), interval)
    for name in mappings.keys() - carried:
        plan.warnings.append(
            f"topic {name} is read over MAVLink but no publisher carries it: not published"
        )
    return plan
