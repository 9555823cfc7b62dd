"""Semantic checks of the instrument sensors (``kind nmea``, ``ascii``,
``modbus``), read by ``modd-sensors`` with no driver code: each needs its
serial device, each of its variables says where its value comes from (and
only in its sensor's kind), the NMEA fields exist and hold numbers, an ascii
line's pattern compiles and has the groups the variables read, and no two
Modbus variables read one register as different things. Registered by
``validate.py``; each diagnostic carries the JSON pointer of what is wrong.

Example::

    >>> lat = {"name": "lat", "unit": "deg", "nmea": {"sentence": "GGA", "field": "f20"}}
    >>> sensor = {"name": "gnss", "kind": "nmea", "device": {"path": "/dev/ttyACM0"},
    ...           "variables": [lat]}
    >>> [d.message for d in instrument_sensors({"drone": {"sensors": [sensor]}})]
    ['GGA has 14 fields: f20 is out of range']
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator
from typing import Any

from .diagnostics import Diagnostic
from .vocabulary import NMEA_SENTENCES

INSTRUMENT_KINDS = ("nmea", "ascii", "modbus")
_SENSOR_ONLY = {
    "device": INSTRUMENT_KINDS,
    "line": ("ascii",),
    "clock": ("nmea",),
    "checksum": ("nmea",),
    "fix": ("nmea",),
}
_VARIABLE_MAPPING = ("source", "nmea", "ascii", "modbus")
_NUMERIC = ("number", "latitude", "longitude")
_TEXT = ("text", "status")
_WORDS = {"int16": 1, "uint16": 1, "int32": 2, "uint32": 2, "float32": 2}


def nmea_field_kind(sentence: str, field: str) -> tuple[str | None, str | None]:
    """(what ``field`` of ``sentence`` holds, None) or (None, why there is no such field)."""
    table = NMEA_SENTENCES.get(sentence)
    if table is None:
        return None, f"unknown NMEA sentence {sentence!r}; known: {', '.join(NMEA_SENTENCES)}"
    kinds = list(table.values())
    if field in table:
        return table[field], None
    if re.fullmatch(r"f[1-9][0-9]?", field):
        n = int(field[1:])
        if sentence != "XDR" and n > len(kinds):
            return None, f"{sentence} has {len(kinds)} fields: {field} is out of range"
        return kinds[(n - 1) % len(kinds)], None
    fields = ", ".join(table)
    return None, f"{sentence} has no field {field!r} (fields: {fields}; or fN for the N-th)"


def nmea_field_problem(sentence: str, field: str) -> str | None:
    """Why ``field`` of ``sentence`` cannot be read as a number (None: it can)."""
    kind, problem = nmea_field_kind(sentence, field)
    if kind is None:
        return problem
    if kind not in _NUMERIC:
        return f"{sentence}.{field} holds {kind}, not a number"
    return None


def _is_number(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


def _nmea_condition(src: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    """A ``where`` on an NMEA source: a field of the sentence holding text or a
    number, compared as it can be; XDR's quadruplet picked by a named field."""
    cond, sentence = src["where"], src["sentence"]
    field, op, value = cond["field"], cond.get("op", "="), cond["value"]
    kind, problem = nmea_field_kind(sentence, field)
    if kind is None:
        yield Diagnostic(f"where: {problem}", f"{ptr}/where/field")
        return
    name = f"{sentence}.{field}"
    if kind not in _NUMERIC + _TEXT:
        yield Diagnostic(
            f"where: {name} holds a {kind}; a condition compares text or numbers",
            f"{ptr}/where/field",
        )
    elif kind in _TEXT and op not in ("=", "!="):
        yield Diagnostic(
            f"where: {name} holds text: compare it with = or !=, not {op}", f"{ptr}/where/op"
        )
    elif kind in _NUMERIC and not _is_number(value):
        yield Diagnostic(
            f"where: {name} holds a number: compare it with a number, not {value!r}",
            f"{ptr}/where/value",
        )
    if (
        sentence == "XDR"
        and field in NMEA_SENTENCES["XDR"]
        and src["field"] not in NMEA_SENTENCES["XDR"]
    ):
        yield Diagnostic(
            f"where: {field} picks an XDR quadruplet: read the quadruplet's field "
            f"(type, value, unit or id), not {src['field']}",
            f"{ptr}/field",
        )


