// Generated from metamodel/modd.schema.json by `python -m modd_contracts.typegen`. Do not edit.

/** A MoDD mission: the drone with its sensors and measured variables (the topics), the on-board PubBroker and the base-station SubBroker, the link between them, the publishers that feed the PubBroker and the subscribers that receive aggregated values. The one source of truth for what a model is: the Python and TypeScript types are generated from this file. */
export interface ModdModel {
  /** Version of this schema the model was written for. Tools refuse models of a later major version. */
  schemaVersion: "1.0";
  /** The drone and its sensors. */
  drone: Drone;
  /** The on-board broker. */
  pubBroker: PubBroker;
  /** The base-station broker. */
  subBroker: SubBroker;
  /** Link settings and planner constants; the paper's defaults when absent. */
  link?: Link;
  /** Processes on board that publish measured variables to the PubBroker (at most 1,000). */
  publishers: Publisher[];
  /** Base-station consumers, each asking for one topic every period, aggregated (at most 50,000). */
  subscribers: Subscriber[];
  /** A campaign: this model is the mission model of several vehicles, each its own drone (identity, keys, link and configuration) made from it with its own settings (modd_model.campaign expands it to one model per vehicle). Absent: the model is one drone, as before. */
  campaign?: Campaign;
  /** Diagram layout of the workbench (not part of the .modd text). */
  layout?: Layout;
}

/** An identifier: a letter or underscore, then letters, digits or underscores. */
export type Name = string;

/** Fully qualified name of a measured variable: drone.sensor.variable. */
export type TopicName = string;

/** An exact decimal number written as a string (e.g. "0.25"), so that periods keep exact rational arithmetic end to end; at most 24 characters. */
export type Decimal = string;

/** A period in seconds, as an exact decimal string, resolved to the microsecond. */
export type Period = Decimal;

/** A network endpoint: host (an IP address or host name) and TCP port. */
export interface Endpoint {
  /** IP address or host name. */
  host: Host;
  /** TCP port. */
  port: number;
}

/** A host name (letters, digits and hyphens in dot-separated labels of at most 63 characters), an IPv4 address, or an IPv6 address (hex digits, colons and dots; checked as an address). */
export type Host = string;

/** Free text: printable characters, line breaks and tabs; no other control characters and no invisible or bidirectional formatting characters. */
export type Text = string;

/** A file or directory path: printable characters only (no control characters, no invisible or bidirectional formatting characters). */
export type Path = string;

/** Physical unit of a measured variable: a UDUNITS-2 unit string, as CF requires (m s-2, degC, degree_north, 1, mS/cm; symbols people type such as m/s² are accepted and read as UDUNITS; PSU reads as 1), or one of the paper's unit names, read as its UDUNITS equivalent (KnownUnit x-udunits). Validation checks it with UDUNITS-2. */
export type Unit = KnownUnit | string;

/** The units of the paper's reference implementation, kept so that its models load; each reads as the UDUNITS-2 unit of x-udunits. */
export type KnownUnit = "METER" | "METER_PER_SECOND" | "METER_PER_SECOND_SQUARED" | "DEGREE_CELSIUS" | "RADIAN" | "RADIAN_PER_SECOND" | "BAR" | "LITER" | "GRAM" | "NONE";
export const KnownUnitValues = ["METER", "METER_PER_SECOND", "METER_PER_SECOND_SQUARED", "DEGREE_CELSIUS", "RADIAN", "RADIAN_PER_SECOND", "BAR", "LITER", "GRAM", "NONE"] as const;

/** Type of the samples of a measured variable, as published and archived. */
export type ValueType = "float32" | "float64" | "int" | "bool";
export const ValueTypeValues = ["float32", "float64", "int", "bool"] as const;

/** How the samples of one period are reduced to what the subscriber receives. ALL sends every raw sample of the period. */
export type Aggregation = "MIN" | "MAX" | "AVERAGE" | "FIRST" | "LAST" | "ALL" | "COUNT" | "SUM" | "MEDIAN" | "STDDEV" | "RANGE" | "PERCENTILE" | "ON_CHANGE" | "THRESHOLD";
export const AggregationValues = ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM", "MEDIAN", "STDDEV", "RANGE", "PERCENTILE", "ON_CHANGE", "THRESHOLD"] as const;

