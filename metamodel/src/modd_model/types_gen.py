"""Generated from metamodel/modd.schema.json by `python -m modd_contracts.typegen`. Do not edit."""

from __future__ import annotations

from typing import Literal, NotRequired, TypedDict


Name = str
TopicName = str
Decimal = str
Period = Decimal
Host = str
Text = str
Path = str
KnownUnit = Literal["METER", "METER_PER_SECOND", "METER_PER_SECOND_SQUARED", "DEGREE_CELSIUS", "RADIAN", "RADIAN_PER_SECOND", "BAR", "LITER", "GRAM", "NONE"]
ValueType = Literal["float32", "float64", "int", "bool"]
Aggregation = Literal["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM", "MEDIAN", "STDDEV", "RANGE", "PERCENTILE", "ON_CHANGE", "THRESHOLD"]
Comparison = Literal["=", "!=", "<", "<=", ">", ">="]
ConditionValue = str
Unit = KnownUnit | str


class ModdModel(TypedDict):
    """A MoDD mission: the drone with its sensors and measured variables (the topics), the on-board PubBroker and the base-station SubBroker, the link between them, the publishers that feed the PubBroker and the subscribers that receive aggregated values. The one source of truth for what a model is: the Python and TypeScript types are generated from this file."""

    schemaVersion: Literal["1.0"]
    drone: Drone
    pubBroker: PubBroker
    subBroker: SubBroker
    link: NotRequired[Link]
    publishers: list[Publisher]
    subscribers: list[Subscriber]
    campaign: NotRequired[Campaign]
    layout: NotRequired[Layout]


class Endpoint(TypedDict):
    """A network endpoint: host (an IP address or host name) and TCP port."""

    host: Host
    port: int


class Drone(TypedDict):
    """The platform (surface, aerial or underwater drone) and the sensors it carries."""

    name: Name
    description: NotRequired[Text]
    sensors: list[Sensor]
    position: NotRequired[PlatformPosition]


class Sensor(TypedDict):
    """A sensor on board; each of its measured variables is a topic."""

    name: Name
    description: NotRequired[Text]
    kind: NotRequired[Literal["generic", "mavlink", "nmea", "ascii", "modbus"]]
    device: NotRequired[SerialDevice]
    line: NotRequired[AsciiLine]
    clock: NotRequired[Literal["receive", "instrument"]]
    checksum: NotRequired[Literal["required", "optional"]]
    fix: NotRequired[Literal["gnss", "any", "differential", "rtk", "rtkFixed"]]
    variables: list[MeasuredVariable]


class MeasuredVariable(TypedDict):
    """A measured variable, i.e. a topic named drone.sensor.variable."""

    name: Name
    unit: Unit
    type: NotRequired[ValueType]
    description: NotRequired[Text]
    source: NotRequired[MavlinkField]
    nmea: NotRequired[NmeaField]
    ascii: NotRequired[AsciiField]
    modbus: NotRequired[ModbusRegister]
    standardName: NotRequired[str]
    longName: NotRequired[str]
    validMin: NotRequired[float]
    validMax: NotRequired[float]
    resolution: NotRequired[float]


class PlatformPosition(TypedDict):
    """Which topics give the platform's position, for datasets (modd dataset interpolates it to every sample). When absent, the MAVLink autopilot's GLOBAL_POSITION_INT lat, lon and alt are used if the model maps them."""

    latitude: TopicName
    longitude: TopicName
    altitude: NotRequired[TopicName]
    maxGapS: NotRequired[Decimal]


class MavlinkField(TypedDict):
    """A field of a MAVLink message, converted to the variable's unit as value = raw * scale + offset."""

    message: str
    field: Name
    scale: NotRequired[float]
    offset: NotRequired[float]


class SerialDevice(TypedDict):
    """A serial device an instrument is read from (RS-232, RS-485 adapter, USB serial)."""

    path: Path
    baud: NotRequired[int]
    parity: NotRequired[Literal["none", "even", "odd"]]
    stopBits: NotRequired[int]


