"""A model document → canonical .modd text.

The canonical form is the paper's Listing 1 (top-level blocks, no
``DataCollector`` wrapper), four-space indents, every statement ended by ``;``.
Comments are not part of the model: ``comments.keep_comments`` puts those of a
source text back into its canonical form (``modd fmt``). The diagram layout is
not part of the text (it stays in the JSON form)."""

from __future__ import annotations

import re
from typing import Any

from modd_contracts import aggregations_gen as agg

from .parser import (
    CHANNEL_SETTINGS,
    INGRESS_SETTINGS,
    LINK_SETTINGS,
    POSITION_SETTINGS,
    RADIO_SETTINGS,
    SENSOR_SETTINGS,
    VARIABLE_ATTRIBUTES,
)
from .vocabulary import KNOWN_UNITS

INDENT = "    "
#: Words of the grammar: a name spelled like one is written ^-escaped (^Sensor).
KEYWORDS = frozenset(
    {
        "DataCollector",
        "Drone",
        "Sensors",
        "Sensor",
        "measures",
        "kind",
        "from",
        "scale",
        "offset",
        "PubBroker",
        "SubBroker",
        "Link",
        "Publishers",
        "Publisher",
        "Subscriptions",
        "Subscriber",
        "Position",
        "on",
        "with",
        "sentence",
        "column",
        "key",
        "register",
        "unit",
        "table",
        "order",
        "where",
    }
)


def name(text: str) -> str:
    """A name as the grammar reads it back: bare, ^-escaped if it is a keyword."""
    return "^" + text if text in KEYWORDS else text