/** The platform (surface, aerial or underwater drone) and the sensors it carries. */
export interface Drone {
  /** Name of the drone; the first part of every topic name and of the zenoh keys. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** Sensors on board (at most 1,000). */
  sensors: Sensor[];
  /** Which topics are the platform's position (datasets). */
  position?: PlatformPosition;
}

/** A sensor on board; each of its measured variables is a topic. */
export interface Sensor {
  /** Name of the sensor, unique on the drone. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** How the sensor is read: generic (a driver publishes through a publisher client), mavlink (the MAVLink bridge publishes fields of an autopilot's messages, mapped per variable), or an instrument read by modd-sensors on a serial device with no driver code: nmea (NMEA 0183 sentences), ascii (one text line per sample) or modbus (Modbus RTU registers, polled). generic when absent. */
  kind?: "generic" | "mavlink" | "nmea" | "ascii" | "modbus";
  /** For an nmea, ascii or modbus sensor: the serial device it is read from. */
  device?: SerialDevice;
  /** For an ascii sensor: how its lines are written. */
  line?: AsciiLine;
  /** For an nmea sensor: which clock stamps its samples: receive (the reader's clock when the line arrives) or instrument (the sentence's own UTC time of day on the date of the last valid RMC or ZDA, across midnight; a sentence without a time takes its fix epoch's; samples held until the instrument states a date; two-digit years and GPS week rollovers resolved against the computer's clock: docs/sensors.md, "Instrument clock"). receive when absent. */
  clock?: "receive" | "instrument";
  /** For an nmea sensor: required (a line without *hh is refused) or optional (for an instrument that sends none: a line without one is read when each field has its sentence's shape; a line with one is still checked). required when absent. */
  checksum?: "required" | "optional";
  /** For an nmea sensor: which fixes give values, by GGA's fix quality and the mode of RMC, GLL, VTG and GNS: gnss (measured: autonomous, differential, precise, RTK), any (also dead reckoning), differential (DGPS, SBAS, precise, RTK), rtk (RTK fixed or float: quality 4 or 5, mode R or F) or rtkFixed (quality 4, mode R). Sentences that say no fix never give values (docs/sensors.md, "Validity"). gnss when absent. */
  fix?: "gnss" | "any" | "differential" | "rtk" | "rtkFixed";
  /** What the sensor measures (1 to 256 variables). */
  variables: MeasuredVariable[];
}

/** A measured variable, i.e. a topic named drone.sensor.variable. */
export interface MeasuredVariable {
  /** Name of the variable, unique within its sensor. */
  name: Name;
  /** Physical unit of the samples. */
  unit: Unit;
  /** Type of the samples; float32 when absent. */
  type?: ValueType;
  /** Free text shown in the workbench. */
  description?: Text;
  /** For a variable of a mavlink sensor: the MAVLink message field it is read from. */
  source?: MavlinkField;
  /** For a variable of an nmea sensor: the sentence field it is read from. */
  nmea?: NmeaField;
  /** For a variable of an ascii sensor: the column or key of the line it is read from. */
  ascii?: AsciiField;
  /** For a variable of a modbus sensor: the register it is read from. */
  modbus?: ModbusRegister;
  /** CF standard name (e.g. sea_water_temperature), checked against the CF standard-name table shipped with MoDD; the unit must convert to the name's canonical unit. Written as standard_name in datasets. */
  standardName?: string;
  /** A human-readable name for datasets (CF long_name). */
  longName?: string;
  /** Smallest valid value, in the variable's unit (CF valid_min); a dataset keeps samples outside the range, and says the range. */
  validMin?: number;
  /** Largest valid value, in the variable's unit (CF valid_max). */
  validMax?: number;
  /** The precision needed live, in the variable's unit (e.g. 0.01): the link sends its float values as whole steps of this size, within half a step (docs/protocol.md, "Quantised values"); validMin and validMax, when given, bound the steps. The archive stays exact. Unquantised when absent. */
  resolution?: number;
}

/** Which topics give the platform's position, for datasets (modd dataset interpolates it to every sample). When absent, the MAVLink autopilot's GLOBAL_POSITION_INT lat, lon and alt are used if the model maps them. */
export interface PlatformPosition {
  /** The topic of the latitude (a unit convertible to degree_north). */
  latitude: TopicName;
  /** The topic of the longitude (a unit convertible to degree_east). */
  longitude: TopicName;
  /** The topic of the altitude (a unit convertible to m, positive up). */
  altitude?: TopicName;
  /** Longest gap between two fixes, in seconds, across which the position is interpolated; a sample in a longer gap gets no position (a fill value). */
  maxGapS?: Decimal;
}

