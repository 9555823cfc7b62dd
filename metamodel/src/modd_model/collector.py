"""A model document → the original tool's `.collector` form.

The original MoDD tool (Eclipse Xtext) reads one ``DataCollector { ... }``
block with named brokers, known units only, endpoints on every publisher and
subscriber, and the aggregations MIN, MAX, AVERAGE, FIRST, LAST and ALL. What
a model says beyond that cannot be written in that form: ``print_collector``
leaves it out and returns one warning per omission, with its JSON pointer, so
a team moving between the two tools knows exactly what the other one will not
see. Text in this form loads back with ``modd_model.load_text`` like any
``.modd`` file.

>>> from modd_model import load_model
>>> text, omitted = print_collector(load_model("metamodel/examples/demo.modd"))  # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any

from modd_contracts import aggregations_gen as agg

from .diagnostics import Diagnostic
from .printer import INDENT, endpoint, name, quote
from .query import DEFAULT_VALUE_TYPE
from .units import PAPER_UNITS
from .vocabulary import KNOWN_UNITS

#: Aggregations the original metamodel knows.
ORIGINAL_AGGREGATIONS = (agg.MIN, agg.MAX, agg.AVERAGE, agg.FIRST, agg.LAST, agg.ALL)
#: Broker names written when the model gives none (the original requires one).
DEFAULT_BROKER_NAMES = {"pubBroker": "broker", "subBroker": "base"}


class _Writer:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.omitted: list[Diagnostic] = []

    def omit(self, pointer: str, what: str) -> None:
        self.omitted.append(
            Diagnostic(f"left out of the .collector form: {what}", pointer, "warning")
        )

    def add(self, depth: int, text: str) -> None:
        self.lines.append(INDENT * depth + text)


def _drone(w: _Writer, drone: dict[str, Any]) -> None:
    if "description" in drone:
        w.omit("/drone/description", "the drone's description")
    if "position" in drone:
        w.omit("/drone/position", "the platform's position topics")
    w.add(1, f"Drone {name(drone['name'])} {{")
    w.add(2, "Sensors {")
    for i, s in enumerate(drone["sensors"]):
        ptr = f"/drone/sensors/{i}"
        if "description" in s:
            w.omit(ptr + "/description", f"the description of sensor {s['name']}")
        if "kind" in s:
            w.omit(
                ptr + "/kind",
                f"sensor {s['name']} is of kind {s['kind']} (the original tool has drivers only)",
            )
        w.add(3, f"Sensor {name(s['name'])} measures {{")
        for j, v in enumerate(s["variables"]):
            _variable(w, v, f"{ptr}/variables/{j}", s["name"])
        w.add(3, "}")
    w.add(2, "}")
    w.add(1, "}")


def _variable(w: _Writer, v: dict[str, Any], ptr: str, sensor: str) -> None:
    label = f"{sensor}.{v['name']}"
    unit = _paper_unit(v["unit"])
    if unit is None:
        w.omit(ptr + "/unit", f"the unit {v['unit']!r} of {label} (written as NONE)")
        unit = "NONE"
    for prop in ("standardName", "longName", "validMin", "validMax"):
        if prop in v:
            w.omit(f"{ptr}/{prop}", f"the {prop} of {label}")
    if v.get("type", DEFAULT_VALUE_TYPE) != DEFAULT_VALUE_TYPE:
        w.omit(ptr + "/type", f"the value type {v['type']} of {label}")
    if "description" in v:
        w.omit(ptr + "/description", f"the description of {label}")
    if "source" in v:
        w.omit(ptr + "/source", f"the MAVLink source of {label}")
    w.add(4, f"{name(v['name'])}({unit});")


def _paper_unit(unit: str) -> str | None:
    """The paper's name of a unit: itself, or the name whose UDUNITS spelling it is."""
    if unit in KNOWN_UNITS:
        return unit
    return next((k for k, text in PAPER_UNITS.items() if text == unit), None)


def _broker(w: _Writer, doc: dict[str, Any], key: str, word: str, path_key: str) -> None:
    broker = doc[key]
    broker_name = broker.get("name", DEFAULT_BROKER_NAMES[key])
    if "ingress" in broker:
        w.omit(f"/{key}/ingress", "the PubBroker's ingress settings")
    w.add(
        1, f"{word} {name(broker_name)}({endpoint(broker['endpoint'])}, {quote(broker[path_key])});"
    )


def _publishers(w: _Writer, doc: dict[str, Any]) -> None:
    w.add(1, "Publishers {")
    for i, p in enumerate(doc["publishers"]):
        ep = p.get("endpoint")
        if ep is None:
            # The original requires one; a publisher runs on board, where the PubBroker is.
            ep = doc["pubBroker"]["endpoint"]
            w.omit(
                f"/publishers/{i}",
                f"publisher {p['name']} has no endpoint; the PubBroker's is written in its place",
            )
        args = [endpoint(ep), p["periodS"], *(quote(t) for t in p["topics"])]
        w.add(2, f"Publisher {name(p['name'])}({', '.join(args)});")
    w.add(1, "}")


def _subscriptions(w: _Writer, doc: dict[str, Any]) -> None:
    w.add(1, "Subscriptions {")
    for i, s in enumerate(doc["subscribers"]):
        ptr = f"/subscribers/{i}"
        if "endpoint" not in s:
            w.omit(
                ptr,
                f"subscriber {s['name']} (served on zenoh only; the original tool "
                "delivers to endpoints)",
            )
            continue
        if s["aggregation"] not in ORIGINAL_AGGREGATIONS:
            w.omit(ptr, f"subscriber {s['name']} (the original tool has no {s['aggregation']})")
            continue
        args = [endpoint(s["endpoint"]), quote(s["topic"]), s["periodS"], s["aggregation"]]
        w.add(2, f"Subscriber {name(s['name'])}({', '.join(args)});")
    w.add(1, "}")


def print_collector(
    doc: dict[str, Any], *, note_omissions: bool = False
) -> tuple[str, list[Diagnostic]]:
    """The model in the original tool's form, and what had to be left out;
    with ``note_omissions`` the file opens with a comment line per omission."""
    w = _Writer()
    w.add(0, "DataCollector {")
    _drone(w, doc["drone"])
    _broker(w, doc, "pubBroker", "PubBroker", "logPath")
    _broker(w, doc, "subBroker", "SubBroker", "configPath")
    if "link" in doc:
        w.omit("/link", "the Link settings (the original tool uses its built-in constants)")
    _publishers(w, doc)
    _subscriptions(w, doc)
    if doc.get("layout"):
        w.omit("/layout", "the diagram layout")
    w.add(0, "}")
    # a line comment ends at \n or \r (Xtext's SL_COMMENT): keep each note on its line
    notes = (
        [" ".join(f"// {d.message} [{d.pointer}]".splitlines()) for d in w.omitted]
        if note_omissions
        else []
    )
    return "\n".join(notes + w.lines) + "\n", w.omitted
