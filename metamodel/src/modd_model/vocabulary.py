"""Closed word lists of the metamodel, read from the schema."""

from __future__ import annotations

from .schema import definition, load_schema

SCHEMA_VERSION: str = load_schema()["properties"]["schemaVersion"]["const"]
KNOWN_UNITS: tuple[str, ...] = tuple(definition("KnownUnit")["enum"])
VALUE_TYPES: tuple[str, ...] = tuple(definition("ValueType")["enum"])
AGGREGATIONS: tuple[str, ...] = tuple(definition("Aggregation")["enum"])
SENSOR_KINDS: tuple[str, ...] = tuple(definition("Sensor")["properties"]["kind"]["enum"])
BACKFILL_POLICIES: tuple[str, ...] = tuple(
    definition("Subscriber")["properties"]["backfill"]["enum"]
)
#: NMEA 0183 sentence type -> {field name: what it holds}, fields in order (field 1 first).
NMEA_SENTENCES: dict[str, dict[str, str]] = definition("NmeaField")["x-sentences"]
#: The roles whose views may show an alert (a THRESHOLD subscriber's ``alert``).
ALERT_ROLES: tuple[str, ...] = tuple(
    definition("Subscriber")["properties"]["alert"]["items"]["enum"]
)
