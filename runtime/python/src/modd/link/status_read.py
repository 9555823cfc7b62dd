"""STATUS as the SubBroker reads it: never a reason to drop the link, and
nothing out of range forwarded (docs/protocol.md, "Instruments' health").

The PubBroker brings every health field into range at its ingress; a STATUS
from an older or faulty PubBroker is read all the same. What cannot be read
is left out and named, field by field: a counter or health field beyond
2^53 − 1 (not exact in a double, so not in a browser), ``state`` beyond 2,
``last_value_ms`` after 2100, an instrument whose name is not printable
UTF-8, and a list cut short (the instruments read before the cut are kept).

>>> st, problems = read_status(bytes([2, 5, 7]))
>>> st.counters, problems
((5, 7), [])
>>> checked_counters(Status((5, 1 << 60)))[0]
{'uptime_s': 5}
"""

from __future__ import annotations

import unicodedata

from modd_contracts.link_wire_gen import (
    MAX_HEALTH_COUNT,
    MAX_HEALTH_FIELDS,
    MAX_HEALTH_NAME,
    MAX_HEALTH_SENSORS,
    MAX_LAST_VALUE_MS,
)

from modd.link.codec import Reader
from modd.link.frames import (
    HEALTH_FIELDS,
    HEALTH_STATES,
    STATUS_FIELDS,
    ProtocolError,
    SensorHealth,
    Status,
)

_STATE = HEALTH_FIELDS.index("state")
_LAST_VALUE = HEALTH_FIELDS.index("last_value_ms")


def read_status(body: bytes) -> tuple[Status, list[str]]:
    """The counters and instruments of a STATUS body, as far as they read."""
    r = Reader(body)
    counters: list[int] = []
    problems: list[str] = []
    sensors: list[SensorHealth] = []
    try:
        n = r.varint()
        for _ in range(n):
            counters.append(r.varint())
        if r.remaining():
            _read_sensors(r, sensors, problems)
        r.end()
    except ProtocolError as e:
        problems.append(f"STATUS read as far as it goes: {e}")
    return Status(tuple(counters), tuple(sensors)), problems


def _read_sensors(r: Reader, into: list[SensorHealth], problems: list[str]) -> None:
    n = r.varint()
    if n > MAX_HEALTH_SENSORS:
        raise r.fail(f"more than {MAX_HEALTH_SENSORS} sensors' health")
    for _ in range(n):
        size = r.varint()
        if size > MAX_HEALTH_NAME:
            raise r.fail(f"string longer than {MAX_HEALTH_NAME}")
        raw = r.take(size)
        k = r.varint()
        if k > MAX_HEALTH_FIELDS:
            raise r.fail(f"more than {MAX_HEALTH_FIELDS} health fields")
        fields = tuple(r.varint() for _ in range(k))
        try:
            into.append(SensorHealth(raw.decode(), fields))
        except UnicodeDecodeError:
            problems.append(f"STATUS instrument {raw!r}: name not UTF-8, left out")


def printable(name: str) -> bool:
    """No control, format (bidirectional overrides) or separator character but spaces."""
    return bool(name) and all(c == " " or unicodedata.category(c)[0] not in "CZ" for c in name)


def checked_counters(status: Status) -> tuple[dict[str, int], list[str]]:
    """The PubBroker's counters by name, those beyond 2^53 − 1 left out."""
    out: dict[str, int] = {}
    problems: list[str] = []
    for i, v in enumerate(status.counters):
        name = STATUS_FIELDS[i] if i < len(STATUS_FIELDS) else f"field_{i}"
        if v > MAX_HEALTH_COUNT:
            problems.append(f"STATUS counter {name} = {v} is beyond 2^53 - 1: left out")
        else:
            out[name] = v
    return out, problems


def _field_ok(i: int, v: int) -> bool:
    if i == _STATE:
        return v < len(HEALTH_STATES)
    if i == _LAST_VALUE:
        return v <= MAX_LAST_VALUE_MS
    return v <= MAX_HEALTH_COUNT


def checked_sensors(
    sensors: tuple[SensorHealth, ...],
) -> tuple[dict[str, dict[str, int]], list[str]]:
    """Instruments' health by name, each bad field (or unprintable name) left out."""
    out: dict[str, dict[str, int]] = {}
    problems: list[str] = []
    for s in sensors:
        if not printable(s.name):
            problems.append(f"STATUS instrument {s.name!r}: name not printable, left out")
            continue
        doc = s.as_dict()
        for i, (key, v) in enumerate(list(doc.items())):
            if not _field_ok(i, v):
                problems.append(f"STATUS instrument {s.name!r}: {key} = {v} out of range, left out")
                del doc[key]
        out[s.name] = doc
    return out, problems