def _ascii_condition(cond: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    if ("column" in cond) == ("key" in cond):
        yield Diagnostic(
            "where: a condition compares exactly one of column and key", ptr + "/where"
        )
    op = cond.get("op", "=")
    if op not in ("=", "!=") and not _is_number(cond["value"]):
        yield Diagnostic(
            f"where: {op} compares numbers: {cond['value']!r} is not a number", ptr + "/where/value"
        )


def _sensor_parts(s: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    kind = s.get("kind", "generic")
    if kind in INSTRUMENT_KINDS and "device" not in s:
        yield Diagnostic(
            f"the {kind} sensor {s['name']!r} needs its serial device: "
            'on "/dev/ttyUSB0" { baud = 9600; }',
            ptr,
        )
    for part, kinds in _SENSOR_ONLY.items():
        if part in s and kind not in kinds:
            yield Diagnostic(
                f"{part} is only for a sensor of kind {' or '.join(kinds)} "
                f"({s['name']!r} is {kind})",
                f"{ptr}/{part}",
            )


def _variable_mapping(s: dict[str, Any], v: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    kind = s.get("kind", "generic")
    for other in _VARIABLE_MAPPING[1:]:
        if other in v and other != kind:
            yield Diagnostic(
                f"variable {v['name']!r} is read as {other} but sensor "
                f"{s['name']!r} is of kind {kind}",
                f"{ptr}/{other}",
            )
    if kind in INSTRUMENT_KINDS and kind not in v:
        how = {
            "nmea": "from sentence SENTENCE.field",
            "ascii": "from column N or from key NAME",
            "modbus": "from register N TYPE",
        }[kind]
        yield Diagnostic(
            f"variable {v['name']!r} of the {kind} sensor {s['name']!r} needs a source: {how}", ptr
        )
    src = v.get(kind) if kind in INSTRUMENT_KINDS else None
    if not isinstance(src, dict):
        return
    scale = src.get("scale", 1)
    if scale != scale or scale in (float("inf"), float("-inf")) or scale == 0:
        yield Diagnostic("scale must be a finite number other than zero", f"{ptr}/{kind}/scale")
    if kind == "nmea" and (problem := nmea_field_problem(src["sentence"], src["field"])):
        yield Diagnostic(problem, f"{ptr}/nmea/field")
    if kind == "nmea" and "where" in src:
        yield from _nmea_condition(src, f"{ptr}/nmea")
    if kind == "ascii" and ("column" in src) == ("key" in src):
        yield Diagnostic("an ascii variable reads exactly one of column and key", f"{ptr}/ascii")
    if kind == "ascii" and "where" in src:
        yield from _ascii_condition(src["where"], f"{ptr}/ascii")


def _ascii_pattern(s: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    text = s.get("line", {}).get("pattern")
    if text is None:
        return
    try:
        pattern = re.compile(text)
    except re.error as exc:
        yield Diagnostic(f"the pattern is not a regular expression: {exc}", f"{ptr}/line/pattern")
        return
    for j, v in enumerate(s["variables"]):
        src = v.get("ascii", {})
        for where, place in ((src, ""), (src.get("where", {}), "/where")):
            at = f"{ptr}/variables/{j}/ascii{place}"
            if "key" in where and where["key"] not in pattern.groupindex:
                yield Diagnostic(f"the pattern has no group named {where['key']!r}", f"{at}/key")
            if "column" in where and where["column"] > pattern.groups:
                yield Diagnostic(
                    f"the pattern has {pattern.groups} groups: no group {where['column']}",
                    f"{at}/column",
                )


def _modbus_registers(s: dict[str, Any], ptr: str) -> Iterator[Diagnostic]:
    """Two variables reading one register must read it alike (same type and word order)."""
    seen: dict[tuple[int, str, int], tuple[str, int, str, str]] = {}
    for j, v in enumerate(s["variables"]):
        src = v.get("modbus")
        if not isinstance(src, dict):
            continue
        rtype, order = src.get("type", "uint16"), src.get("wordOrder", "big")
        start = src["register"]
        here = f"{ptr}/variables/{j}/modbus/register"
        if start + _WORDS[rtype] > 65536:
            yield Diagnostic(f"a {rtype} at register {start} runs past register 65535", here)
            continue
        for reg in range(start, start + _WORDS[rtype]):
            key = (src.get("unit", 1), src.get("table", "holding"), reg)
            name, first_start, first_type, first_order = seen.setdefault(
                key, (v["name"], start, rtype, order)
            )
            if (first_start, first_type, first_order) != (start, rtype, order):
                yield Diagnostic(
                    f"register {reg} of unit {key[0]} ({key[1]}) is read by "
                    f"{name!r} as a {first_type} at {first_start} "
                    f"({first_order} word order) and here as a {rtype} at "
                    f"{start} ({order})",
                    here,
                )
                break


def instrument_sensors(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """Every problem of the model's instrument sensors and of their variables' sources."""
    for i, s in enumerate(doc["drone"]["sensors"]):
        ptr = f"/drone/sensors/{i}"
        yield from _sensor_parts(s, ptr)
        for j, v in enumerate(s["variables"]):
            yield from _variable_mapping(s, v, f"{ptr}/variables/{j}")
        if s.get("kind") == "ascii":
            yield from _ascii_pattern(s, ptr)
        if s.get("kind") == "modbus":
            yield from _modbus_registers(s, ptr)
