"""What a dataset holds, read from the model: the variables (topics) to
export with their CF metadata, the position topics, the time range.

>>> from modd_model import load_model
>>> p = plan_export(load_model("metamodel/examples/demo.modd"), None)  # doctest: +SKIP
>>> p.variables["usv.ctd.water_temperature"].unit, p.variables[...].standard_name  # doctest: +SKIP
('degC', 'sea_water_temperature')
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from typing import Any

from modd_model.position import PlatformPosition, platform_position
from modd_model.query import DEFAULT_VALUE_TYPE
from modd_model.units import convertible, udunits

from .metadata import Metadata


class PlanError(ValueError):
    """A request the model cannot answer (an unknown topic, no position for a track)."""


@dataclass(frozen=True)
class Variable:
    """One exported topic and its CF metadata."""

    topic: str
    name: str  # <sensor>_<variable>: a NetCDF/CSV column name
    unit: str  # UDUNITS-2, ASCII
    value_type: str
    standard_name: str | None
    long_name: str
    valid_min: float | None
    valid_max: float | None
    temperature: bool = False  # a temperature on a scale (CF units_metadata)
    cell_methods: str | None = None  # a received window's aggregation (CF §7.3)
    sensor: str | None = None  # the model's sensor (the NetCDF instrument)
    #: The sensor declares ``clock = instrument``: the archive's publish time is the
    #: instrument's (the log time stays the PubBroker's receive time).
    instrument_clock: bool = False


@dataclass(frozen=True)
class ExportPlan:
    drone: str
    description: str
    variables: dict[str, Variable]  # by topic, in the model's order
    position: PlatformPosition | None
    model_revision: str  # sha256 of the model's JSON, first 16 hex digits
    start_ns: int | None
    end_ns: int | None
    #: "archive": the samples archived on board; "received": the windows the
    #: subscribers received (the base-station record, received.py).
    source: str = "archive"
    #: The model's sensors by name: their description (the NetCDF instruments).
    sensors: dict[str, str] = field(default_factory=dict)
    #: The scientist's discovery metadata (metadata.py); none declared when empty.
    metadata: Metadata = field(default_factory=Metadata)
    #: The primary time axis: "receive" (the PubBroker's receive time, every topic) or
    #: "instrument" (the instrument's time for the topics of sensors declaring it).
    clock: str = "receive"
    #: Every topic of the model (the export may hold fewer): a QC section may name any.
    model_topics: tuple[str, ...] = ()

    @property
    def two_clocks(self) -> bool:
        """A topic of the export declares the instrument's clock: both times are written."""
        return any(v.instrument_clock for v in self.variables.values())

    @property
    def other_clock(self) -> str:
        """The name of the second time (column, variable): the clock not on the axis."""
        return "receive_time" if self.clock == "instrument" else "instrument_time"


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]", "_", text)


def model_revision(model: dict[str, Any]) -> str:
    """A short digest of the model (its JSON without the diagram layout)."""
    doc = {k: v for k, v in model.items() if k != "layout"}
    return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()[:16]


def _variable(drone: str, sensor: dict[str, Any], var: dict[str, Any]) -> Variable:
    topic = f"{drone}.{sensor['name']}.{var['name']}"
    return Variable(
        topic=topic,
        name=_safe(f"{sensor['name']}_{var['name']}"),
        unit=udunits(var["unit"]),
        value_type=var.get("type", DEFAULT_VALUE_TYPE),
        standard_name=var.get("standardName"),
        long_name=var.get("longName") or var.get("description") or topic,
        valid_min=var.get("validMin"),
        valid_max=var.get("validMax"),
        temperature=convertible(var["unit"], "K"),
        sensor=sensor["name"],
        instrument_clock=sensor.get("clock") == "instrument",
    )


def plan_export(
    model: dict[str, Any],
    topics: list[str] | None,
    start_ns: int | None = None,
    end_ns: int | None = None,
) -> ExportPlan:
    """The plan for ``topics`` (all the model's when None). Raises PlanError."""
    drone = model["drone"]["name"]
    every = {
        v.topic: v
        for s in model["drone"]["sensors"]
        for v in (_variable(drone, s, var) for var in s["variables"])
    }
    chosen = every
    if topics:
        short = {t.split(".", 1)[1]: t for t in every} | {t.rsplit(".", 1)[1]: t for t in every}
        unknown = [t for t in topics if t not in every and t not in short]
        if unknown:
            raise PlanError(
                f"unknown topic(s) {', '.join(unknown)}; the model has {', '.join(every)}"
            )
        wanted = {every.get(t) or every[short[t]] for t in topics}
        chosen = {t: v for t, v in every.items() if v in wanted}
    if start_ns is not None and end_ns is not None and end_ns <= start_ns:
        raise PlanError("--to must be after --from")
    return ExportPlan(
        drone,
        model["drone"].get("description", drone),
        chosen,
        platform_position(model),
        model_revision(model),
        start_ns,
        end_ns,
        sensors={
            s["name"]: s.get("description") or s.get("kind") or s["name"]
            for s in model["drone"]["sensors"]
        },
        model_topics=tuple(every),
    )