/** A field of a MAVLink message, converted to the variable's unit as value = raw * scale + offset. */
export interface MavlinkField {
  /** MAVLink message name, e.g. GLOBAL_POSITION_INT. */
  message: string;
  /** Field of the message, e.g. lat. */
  field: Name;
  /** Factor applied to the raw field (e.g. 1e-7 for degE7 to degrees). */
  scale?: number;
  /** Added after scaling. */
  offset?: number;
}

/** A serial device an instrument is read from (RS-232, RS-485 adapter, USB serial). */
export interface SerialDevice {
  /** The character device, e.g. /dev/ttyUSB0; a /dev/serial/by-id/ link keeps working when the adapter is renumbered (it is resolved at each reopen). */
  path: Path;
  /** Baud rate. */
  baud?: number;
  /** Parity bit. */
  parity?: "none" | "even" | "odd";
  /** Stop bits. */
  stopBits?: number;
}

/** How an ascii instrument writes its lines: columns split by a separator, key=value pairs, or the named groups of a regular expression. */
export interface AsciiLine {
  /** What splits columns and key=value pairs; a single space means any run of spaces or tabs. */
  separator?: string;
  /** What ends a line: crlf, lf (a line ends at LF; a CR before it is dropped) or cr. */
  terminator?: "crlf" | "lf" | "cr";
  /** Sent to the instrument (with the terminator) each time the device is opened, e.g. START. */
  startCommand?: string;
  /** A regular expression a whole line must match (Python syntax); variables read its named groups (key) or numbered groups (column). */
  pattern?: string;
}

/** A field of an NMEA 0183 sentence, talker-agnostic (GPGGA, GNGGA and GLGGA are all GGA), converted as value = raw * scale + offset. Latitude and longitude fields are signed decimal degrees (their N/S/E/W field applied). */
export interface NmeaField {
  /** Sentence type without the talker, e.g. GGA. */
  sentence: "GGA" | "GNS" | "GLL" | "RMC" | "VTG" | "GSA" | "GST" | "ZDA" | "DBT" | "DPT" | "MTW" | "MWV" | "HDG" | "HDT" | "MDA" | "XDR";
  /** A field name of the sentence (x-sentences), or fN for its N-th field (1-based). */
  field: Name;
  /** Factor applied to the field. */
  scale?: number;
  /** Added after scaling. */
  offset?: number;
  /** Read the field only from sentences where another of their fields compares so, e.g. MWV's reference is T (true wind) or R (relative), XDR's transducer id is AIRTEMP. For XDR, a condition on the quadruplet's type, value, unit or id picks the first quadruplet that meets it, and the field is read from that quadruplet. A sentence that does not meet it gives this variable nothing (counted ignored when it gives no variable anything). */
  where?: NmeaCondition;
}

/** Where a value is in an ascii instrument's line (exactly one of column and key), converted as value = raw * scale + offset. */
export interface AsciiField {
  /** Column number, 1 for the first (or group number, with a pattern). */
  column?: number;
  /** Key of a key=value pair (or group name, with a pattern). */
  key?: string;
  /** Factor applied to the value read. */
  scale?: number;
  /** Added after scaling. */
  offset?: number;
  /** Read the value only from lines where another column or key compares so, e.g. a CTD's record type in column 1 is S. A line that does not meet it gives this variable nothing (counted ignored when it gives no variable anything). */
  where?: AsciiCondition;
}

/** A condition on another field of the same NMEA sentence: field op value. */
export interface NmeaCondition {
  /** The field compared: a field name of the sentence (x-sentences) or fN for its N-th; not a time or a date. */
  field: Name;
  /** The comparison: = and != compare text exactly (a number field: as numbers); <, <=, >, >= compare numbers and need a number field. An empty field meets no condition. */
  op?: Comparison;
  /** What the field is compared with, as written: T, AIRTEMP, or a number for a number field. */
  value: ConditionValue;
}

