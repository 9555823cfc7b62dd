"""Model → what ``modd-sensors`` reads: for each ``nmea``, ``ascii`` or
``modbus`` sensor, its device and, for each published variable, where the
value comes from, the publisher that carries its topic and the value's
``raw * scale + offset``. Modbus registers are polled at the fastest period
of the publishers carrying the sensor's topics.

Example::

    plans = plan_sensors(model)
    plans[0].device.path, [m.topic for m in plans[0].mappings]
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from modd_model.instruments import INSTRUMENT_KINDS
from modd_model.numbers import to_fraction
from modd_model.query import DEFAULT_VALUE_TYPE, topic_name

from .ascii import Column, Key, LineFormat, Where
from .condition import Condition
from .lines import LINE_ENDS, TERMINATORS


@dataclass(frozen=True)
class Device:
    path: str
    baud: int = 9600
    parity: str = "none"  # none | even | odd
    stop_bits: int = 1


@dataclass(frozen=True)
class Register:
    unit: int
    table: str  # holding | input
    address: int
    type: str  # int16 | uint16 | int32 | uint32 | float32
    order: str  # big | little (word order)


@dataclass(frozen=True)
class Mapping:
    """One variable: its topic, the publisher that carries it, where its raw value is."""

    topic: str
    type: str
    publisher: str
    where: tuple[str, str] | Where | Register  # nmea: (sentence, field)
    scale: float = 1.0
    offset: float = 0.0
    condition: Condition | None = None  # read only where another field compares so (where)

    def value(self, raw: float) -> float:
        return raw * self.scale + self.offset


@dataclass(frozen=True)
class SensorPlan:
    name: str
    kind: str  # nmea | ascii | modbus
    device: Device
    mappings: tuple[Mapping, ...]
    instrument_clock: bool = False  # nmea: stamp with the sentence's own UTC (clock.py)
    checksum_required: bool = True  # nmea: false with `checksum = optional`
    fix: str = "gnss"  # nmea: the fixes accepted (validity.FIX_CLASSES)
    line: LineFormat = field(default_factory=LineFormat)
    terminator: bytes = b"\n"
    start_command: str | None = None
    line_end: bytes = b"\r\n"  # ends the start command
    poll_s: float = 1.0  # modbus


def _where(kind: str, var: dict[str, Any]) -> tuple[str, str] | Where | Register:
    src = var[kind]
    if kind == "nmea":
        return (src["sentence"], src["field"])
    if kind == "ascii":
        return Column(src["column"]) if "column" in src else Key(src["key"])
    return Register(
        src.get("unit", 1),
        src.get("table", "holding"),
        src["register"],
        src.get("type", "uint16"),
        src.get("wordOrder", "big"),
    )


def _condition(kind: str, src: dict[str, Any]) -> Condition | None:
    cond = src.get("where")
    if cond is None:
        return None
    place: str | Where = cond.get("field", "")
    if kind == "ascii":
        place = Column(cond["column"]) if "column" in cond else Key(cond["key"])
    return Condition(place, cond.get("op", "="), cond["value"])


def _line_format(sensor: dict[str, Any]) -> LineFormat:
    line = sensor.get("line", {})
    pattern = line.get("pattern")
    return LineFormat(line.get("separator", ","), re.compile(pattern) if pattern else None)


def _sensor_plan(
    drone: str, sensor: dict[str, Any], carrier: dict[str, tuple[str, float]]
) -> SensorPlan | None:
    kind = sensor["kind"]
    mappings, periods = [], []
    for var in sensor["variables"]:
        topic = topic_name(drone, sensor["name"], var["name"])
        if topic not in carrier or kind not in var:
            continue
        publisher, period = carrier[topic]
        periods.append(period)
        src = var[kind]
        mappings.append(
            Mapping(
                topic,
                var.get("type", DEFAULT_VALUE_TYPE),
                publisher,
                _where(kind, var),
                float(src.get("scale", 1)),
                float(src.get("offset", 0)),
                _condition(kind, src),
            )
        )
    if not mappings:
        return None
    dev = sensor["device"]
    line = sensor.get("line", {})
    terminator = line.get("terminator", "crlf")
    return SensorPlan(
        name=sensor["name"],
        kind=kind,
        device=Device(
            dev["path"], dev.get("baud", 9600), dev.get("parity", "none"), dev.get("stopBits", 1)
        ),
        mappings=tuple(mappings),
        instrument_clock=sensor.get("clock") == "instrument",
        checksum_required=sensor.get("checksum", "required") == "required",
        fix=sensor.get("fix", "gnss"),
        line=_line_format(sensor),
        terminator=TERMINATORS[terminator],
        start_command=line.get("startCommand"),
        line_end=LINE_ENDS[terminator],
        poll_s=min(periods),
    )


def plan_sensors(model: dict[str, Any]) -> list[SensorPlan]:
    """The model's instrument sensors with at least one published variable (a
    valid model: ``modd_model.validate`` checks the mappings)."""
    carrier: dict[str, tuple[str, float]] = {}
    for pub in model.get("publishers", []):
        for t in pub["topics"]:
            carrier.setdefault(t, (pub["name"], float(to_fraction(pub["periodS"]))))
    drone = model["drone"]["name"]
    plans = [
        _sensor_plan(drone, s, carrier)
        for s in model["drone"]["sensors"]
        if s.get("kind") in INSTRUMENT_KINDS
    ]
    return [p for p in plans if p is not None]


def has_instrument_sensors(model: dict[str, Any]) -> bool:
    return any(s.get("kind") in INSTRUMENT_KINDS for s in model["drone"]["sensors"])