class AsciiLine(TypedDict):
    """How an ascii instrument writes its lines: columns split by a separator, key=value pairs, or the named groups of a regular expression."""

    separator: NotRequired[str]
    terminator: NotRequired[Literal["crlf", "lf", "cr"]]
    startCommand: NotRequired[str]
    pattern: NotRequired[str]


class NmeaField(TypedDict):
    """A field of an NMEA 0183 sentence, talker-agnostic (GPGGA, GNGGA and GLGGA are all GGA), converted as value = raw * scale + offset. Latitude and longitude fields are signed decimal degrees (their N/S/E/W field applied)."""

    sentence: Literal["GGA", "GNS", "GLL", "RMC", "VTG", "GSA", "GST", "ZDA", "DBT", "DPT", "MTW", "MWV", "HDG", "HDT", "MDA", "XDR"]
    field: Name
    scale: NotRequired[float]
    offset: NotRequired[float]
    where: NotRequired[NmeaCondition]


class AsciiField(TypedDict):
    """Where a value is in an ascii instrument's line (exactly one of column and key), converted as value = raw * scale + offset."""

    column: NotRequired[int]
    key: NotRequired[str]
    scale: NotRequired[float]
    offset: NotRequired[float]
    where: NotRequired[AsciiCondition]


class NmeaCondition(TypedDict):
    """A condition on another field of the same NMEA sentence: field op value."""

    field: Name
    op: NotRequired[Comparison]
    value: ConditionValue


class AsciiCondition(TypedDict):
    """A condition on another column or key of the same ascii line (exactly one of column and key): column op value."""

    column: NotRequired[int]
    key: NotRequired[str]
    op: NotRequired[Comparison]
    value: ConditionValue


class ModbusRegister(TypedDict):
    """A Modbus RTU register (or pair) read at the sensor's publisher period, converted as value = raw * scale + offset."""

    unit: NotRequired[int]
    register: int
    table: NotRequired[Literal["holding", "input"]]
    type: NotRequired[Literal["int16", "uint16", "int32", "uint32", "float32"]]
    wordOrder: NotRequired[Literal["big", "little"]]
    scale: NotRequired[float]
    offset: NotRequired[float]


class PubBroker(TypedDict):
    """The on-board broker: archives every sample and sends scheduled aggregates over the link."""

    name: NotRequired[Name]
    endpoint: Endpoint
    logPath: Path
    ingress: NotRequired[Ingress]


class Ingress(TypedDict):
    """Where publishers on board connect to the PubBroker, kept apart from the link endpoint."""

    unixSocket: NotRequired[Path]
    tcpPort: NotRequired[int]


class SubBroker(TypedDict):
    """The base-station broker: receives scheduled frames and fans values out to subscribers."""

    name: NotRequired[Name]
    endpoint: Endpoint
    configPath: Path


class Link(TypedDict):
    """The drone link between the PubBroker and the SubBroker, and the constants of the buffer-size planner."""

    transport: NotRequired[Literal["tcp", "udp", "serial"]]
    device: NotRequired[str]
    droneDevice: NotRequired[str]
    baud: NotRequired[int]
    rateBps: NotRequired[int]
    maxPacket: NotRequired[int]
    acceptedDelayS: NotRequired[Decimal]
    keyRef: NotRequired[str]
    expectedRttS: NotRequired[Decimal]
    maxBuffer: NotRequired[int]
    pingS: NotRequired[Decimal]
    alpha: NotRequired[Decimal]
    beta: NotRequired[Decimal]
    radio: NotRequired[Radio]