/** A condition on another column or key of the same ascii line (exactly one of column and key): column op value. */
export interface AsciiCondition {
  /** Column number compared, 1 for the first (or group number, with a pattern). */
  column?: number;
  /** Key of the key=value pair compared (or group name, with a pattern). */
  key?: string;
  /** The comparison: = and != compare text exactly (blanks around it trimmed); <, <=, >, >= compare numbers (a line whose column is not a number does not meet it). A missing column or key meets no condition. */
  op?: Comparison;
  /** What the column is compared with, as written: S, or a number for <, <=, >, >=. */
  value: ConditionValue;
}

/** How a condition compares a field with its value. */
export type Comparison = "=" | "!=" | "<" | "<=" | ">" | ">=";
export const ComparisonValues = ["=", "!=", "<", "<=", ">", ">="] as const;

/** The text a condition compares a field with (printable, no comma, asterisk or line end: NMEA and CSV fields cannot hold them). */
export type ConditionValue = string;

/** A Modbus RTU register (or pair) read at the sensor's publisher period, converted as value = raw * scale + offset. */
export interface ModbusRegister {
  /** Unit (slave) id on the bus. */
  unit?: number;
  /** Register address (0-based, as on the wire). */
  register: number;
  /** holding (function 3) or input (function 4) registers. */
  table?: "holding" | "input";
  /** What the register holds: int16, uint16 (one register), int32, uint32, float32 (two). */
  type?: "int16" | "uint16" | "int32" | "uint32" | "float32";
  /** For two registers: big (high word first, Modbus's usual order) or little (low word first). */
  wordOrder?: "big" | "little";
  /** Factor applied to the raw number. */
  scale?: number;
  /** Added after scaling. */
  offset?: number;
}

/** The on-board broker: archives every sample and sends scheduled aggregates over the link. */
export interface PubBroker {
  /** Optional name (the reference implementation writes one). */
  name?: Name;
  /** Link endpoint: where the PubBroker listens for the SubBroker. */
  endpoint: Endpoint;
  /** Directory of the on-board archive (MCAP files). */
  logPath: Path;
  /** Where publishers connect; generated defaults when absent. */
  ingress?: Ingress;
}

/** Where publishers on board connect to the PubBroker, kept apart from the link endpoint. */
export interface Ingress {
  /** Path of the Unix socket publishers connect to. */
  unixSocket?: Path;
  /** TCP port on the PubBroker's host publishers connect to. */
  tcpPort?: number;
}

/** The base-station broker: receives scheduled frames and fans values out to subscribers. */
export interface SubBroker {
  /** Optional name (the reference implementation writes one). */
  name?: Name;
  /** Endpoint of the SubBroker on the base station. */
  endpoint: Endpoint;
  /** Directory where the SubBroker keeps its configuration. */
  configPath: Path;
}

/** The drone link between the PubBroker and the SubBroker, and the constants of the buffer-size planner. */
export interface Link {
  /** Transport of the link: tcp (a stream, today's protocol), udp (datagrams to the PubBroker's endpoint, for IP radios: long-range Wi-Fi, mesh, LTE) or serial (framed datagrams on a character device: a SiK/RFD900 telemetry radio, a UART). */
  transport?: "tcp" | "udp" | "serial";
  /** For a serial link: the character device of the radio on the base station, e.g. /dev/ttyUSB0. */
  device?: string;
  /** For a serial link: the character device of the radio on board (the PubBroker's side); the base station's device when absent. */
  droneDevice?: string;
  /** For a serial link: the baud rate of the serial port (not the radio's air rate). */
  baud?: number;
  /** Usable bytes per second of the radio, one way, on the wire (headers and framing included); the planner's link budget. No budget when absent. */
  rateBps?: number;
  /** Largest packet the radio carries, in bytes: one datagram (UDP, IP+UDP headers excluded) or one frame (serial, framing included). 1472 for udp, 252 for serial (a SiK radio) when absent. */
  maxPacket?: number;
  /** Largest delay, in seconds, the scientists accept before a value is sent: consecutive slots are packed into one datagram up to this delay and the packet size (udp, serial). */
  acceptedDelayS?: Decimal;
  /** Where the pre-shared key is read from: env:NAME (an environment variable name) or file:PATH (a path without control characters). Never the key itself. */
  keyRef?: string;
  /** Expected round-trip time of the link in seconds, until measured. */
  expectedRttS?: Decimal;
  /** MAX_BUFFER: the largest buffer size n the planner may choose (at most one million samples per topic). */
  maxBuffer?: number;
  /** PING_TIME in seconds: a subscriber's delay may not exceed 3 x PING. */
  pingS?: Decimal;
  /** Weight of the sum of deviations in the planner's objective. */
  alpha?: Decimal;
  /** Weight of the largest deviation in the planner's objective. */
  beta?: Decimal;
  /** The drone's radio (sik, wifi, lora) for the planner's air time, duty cycle and energy per hour; none when absent. */
  radio?: Radio;
}

