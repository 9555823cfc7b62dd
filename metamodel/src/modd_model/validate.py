"""Validation of a model document: the JSON Schema first, then the semantic
checks a user needs. All problems are reported at once, each with its JSON
pointer. Semantic checks are small registered functions (one concern each)
that run only on documents the schema accepts."""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Callable, Iterator
from fractions import Fraction
from functools import cache, lru_cache
from typing import TYPE_CHECKING, Any

from modd_contracts import aggregations_gen as agg
from modd_contracts.aggregations_gen import AGGREGATIONS
from modd_contracts.events import EVENT_AGGREGATIONS
from modd_contracts.link_wire_gen import MAX_LIST, MAX_PERIOD_US

from .bounds import size_errors
from .campaign import campaign_checks, vehicle_diagnostics
from .diagnostics import Diagnostic, pointer_join
from .instruments import instrument_sensors
from .numbers import to_fraction, to_micros
from .query import topic_name
from .resolution import CHECKS as RESOLUTION_CHECKS
from .schema import definition, load_schema
from .science import CHECKS as SCIENCE_CHECKS

if TYPE_CHECKING:  # jsonschema is imported on first validation (it is slow to import)
    from jsonschema import Draft202012Validator
    from jsonschema.exceptions import ValidationError

Check = Callable[[dict[str, Any]], Iterator[Diagnostic]]
#: Units, standard names, valid ranges and the platform position (science.py) first.
CHECKS: list[Check] = [*SCIENCE_CHECKS, *RESOLUTION_CHECKS, campaign_checks]

# Aggregations that make no sense on booleans (their mean or sum is not a bool):
# the aggregation table's numericOnly.
_NUMERIC_ONLY = {a.name for a in AGGREGATIONS if a.numeric_only}
# Aggregations whose window's samples the PubBroker holds (ALL, MEDIAN,
# PERCENTILE): at most
# the link's list bound a window (docs/protocol.md, "Aggregation semantics").
_KEEPS_SAMPLES = {a.name for a in AGGREGATIONS if a.keeps_samples}


def check(fn: Check) -> Check:
    """Register a semantic check."""
    CHECKS.append(fn)
    return fn


def validate(doc: Any) -> list[Diagnostic]:
    """Every problem of ``doc``: schema errors, then semantic errors and warnings.

    The semantic checks also run on a document the schema rejects, so that a
    user sees all problems at once; a check that cannot make sense of a
    malformed part is skipped (the schema error already names that part).
    A document past the schema's size bounds is reported for those alone
    (bounds.py): the work stays bounded whatever its size."""
    oversized = size_errors(doc)
    if oversized:
        return oversized
    out = _schema_diagnostics(doc)
    if not isinstance(doc, dict):
        return out
    for fn in CHECKS:
        try:
            out.extend(list(fn(doc)))
        except (KeyError, TypeError, ValueError, AttributeError, IndexError):
            if not out:
                raise  # on a schema-valid document a failing check is a bug
    if "campaign" in doc and not any(d.severity == "error" for d in out):
        out.extend(vehicle_diagnostics(doc, out, validate))  # each vehicle's own model
    return out


_VALIDATOR: Draft202012Validator | None = None


def _schema_diagnostics(doc: Any) -> list[Diagnostic]:
    """The schema's errors, sorted by pointer. A compiled validator
    (jsonschema-rs, ~300x faster on a model of 25,000 subscriptions) says
    whether there are any; only then does the reference validator
    (jsonschema, whose messages and pointers the diagnostics use) walk the
    document. The fast one may refuse more (then the reference decides),
    never less: the patterns are ECMA-262 in both (tests/test_validate_fast.py)."""
    fast = _fast_validator()
    if fast is not None:
        try:
            if fast.is_valid(doc):
                return []
        except Exception:  # noqa: BLE001 - anything it cannot read: the reference decides
            pass
    return sorted(
        (_schema_diagnostic(e) for e in _schema_validator().iter_errors(doc)),
        key=lambda d: d.pointer,
    )