class Radio(TypedDict):
    """The drone's radio, for the planner's air time, duty cycle and energy per hour (docs/planning.md, "Radio profiles"). Absent settings take the kind's datasheet defaults."""

    kind: Literal["sik", "wifi", "lora"]
    airRateBps: NotRequired[int]
    ecc: NotRequired[bool]
    spreadingFactor: NotRequired[int]
    bandwidthHz: NotRequired[int]
    codingRate: NotRequired[int]
    preamble: NotRequired[int]
    explicitHeader: NotRequired[bool]
    crc: NotRequired[bool]
    lowDataRate: NotRequired[bool]
    maxPayload: NotRequired[int]
    dutyCycle: NotRequired[Decimal]
    txW: NotRequired[Decimal]
    rxW: NotRequired[Decimal]
    idleW: NotRequired[Decimal]
    batteryWh: NotRequired[Decimal]


class Publisher(TypedDict):
    """A process on board (a sensor driver) that publishes some measured variables every period."""

    name: Name
    endpoint: NotRequired[Endpoint]
    periodS: Period
    topics: list[TopicName]


class Subscriber(TypedDict):
    """A consumer on the base station: one topic, every period, aggregated."""

    name: Name
    endpoint: NotRequired[Endpoint]
    topic: TopicName
    periodS: Period
    aggregation: Aggregation
    percentile: NotRequired[float]
    deadband: NotRequired[float]
    deadbandPercent: NotRequired[float]
    level: NotRequired[float]
    hysteresis: NotRequired[float]
    crossing: NotRequired[Literal["up", "down", "both"]]
    maxEvents: NotRequired[int]
    alert: NotRequired[list[Literal["designer", "integrator", "scientist", "operator"]]]
    resolution: NotRequired[float]
    backfill: NotRequired[Literal["off", "gaps", "mission"]]


class Campaign(TypedDict):
    """Several vehicles flying one mission model. Each vehicle is a drone named after it: its topics are the mission's with the vehicle's name in place of the mission drone's; its sensors' devices, its link and its brokers' endpoints are the mission's unless the vehicle says otherwise. Vehicles on one radio channel share its rate and duty cycle: the planner checks their sum."""

    name: Name
    description: NotRequired[Text]
    channels: NotRequired[list[Channel]]
    vehicles: list[Vehicle]


class Channel(TypedDict):
    """A radio channel several vehicles transmit on: their links share its rate and its duty cycle."""

    name: Name
    rateBps: NotRequired[int]
    dutyCycle: NotRequired[Decimal]


class Vehicle(TypedDict):
    """One vehicle of a campaign: a drone made from the mission model with these settings."""

    name: Name
    description: NotRequired[Text]
    channel: NotRequired[Name]
    pubBroker: NotRequired[VehicleBroker]
    subBroker: NotRequired[VehicleBroker]
    devices: NotRequired[list[DeviceOverride]]
    link: NotRequired[Link]


class VehicleBroker(TypedDict):
    """A vehicle's broker: its endpoint, and its directory when not the mission's."""

    endpoint: Endpoint
    path: NotRequired[Path]


class DeviceOverride(TypedDict):
    """The device a sensor of the mission model reads on this vehicle."""

    sensor: Name
    path: Path


class Layout(TypedDict):
    """Diagram layout, kept apart from the semantic model: node positions by node id."""

    nodes: NotRequired[dict[str, Position]]


class Position(TypedDict):
    """Top-left corner of a node on the canvas."""

    x: float
    y: float


__all__ = ["ModdModel", "Name", "TopicName", "Decimal", "Period", "Endpoint", "Host", "Text", "Path", "Unit", "KnownUnit", "ValueType", "Aggregation", "Drone", "Sensor", "MeasuredVariable", "PlatformPosition", "MavlinkField", "SerialDevice", "AsciiLine", "NmeaField", "AsciiField", "NmeaCondition", "AsciiCondition", "Comparison", "ConditionValue", "ModbusRegister", "PubBroker", "Ingress", "SubBroker", "Link", "Radio", "Publisher", "Subscriber", "Campaign", "Channel", "Vehicle", "VehicleBroker", "DeviceOverride", "Layout", "Position"]