/** The drone's radio, for the planner's air time, duty cycle and energy per hour (docs/planning.md, "Radio profiles"). Absent settings take the kind's datasheet defaults. */
export interface Radio {
  /** sik (a SiK/RFD900-class FHSS serial radio), wifi (802.11 OFDM) or lora (a LoRa modem, SX127x-class). */
  kind: "sik" | "wifi" | "lora";
  /** sik and wifi: the air data rate in bit/s (sik 64000, wifi 24000000 when absent). */
  airRateBps?: number;
  /** sik: Golay error correction on (doubles the bits on air). */
  ecc?: boolean;
  /** lora: spreading factor SF6 to SF12. */
  spreadingFactor?: number;
  /** lora: bandwidth in Hz, one of 7800, 10400, 15600, 20800, 31250, 41700, 62500, 125000, 250000, 500000. */
  bandwidthHz?: number;
  /** lora: coding rate 4/5 to 4/8, given as its denominator 5 to 8. */
  codingRate?: number;
  /** lora: programmed preamble length in symbols. */
  preamble?: number;
  /** lora: explicit header mode (implicit when false). */
  explicitHeader?: boolean;
  /** lora: payload CRC on. */
  crc?: boolean;
  /** lora: low-data-rate optimisation; when absent, on when a symbol lasts more than 16 ms (SF11 and SF12 at 125 kHz). */
  lowDataRate?: boolean;
  /** Largest radio packet payload in bytes; lora: the EU868 table per spreading factor when absent (59 B at SF10-12, 123 B at SF9, 250 B at SF7-8); sik 252. */
  maxPayload?: number;
  /** Regional duty-cycle limit: the largest share of each hour the radio may transmit (0.01: EU868's 1 % sub-band). lora: 0.01 when absent; none for sik and wifi unless given. */
  dutyCycle?: Decimal;
  /** Power drawn while transmitting, in watts (the kind's datasheet default when absent). */
  txW?: Decimal;
  /** Power drawn while receiving the base station's packets, in watts. */
  rxW?: Decimal;
  /** Power drawn between packets, in watts. */
  idleW?: Decimal;
  /** The battery energy, in watt-hours, declared for the link's share (the planner reports the radio's share of it per hour). */
  batteryWh?: Decimal;
}

/** A process on board (a sensor driver) that publishes some measured variables every period. */
export interface Publisher {
  /** Name of the publisher, unique among publishers and subscribers. */
  name: Name;
  /** Endpoint of the publisher (the paper's model gives one; publishers connect to the PubBroker's ingress). */
  endpoint?: Endpoint;
  /** Publication period in seconds. */
  periodS: Period;
  /** Topics it publishes (1 to 256). */
  topics: TopicName[];
}

