"""A model document → canonical .modd text.

The canonical form is the paper's Listing 1 (top-level blocks, no
``DataCollector`` wrapper), four-space indents, every statement ended by ``;``.
Comments and the diagram layout are not part of the text: they do not survive
a JSON → .modd → JSON trip (the layout stays in the JSON form)."""

from __future__ import annotations

from typing import Any

from .parser import INGRESS_SETTINGS, LINK_SETTINGS, RADIO_SETTINGS
from .vocabulary import KNOWN_UNITS

INDENT = "    "
#: Words of the grammar: a name spelled like one is written ^-escaped (^Sensor).
KEYWORDS = frozenset({"DataCollector", "Drone", "Sensors", "Sensor", "measures", "kind", "from",
                      "scale", "offset", "PubBroker", "SubBroker", "Link", "Publishers",
                      "Publisher", "Subscriptions", "Subscriber"})


def name(text: str) -> str:
    """A name as the grammar reads it back: bare, ^-escaped if it is a keyword."""
    return "^" + text if text in KEYWORDS else text


_QUOTE_ESCAPES = str.maketrans({"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t",
                                "\r": "\\r", "\b": "\\b", "\f": "\\f"})


def quote(text: str) -> str:
    """A string literal the parser reads back as ``text``."""
    return '"' + text.translate(_QUOTE_ESCAPES) + '"'


def endpoint(ep: dict[str, Any]) -> str:
    return f'{quote(ep["host"])}:{ep["port"]}'


def _description(obj: dict[str, Any]) -> str:
    return f" {quote(obj['description'])}" if "description" in obj else ""


def _source(src: dict[str, Any]) -> str:
    text = f" from {src['message']}.{src['field']}"
    for key in ("scale", "offset"):
        if key in src:
            text += f" {key} {float(src[key])!r}"
    return text


def _settings(values: dict[str, Any], known: dict[str, tuple[str, str]], depth: int) -> list[str]:
    pad = INDENT * depth
    lines: list[str] = []
    for word, (prop, kind) in known.items():
        if prop not in values:
            continue
        v = values[prop]
        text = quote(v) if kind == "string" else str(v).lower() if kind == "bool" else str(v)
        lines.append(f"{pad}{INDENT}{word} = {text};")
    return lines


def _drone(drone: dict[str, Any]) -> list[str]:
    out = [f"Drone {name(drone['name'])}{_description(drone)} {{", f"{INDENT}Sensors {{"]
    for s in drone["sensors"]:
        kind = f" kind {s['kind']}" if "kind" in s else ""
        out.append(f"{INDENT * 2}Sensor {name(s['name'])}{_description(s)}{kind} measures {{")
        for v in s["variables"]:
            unit = v["unit"] if v["unit"] in KNOWN_UNITS else quote(v["unit"])
            vtype = f", {v['type']}" if "type" in v else ""
            source = _source(v["source"]) if "source" in v else ""
            out.append(f"{INDENT * 3}{name(v['name'])}({unit}{vtype}){_description(v)}{source};")
        out.append(f"{INDENT * 2}}}")
    out += [f"{INDENT}}}", "}"]
    return out


def _broker(word: str, broker: dict[str, Any], path_key: str) -> list[str]:
    label = f" {name(broker['name'])}" if "name" in broker else ""
    head = f"{word}{label}({endpoint(broker['endpoint'])}, {quote(broker[path_key])})"
    ingress = broker.get("ingress")
    if ingress is None:
        return [head + ";"]
    return [head + " {", *_settings(ingress, INGRESS_SETTINGS, 0), "};"]


def print_model(doc: dict[str, Any]) -> str:
    """The canonical .modd text of a model document (ends with a newline)."""
    out: list[str] = []
    out += _drone(doc["drone"])
    out += _broker("PubBroker", doc["pubBroker"], "logPath")
    out += _broker("SubBroker", doc["subBroker"], "configPath")
    if "link" in doc:
        link = dict(doc["link"])  # the radio profile is written flat (parser.RADIO_SETTINGS)
        link.update({f"radio/{k}": v for k, v in link.pop("radio", {}).items()})
        out += ["Link {", *_settings(link, LINK_SETTINGS | RADIO_SETTINGS, 0), "}"]
    out.append("Publishers {")
    for p in doc["publishers"]:
        args = [endpoint(p["endpoint"])] if "endpoint" in p else []
        args.append(p["periodS"])
        args += [quote(t) for t in p["topics"]]
        out.append(f"{INDENT}Publisher {name(p['name'])}({', '.join(args)});")
    out.append("}")
    out.append("Subscriptions {")
    for s in doc["subscribers"]:
        args = [endpoint(s["endpoint"])] if "endpoint" in s else []
        args += [quote(s["topic"]), s["periodS"], s["aggregation"]]
        if "backfill" in s:  # "off" too when set: the text keeps what the model says
            args.append(f"backfill = {s['backfill']}")
        out.append(f"{INDENT}Subscriber {name(s['name'])}({', '.join(args)});")
    out.append("}")
    return "\n".join(out) + "\n"