_QUOTE_ESCAPES = str.maketrans(
    {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r", "\b": "\\b", "\f": "\\f"}
)


def quote(text: str) -> str:
    """A string literal the parser reads back as ``text``."""
    return '"' + text.translate(_QUOTE_ESCAPES) + '"'


def endpoint(ep: dict[str, Any]) -> str:
    return f"{quote(ep['host'])}:{ep['port']}"


def _description(obj: dict[str, Any]) -> str:
    return f" {quote(obj['description'])}" if "description" in obj else ""


def _source(src: dict[str, Any]) -> str:
    text = f" from {src['message']}.{src['field']}"
    for key in ("scale", "offset"):
        if key in src:
            text += f" {key} {float(src[key])!r}"
    return text


def _factors(src: dict[str, Any]) -> str:
    return "".join(f" {key} {float(src[key])!r}" for key in ("scale", "offset") if key in src)


_BARE_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_BARE_NUMBER = re.compile(r"[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?")


def _condition(cond: dict[str, Any] | None) -> str:
    """`` where PLACE OP VALUE`` of a source ("" without one); a value that is a plain
    word (not a keyword) or a number is written bare, anything else quoted."""
    if cond is None:
        return ""
    if "field" in cond:
        place = cond["field"]
    else:
        place = f"column {cond['column']}" if "column" in cond else f"key {quote(cond['key'])}"
    value = cond["value"]
    bare = (_BARE_WORD.fullmatch(value) and value not in KEYWORDS) or _BARE_NUMBER.fullmatch(value)
    return f" where {place} {cond.get('op', '=')} {value if bare else quote(value)}"


def _instrument_source(v: dict[str, Any]) -> str:
    """The ``from`` of an nmea, ascii or modbus variable ("" when it has none)."""
    if "nmea" in v:
        n = v["nmea"]
        where = _condition(n.get("where"))
        return f" from sentence {n['sentence']}.{n['field']}{_factors(n)}{where}"
    if "ascii" in v:
        a = v["ascii"]
        where = f"column {a['column']}" if "column" in a else f"key {quote(a['key'])}"
        return f" from {where}{_factors(a)}{_condition(a.get('where'))}"
    if "modbus" in v:
        m = v["modbus"]
        text = f" from register {m['register']} {m.get('type', 'uint16')}"
        for key, word in (("unit", "unit"), ("table", "table"), ("wordOrder", "order")):
            if key in m:
                text += f" {word} {m[key]}"
        return text + _factors(m)
    return ""


def _device(s: dict[str, Any]) -> str:
    """`` on "PATH" { settings }`` of an instrument sensor ("" when it has neither)."""
    flat = {
        f"{part}/{k}": v
        for part in ("device", "line")
        for k, v in s.get(part, {}).items()
        if (part, k) != ("device", "path")
    }
    flat.update({k: s[k] for k in ("clock", "checksum", "fix") if k in s})
    settings = " ".join(line.strip() for line in _settings(flat, SENSOR_SETTINGS, 0))
    path = s.get("device", {}).get("path")
    head = f" on {quote(path)}" if path is not None else " with" if settings else ""
    return head + (f" {{ {settings} }}" if settings else "")


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
        out.append(
            f"{INDENT * 2}Sensor {name(s['name'])}{_description(s)}{kind}{_device(s)} measures {{"
        )
        for v in s["variables"]:
            unit = v["unit"] if v["unit"] in KNOWN_UNITS else quote(v["unit"])
            vtype = f", {v['type']}" if "type" in v else ""
            source = _source(v["source"]) if "source" in v else _instrument_source(v)
            out.append(
                f"{INDENT * 3}{name(v['name'])}({unit}{vtype}){_description(v)}{source}"
                f"{_attributes(v)};"
            )
        out.append(f"{INDENT * 2}}}")
    out.append(f"{INDENT}}}")
    if "position" in drone:
        out += [
            f"{INDENT}Position {{",
            *_settings(drone["position"], POSITION_SETTINGS, 1),
            f"{INDENT}}}",
        ]
    out.append("}")
    return out


def _attributes(v: dict[str, Any]) -> str:
    """`` { standardName = ...; longName = "..."; }`` when the variable has any."""
    parts = []
    for word, (prop, kind) in VARIABLE_ATTRIBUTES.items():
        if prop in v:
            value = v[prop]
            text = (
                quote(value)
                if kind == "text"
                else repr(float(value))
                if kind == "number"
                else str(value)
            )
            parts.append(f"{word} = {text};")
    return f" {{ {' '.join(parts)} }}" if parts else ""


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
        out += ["Link {", *_link_settings(doc["link"], 0), "}"]
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
        positional, named = _agg_args(s)
        args += [quote(s["topic"]), s["periodS"], s["aggregation"] + positional]
        if "backfill" in s:  # "off" too when set: the text keeps what the model says
            args.append(f"backfill = {s['backfill']}")
        if "resolution" in s:
            args.append(f"resolution = {float(s['resolution'])!r}")
        args += named
        if "maxEvents" in s:
            args.append(f"maxEvents = {s['maxEvents']}")
        if s.get("alert"):
            args.append("alert = " + " + ".join(s["alert"]))
        out.append(f"{INDENT}Subscriber {name(s['name'])}({', '.join(args)});")
    out.append("}")
    if "campaign" in doc:
        out += _campaign(doc["campaign"])
    return "\n".join(out) + "\n"


def _link_settings(link: dict[str, Any], depth: int) -> list[str]:
    flat = dict(link)  # the radio profile is written flat (parser.RADIO_SETTINGS)
    flat.update({f"radio/{k}": v for k, v in flat.pop("radio", {}).items()})
    return _settings(flat, LINK_SETTINGS | RADIO_SETTINGS, depth)


def _campaign(campaign: dict[str, Any]) -> list[str]:
    out = [f"Campaign {name(campaign['name'])}{_description(campaign)} {{"]
    for c in campaign.get("channels", []):
        out += [f"{INDENT}Channel {name(c['name'])} {{", *_settings(c, CHANNEL_SETTINGS, 1)]
        out.append(f"{INDENT}}}")
    for v in campaign["vehicles"]:
        out.append(f"{INDENT}Vehicle {name(v['name'])}{_description(v)} {{")
        inner = INDENT * 2
        if "channel" in v:
            out.append(f"{inner}channel = {name(v['channel'])};")
        for part, word in (("pubBroker", "PubBroker"), ("subBroker", "SubBroker")):
            if part in v:
                path = f", {quote(v[part]['path'])}" if "path" in v[part] else ""
                out.append(f"{inner}{word}({endpoint(v[part]['endpoint'])}{path});")
        for d in v.get("devices", []):
            out.append(f"{inner}device {name(d['sensor'])} = {quote(d['path'])};")
        if "link" in v:
            out += [f"{inner}Link {{", *_link_settings(v["link"], 2), f"{inner}}}"]
        out.append(f"{INDENT}}}")
    return [*out, "}"]


def _number(x: Any) -> str:
    """The shortest text of a number that reads back."""
    return repr(float(x)).removesuffix(".0")


_EVENT_KEYS = ("deadband", "deadbandPercent", "level", "hysteresis", "crossing")


def _agg_args(sub: dict[str, Any]) -> tuple[str, list[str]]:
    """The aggregation's parameters in parentheses where their places say them,
    ``(95)`` after PERCENTILE, ``(0.5)`` or ``(5%)`` after ON_CHANGE,
    ``(DOWN 5, 0.2)`` after THRESHOLD; any other (a field the aggregation does
    not take, which the validator reports) by name, ``level = 5``, so that the
    text keeps what the model says."""
    keys = [k for k in ("percentile", *_EVENT_KEYS) if k in sub]
    aggregation = sub["aggregation"]
    if aggregation == agg.ON_CHANGE and keys in (["deadband"], ["deadbandPercent"]):
        x = sub[keys[0]]
        return f"({_number(x)}{'%' if keys[0] == 'deadbandPercent' else ''})", []
    if (
        aggregation == agg.THRESHOLD
        and "level" in keys
        and set(keys) <= {"level", "hysteresis", "crossing"}
    ):
        crossing = f"{sub['crossing'].upper()} " if "crossing" in sub else ""
        h = f", {_number(sub['hysteresis'])}" if "hysteresis" in sub else ""
        return f"({crossing}{_number(sub['level'])}{h})", []
    positional = ""
    if "percentile" in keys and aggregation not in (agg.ON_CHANGE, agg.THRESHOLD):
        positional, keys = f"({_number(sub['percentile'])})", keys[1:]
    named = [f"{k} = {sub[k] if k == 'crossing' else _number(sub[k])}" for k in keys]
    return positional, named