/** A consumer on the base station: one topic, every period, aggregated. */
export interface Subscriber {
  /** Name of the subscriber, unique among publishers and subscribers. */
  name: Name;
  /** Where the SubBroker delivers over TCP; without it, values are delivered on zenoh only. */
  endpoint?: Endpoint;
  /** The monitored variable. */
  topic: TopicName;
  /** Subscription period in seconds: one value (or one batch, for ALL) per period. */
  periodS: Period;
  /** How the samples of each period are reduced. */
  aggregation: Aggregation;
  /** The p of a PERCENTILE subscription (numpy.percentile, linear), 0 to 100; required with PERCENTILE and only with it. */
  percentile?: number;
  /** ON_CHANGE: a sample is an event when it differs from the last event's value by more than this, in the topic's unit (absolute deadband); >= 0. ON_CHANGE takes deadband or deadbandPercent, and only it. */
  deadband?: number;
  /** ON_CHANGE: the deadband as a percentage of the last event's value (relative deadband), |x - last| > deadbandPercent / 100 * |last|; >= 0. */
  deadbandPercent?: number;
  /** THRESHOLD: the level whose crossings are events; required with THRESHOLD and only with it. */
  level?: number;
  /** THRESHOLD: the signal must pass the level by more than this to cross it (a crossing UP needs x > level + hysteresis, DOWN x < level - hysteresis); >= 0, default 0. */
  hysteresis?: number;
  /** THRESHOLD: which crossings are events: up, down or both (default both). */
  crossing?: "up" | "down" | "both";
  /** ON_CHANGE or THRESHOLD: the declared worst case, at most this many events a period (window); beyond it the newest event replaces the window's last one and is counted as coalesced. Without it the worst case is every sample of the window (from the topic's publication period). */
  maxEvents?: number;
  /** THRESHOLD only: the subscription is an alert, shown at once in the workbench (a banner with an optional sound, a mark on its chart) to these roles' views, and listed in the operator's Monitor while active. Active: from a crossing of the subscription's direction (UP: above level + hysteresis; DOWN: below level - hysteresis; BOTH: either) until the signal crosses back past the level by more than the hysteresis, or a user clears it (docs/user-guide/operator.md, "Alerts"). The drone reports an alert's crossings both ways (its stream is THRESHOLD(BOTH ...)) so that the way back is seen. */
  alert?: ("designer" | "integrator" | "scientist" | "operator")[];
  /** The precision this subscription needs live, in the topic's unit: at least the variable's resolution (coarser still); the stream is sent at the finest resolution of the subscriptions it serves, unquantised if one of them declares none. */
  resolution?: number;
  /** What the SubBroker fills by itself from the drone's archive after a link outage: off (nothing; a backfill can still be asked for), gaps (the windows missed since the last connection) or mission (every window missed since the running config began). */
  backfill?: "off" | "gaps" | "mission";
}

/** Several vehicles flying one mission model. Each vehicle is a drone named after it: its topics are the mission's with the vehicle's name in place of the mission drone's; its sensors' devices, its link and its brokers' endpoints are the mission's unless the vehicle says otherwise. Vehicles on one radio channel share its rate and duty cycle: the planner checks their sum. */
export interface Campaign {
  /** Name of the campaign. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** Radio channels shared by several vehicles (at most 100). */
  channels?: Channel[];
  /** The vehicles, each one drone of the campaign (1 to 100). */
  vehicles: Vehicle[];
}

/** A radio channel several vehicles transmit on: their links share its rate and its duty cycle. */
export interface Channel {
  /** Name of the channel, referred to by its vehicles. */
  name: Name;
  /** Usable bytes per second of the channel, shared by every vehicle on it: the sum of their links' planned bytes per second, both ways, must fit. */
  rateBps?: number;
  /** Largest share of each hour the channel may carry transmissions, all its vehicles' air time together (0.01: EU868's 1 % sub-band). */
  dutyCycle?: Decimal;
}

/** One vehicle of a campaign: a drone made from the mission model with these settings. */
export interface Vehicle {
  /** Name of the vehicle's drone: the first part of its topics and zenoh keys. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** The shared radio channel the vehicle transmits on (one of the campaign's channels). */
  channel?: Name;
  /** The vehicle's PubBroker endpoint, and archive directory (the mission's when absent). */
  pubBroker?: VehicleBroker;
  /** The vehicle's SubBroker endpoint, and configuration directory (the mission's when absent). */
  subBroker?: VehicleBroker;
  /** The vehicle's device paths, per sensor of the mission model (at most 1,000). */
  devices?: DeviceOverride[];
  /** Link settings of this vehicle over the mission's: each setting given replaces the mission's (the radio's one by one). */
  link?: Link;
}

/** A vehicle's broker: its endpoint, and its directory when not the mission's. */
export interface VehicleBroker {
  /** Endpoint of the broker. */
  endpoint: Endpoint;
  /** The PubBroker's archive directory or the SubBroker's configuration directory. */
  path?: Path;
}

/** The device a sensor of the mission model reads on this vehicle. */
export interface DeviceOverride {
  /** Name of the sensor in the mission model (one with a device). */
  sensor: Name;
  /** The vehicle's device, e.g. /dev/ttyUSB3. */
  path: Path;
}

/** Diagram layout, kept apart from the semantic model: node positions by node id. */
export interface Layout {
  /** Position of each diagram node, by node id (at most 60,000 nodes). */
  nodes?: Record<string, Position>;
}

/** Top-left corner of a node on the canvas. */
export interface Position {
  /** Horizontal position. */
  x: number;
  /** Vertical position. */
  y: number;
}