@cache
def _fast_validator() -> Any:
    try:
        import jsonschema_rs
    except ImportError:  # pragma: no cover - a declared dependency
        return None
    return jsonschema_rs.validator_for(load_schema())


@cache
def ecma_regex(pattern: str) -> re.Pattern[str]:
    """A schema ``pattern`` compiled with the meaning JSON Schema gives it (ECMA-262,
    as the workbench's browser reads it), not Python's: an unescaped ``$`` outside
    a character class is the end of the text (``\\Z``), where Python's ``$`` also
    accepts a trailing newline (``re.search("^a$", "a\\n")`` matches); ``\\d``
    and ``\\w`` are ASCII.

    >>> bool(ecma_regex("^[a-z]+$").search("abc\\n"))
    False
    """
    out, in_class, i = [], False, 0
    while i < len(pattern):
        c = pattern[i]
        if c == "\\":
            out.append(pattern[i : i + 2])
            i += 2
            continue
        if c == "[":
            in_class = True
        elif c == "]":
            in_class = False
        out.append(r"\Z" if c == "$" and not in_class else c)
        i += 1
    return re.compile("".join(out), re.ASCII)


def _pattern(validator: Any, pattern: str, instance: Any, schema: Any) -> Iterator[ValidationError]:
    from jsonschema.exceptions import ValidationError

    if validator.is_type(instance, "string") and not ecma_regex(pattern).search(instance):
        yield ValidationError(f"{instance!r} does not match {pattern!r}")


@cache
def _validator_class() -> Any:
    """Draft 2020-12 with ECMA-262 ``pattern``; jsonschema is imported here, on
    first validation (it is slow to import)."""
    from jsonschema import Draft202012Validator, validators

    return validators.extend(  # type: ignore[no-untyped-call]
        Draft202012Validator, {"pattern": _pattern}
    )


def _schema_validator() -> Draft202012Validator:
    global _VALIDATOR
    if _VALIDATOR is None:
        _VALIDATOR = _validator_class()(load_schema())
    return _VALIDATOR


def _schema_diagnostic(err: ValidationError) -> Diagnostic:
    pointer = pointer_join(*err.absolute_path)
    if err.validator == "additionalProperties":
        message = err.message.replace("Additional properties are not allowed", "unknown property")
    elif err.validator == "pattern":
        message = f"{err.instance!r} is not well-formed ({_pattern_hint(err)})"
    elif err.validator == "anyOf" and isinstance(err.instance, str):
        message = (
            f"{err.instance!r} is not a valid unit (a UDUNITS-2 unit or one of the "
            "paper's unit names, 1 to 64 printable characters without control or "
            "invisible formatting characters)"
        )
    else:
        message = err.message
    return Diagnostic(message, pointer)


def _pattern_hint(err: ValidationError) -> str:
    desc = err.schema.get("description") if isinstance(err.schema, dict) else None
    return str(desc) if desc else f"expected pattern {err.validator_value}"


# -- semantic checks ---------------------------------------------------------


def _duplicates(items: list[tuple[str, str]], what: str) -> Iterator[Diagnostic]:
    first: dict[str, str] = {}
    for name, ptr in items:
        if name in first:
            yield Diagnostic(f"{what} {name!r} is already defined at {first[name]}", ptr)
        else:
            first[name] = ptr


@check
def unique_names(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    sensors = doc["drone"]["sensors"]
    yield from _duplicates(
        [(s["name"], f"/drone/sensors/{i}/name") for i, s in enumerate(sensors)], "sensor"
    )
    for i, s in enumerate(sensors):
        yield from _duplicates(
            [
                (v["name"], f"/drone/sensors/{i}/variables/{j}/name")
                for j, v in enumerate(s["variables"])
            ],
            f"variable of sensor {s['name']!r}",
        )
    # Publishers and subscribers are two name spaces (as in the original tool):
    # their generated files, diagram nodes and zenoh keys never meet.
    yield from _duplicates(
        [(p["name"], f"/publishers/{i}/name") for i, p in enumerate(doc["publishers"])], "publisher"
    )
    yield from _duplicates(
        [(s["name"], f"/subscribers/{i}/name") for i, s in enumerate(doc["subscribers"])],
        "subscriber",
    )


def _declared_topics(doc: dict[str, Any]) -> dict[str, dict[str, Any]]:
    drone = doc["drone"]["name"]
    return {
        topic_name(drone, s["name"], v["name"]): v
        for s in doc["drone"]["sensors"]
        for v in s["variables"]
    }


def _unknown_topic(topic: str, doc: dict[str, Any], ptr: str) -> Diagnostic:
    drone = doc["drone"]["name"]
    hint = ""
    if not topic.startswith(drone + "."):
        hint = f"; topics of this drone start with {drone + '.'!r}"
    return Diagnostic(f"unknown topic {topic!r}{hint}", ptr)


@check
def references_resolve(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    declared = _declared_topics(doc)
    publisher_of: dict[str, str] = {}
    for i, pub in enumerate(doc["publishers"]):
        for j, t in enumerate(pub["topics"]):
            ptr = f"/publishers/{i}/topics/{j}"
            if t not in declared:
                yield _unknown_topic(t, doc, ptr)
            elif t in publisher_of:
                # Runnable (the broker archives both), but the planner sizes the
                # buffer for the first publisher's period: say so.
                yield Diagnostic(
                    f"topic {t!r} is also published by {publisher_of[t]!r}; "
                    "buffer sizes are planned for the first publisher's "
                    "period only",
                    ptr,
                    "warning",
                )
            else:
                publisher_of[t] = pub["name"]
    for i, sub in enumerate(doc["subscribers"]):
        t = sub["topic"]
        ptr = f"/subscribers/{i}/topic"
        if t not in declared:
            yield _unknown_topic(t, doc, ptr)
        elif t not in publisher_of:
            yield Diagnostic(
                f"no publisher publishes {t!r}, so subscriber "
                f"{sub['name']!r} would never receive a value",
                ptr,
            )


#: Longest period (s) a model may use: about 11.6 days. It bounds the
#: planner's integers (hyperperiods, buffer-size candidates), and never exceeds
#: the link's own bound (modd_contracts/wire.json), so a valid model's CONFIG decodes.
MAX_PERIOD_S = min(1_000_000, MAX_PERIOD_US // 1_000_000)


@lru_cache(maxsize=65_536)  # bounded: a model repeats few period texts
def _period_problem(text: str) -> str | None:
    if to_fraction(text) <= 0:
        return "a period must be greater than zero"
    if to_fraction(text) > MAX_PERIOD_S:
        return f"a period must be at most {MAX_PERIOD_S:,} s"
    try:
        to_micros(text)
    except ValueError:
        return f"period {text} s is finer than a microsecond, the resolution of the link"
    return None


@check
def periods_valid(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    for kind in ("publishers", "subscribers"):
        for i, item in enumerate(doc[kind]):
            problem = _period_problem(item["periodS"])
            if problem:
                yield Diagnostic(problem, f"/{kind}/{i}/periodS")
    ping = doc.get("link", {}).get("pingS")
    if ping is not None and to_fraction(ping) <= 0:
        yield Diagnostic("PING time must be greater than zero", "/link/pingS")


@check
def subscription_periods(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    pub_period: dict[str, str] = {}
    for pub in doc["publishers"]:
        for t in pub["topics"]:
            pub_period.setdefault(t, pub["periodS"])
    shorter: dict[tuple[str, str], bool] = {}  # (pm, ps) texts: few distinct pairs
    for i, sub in enumerate(doc["subscribers"]):
        pm_text = pub_period.get(sub["topic"])
        if pm_text is None:
            continue
        pair = (pm_text, sub["periodS"])
        if pair not in shorter:
            shorter[pair] = 0 < to_fraction(sub["periodS"]) < to_fraction(pm_text)
        if shorter[pair]:
            pm = to_fraction(pm_text)
            yield Diagnostic(
                f"subscription period {sub['periodS']} s is shorter than the "
                f"publication period {float(pm):g} s of {sub['topic']!r}",
                f"/subscribers/{i}/periodS",
            )


@check
def window_samples_bounded(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """A MEDIAN, PERCENTILE or ALL window holds every sample of its period on board: at most
    MAX_LIST, from the topic's publication period (its fastest publisher); so may an
    ON_CHANGE or THRESHOLD window's events without maxEvents (its worst case)."""
    fastest: dict[str, Fraction] = {}
    for pub in doc["publishers"]:
        period = to_fraction(pub["periodS"])
        for t in pub["topics"]:
            if period > 0 and (t not in fastest or period < fastest[t]):
                fastest[t] = period
    for i, sub in enumerate(doc["subscribers"]):
        pm = fastest.get(sub["topic"])
        derived = sub["aggregation"] in EVENT_AGGREGATIONS and "maxEvents" not in sub
        if sub["aggregation"] not in _KEEPS_SAMPLES and not derived or pm is None:
            continue
        samples = -(-to_fraction(sub["periodS"]) // pm)  # ceil: a window's most
        if samples > MAX_LIST:
            yield Diagnostic(
                f"a {sub['aggregation']} window of {sub['periodS']} s holds up to {samples} "
                f"samples of {sub['topic']!r} (published every {float(pm):g} s); the "
                f"PubBroker keeps at most {MAX_LIST} a window: choose a period of at most "
                f"{float(pm * MAX_LIST):g} s" + (" (or declare maxEvents)" if derived else ""),
                f"/subscribers/{i}/periodS",
            )


@check
def aggregation_fits_type(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    declared = _declared_topics(doc)
    for i, sub in enumerate(doc["subscribers"]):
        var = declared.get(sub["topic"])
        if var and var.get("type") == "bool" and sub["aggregation"] in _NUMERIC_ONLY:
            yield Diagnostic(
                f"{sub['aggregation']} is not defined for the bool topic {sub['topic']!r}",
                f"/subscribers/{i}/aggregation",
            )


@check
def percentile_has_its_p(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """PERCENTILE names its p (``PERCENTILE(95)``, ``"percentile": 95``); no
    other aggregation takes one. Its range, 0 to 100, is the schema's."""
    for i, sub in enumerate(doc["subscribers"]):
        is_percentile = sub["aggregation"] == agg.PERCENTILE
        if is_percentile and "percentile" not in sub:
            yield Diagnostic(
                "PERCENTILE needs its p, 0 to 100: PERCENTILE(95) in .modd, "
                '"percentile": 95 in JSON',
                f"/subscribers/{i}/aggregation",
            )
        elif not is_percentile and "percentile" in sub:
            yield Diagnostic(
                f"{sub['aggregation']} takes no percentile (only PERCENTILE(p) does)",
                f"/subscribers/{i}/percentile",
            )


#: Each event subscription's own fields (modd_contracts.events); maxEvents is both's.
_EVENT_FIELDS = {
    agg.ON_CHANGE: ("deadband", "deadbandPercent", "maxEvents"),
    agg.THRESHOLD: ("level", "hysteresis", "crossing", "maxEvents"),
}


@check
def event_parameters(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """ON_CHANGE takes a deadband (absolute, or deadbandPercent), THRESHOLD its
    level (and hysteresis, crossing); both an optional maxEvents; no other
    aggregation takes any of them. Their ranges are the schema's."""
    every = {f for fields in _EVENT_FIELDS.values() for f in fields}
    for i, sub in enumerate(doc["subscribers"]):
        mine = _EVENT_FIELDS.get(sub["aggregation"], ())
        for f in sorted(every.intersection(sub).difference(mine)):
            yield Diagnostic(
                f"{sub['aggregation']} takes no {f} (ON_CHANGE takes deadband or "
                "deadbandPercent, THRESHOLD level, hysteresis and crossing; both maxEvents)",
                f"/subscribers/{i}/{f}",
            )
        if sub["aggregation"] == agg.ON_CHANGE and {"deadband", "deadbandPercent"} <= sub.keys():
            yield Diagnostic(
                "ON_CHANGE takes one deadband: deadband (absolute) or deadbandPercent (relative)",
                f"/subscribers/{i}/deadbandPercent",
            )
        if sub["aggregation"] in _EVENT_FIELDS and "resolution" in sub:
            yield Diagnostic(
                f"{sub['aggregation']} sends each event's sample exact: it takes no resolution",
                f"/subscribers/{i}/resolution",
            )
        if "alert" in sub and sub["aggregation"] != agg.THRESHOLD:
            yield Diagnostic(
                f"only a THRESHOLD subscription can be an alert ({sub['aggregation']} "
                "has no crossing to raise it): THRESHOLD(UP 0.5, 0.1), alert = scientist",
                f"/subscribers/{i}/alert",
            )
        if sub["aggregation"] == agg.THRESHOLD and "level" not in sub:
            yield Diagnostic(
                "THRESHOLD needs its level: THRESHOLD(DOWN 5.0, 0.2) in .modd, "
                '"level": 5.0 in JSON',
                f"/subscribers/{i}/aggregation",
            )


@check
def mavlink_sources(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """A mavlink sensor maps every variable to a message field; a generic one maps none."""
    for i, s in enumerate(doc["drone"]["sensors"]):
        mavlink = s.get("kind") == "mavlink"
        for j, v in enumerate(s["variables"]):
            ptr = f"/drone/sensors/{i}/variables/{j}"
            if mavlink and "source" not in v:
                yield Diagnostic(
                    f"variable {v['name']!r} of the mavlink sensor {s['name']!r} "
                    "needs a source: from MESSAGE.field",
                    ptr,
                )
            elif not mavlink and "source" in v:
                yield Diagnostic(
                    f"variable {v['name']!r} has a MAVLink source but sensor "
                    f"{s['name']!r} is not of kind mavlink",
                    ptr + "/source",
                )
            scale = v.get("source", {}).get("scale", 1)
            if scale != scale or scale in (float("inf"), float("-inf")) or scale == 0:
                yield Diagnostic(
                    "scale must be a finite number other than zero", ptr + "/source/scale"
                )


_SERIAL_ONLY = ("device", "droneDevice", "baud")


@check
def link_transport(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """Device and baud belong to a serial link, which needs a device; the accepted
    delay is positive; a serial frame fits the radio's packet."""
    link = doc.get("link", {})
    transport = link.get("transport", "tcp")
    if transport == "serial" and "device" not in link:
        yield Diagnostic(
            'a serial link needs the radio\'s device, e.g. device = "/dev/ttyUSB0"', "/link"
        )
    if transport != "serial":
        for key in _SERIAL_ONLY:
            if key in link:
                yield Diagnostic(
                    f"{key} is only for a serial link (this link is {transport})", f"/link/{key}"
                )
    delay = link.get("acceptedDelayS")
    if delay is not None and to_fraction(delay) <= 0:
        yield Diagnostic("the accepted delay must be greater than zero", "/link/acceptedDelayS")
    packet = link.get("maxPacket")
    if transport == "serial" and packet is not None and packet > 4096:
        yield Diagnostic(
            f"a serial frame of {packet} B is larger than any telemetry radio "
            "carries (at most 4096)",
            "/link/maxPacket",
        )


@check
def hosts_are_addresses(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """A host the schema reads as an address (a colon, or only digits and dots)
    must be one: ``999.1.1.1`` and ``1:2:3`` are neither names nor addresses."""
    well_formed = ecma_regex(definition("Host")["pattern"])
    for host, _port, ptr, _kind in _endpoints(doc):
        if not well_formed.search(host):
            continue  # the schema error names it
        if ":" in host or re.fullmatch(r"[0-9.]+", host):
            try:
                ipaddress.ip_address(host)
            except ValueError:
                yield Diagnostic(f"{host!r} is not an IP address", ptr + "/host")


def _endpoints(doc: dict[str, Any]) -> Iterator[tuple[str, int, str, str]]:
    """(host, port, pointer, kind) of every endpoint; kind is ``listener`` for
    the sockets a broker binds, else ``publishers`` or ``subscribers``."""
    for key in ("pubBroker", "subBroker"):
        ep = doc[key]["endpoint"]
        yield ep["host"], ep["port"], f"/{key}/endpoint", "listener"
    ingress = doc["pubBroker"].get("ingress", {})
    if "tcpPort" in ingress:
        host = doc["pubBroker"]["endpoint"]["host"]
        yield host, ingress["tcpPort"], "/pubBroker/ingress/tcpPort", "listener"
    for kind in ("publishers", "subscribers"):
        for i, item in enumerate(doc[kind]):
            if "endpoint" in item:
                ep = item["endpoint"]
                yield ep["host"], ep["port"], f"/{kind}/{i}/endpoint", kind


@check
def endpoints_distinct(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """Two brokers' sockets on one endpoint cannot both be bound: an error.
    The original tool allows the rest and so do we, with a warning: a
    publisher's endpoint names the machine it runs on (it connects to the
    ingress, it binds nothing), and subscribers sharing an endpoint share
    one receiving program (each delivered value names its subscriber)."""
    first: dict[tuple[str, int], tuple[str, str]] = {}
    for host, port, ptr, kind in _endpoints(doc):
        key = (host.lower(), port)
        if key not in first:
            first[key] = (ptr, kind)
            continue
        other, other_kind = first[key]
        if kind == "listener" or (other_kind == "listener" and kind == "subscribers"):
            yield Diagnostic(f"endpoint {host}:{port} is already used by {other}", ptr)
        elif kind == "subscribers" and other_kind == "subscribers":
            yield Diagnostic(
                f"endpoint {host}:{port} is shared with {other}: one program "
                "must receive both subscriptions there",
                ptr,
                "warning",
            )
        else:
            yield Diagnostic(f"endpoint {host}:{port} is also used by {other}", ptr, "warning")


@check
def unused_topics(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    published = {t for p in doc["publishers"] for t in p["topics"]}
    drone = doc["drone"]["name"]
    for i, s in enumerate(doc["drone"]["sensors"]):
        for j, v in enumerate(s["variables"]):
            if topic_name(drone, s["name"], v["name"]) not in published:
                yield Diagnostic(
                    f"no publisher publishes {s['name']}.{v['name']}; it will not be archived",
                    f"/drone/sensors/{i}/variables/{j}",
                    "warning",
                )


check(instrument_sensors)


# LoRa's bandwidths (SX127x RegModemConfig1), in Hz
_LORA_BANDWIDTHS = (7800, 10400, 15600, 20800, 31250, 41700, 62500, 125000, 250000, 500000)


@check
def radio_profile(doc: dict[str, Any]) -> Iterator[Diagnostic]:
    """The link's radio: a LoRa bandwidth, a duty cycle in (0, 1], powers
    and battery that the planner can use."""
    radio = doc.get("link", {}).get("radio")
    if not isinstance(radio, dict):
        return
    bw = radio.get("bandwidthHz")
    if isinstance(bw, int) and bw not in _LORA_BANDWIDTHS:
        yield Diagnostic(
            f"bandwidth {bw} Hz is not a LoRa bandwidth; expected one of "
            f"{', '.join(map(str, _LORA_BANDWIDTHS))}",
            "/link/radio/bandwidthHz",
        )
    for key, low, high in (
        ("dutyCycle", 0, 1),
        ("txW", 0, None),
        ("rxW", 0, None),
        ("idleW", 0, None),
        ("batteryWh", 0, None),
    ):
        if key not in radio:
            continue
        value = to_fraction(radio[key])
        open_low = key in ("dutyCycle", "batteryWh")
        if value < low or (open_low and value == low) or (high is not None and value > high):
            bound = f"in (0, {high}]" if high is not None else "> 0" if open_low else ">= 0"
            yield Diagnostic(f"{key} {radio[key]} must be {bound}", f"/link/radio/{key}")
