// Generated from metamodel/modd.schema.json by `python -m modd_model.typegen`. Do not edit.

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

/** Physical unit of a measured variable: one of the paper's units, or a free-form unit string (e.g. "mS/cm"). */
export type Unit = KnownUnit | string;

/** The units of the paper's reference implementation. */
export type KnownUnit = "METER" | "METER_PER_SECOND" | "METER_PER_SECOND_SQUARED" | "DEGREE_CELSIUS" | "RADIAN" | "RADIAN_PER_SECOND" | "BAR" | "LITER" | "GRAM" | "NONE";
export const KnownUnitValues = ["METER", "METER_PER_SECOND", "METER_PER_SECOND_SQUARED", "DEGREE_CELSIUS", "RADIAN", "RADIAN_PER_SECOND", "BAR", "LITER", "GRAM", "NONE"] as const;

/** Type of the samples of a measured variable, as published and archived. */
export type ValueType = "float32" | "float64" | "int" | "bool";
export const ValueTypeValues = ["float32", "float64", "int", "bool"] as const;

/** How the samples of one period are reduced to what the subscriber receives. ALL sends every raw sample of the period. */
export type Aggregation = "MIN" | "MAX" | "AVERAGE" | "FIRST" | "LAST" | "ALL" | "COUNT" | "SUM";
export const AggregationValues = ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM"] as const;

/** The platform (surface, aerial or underwater drone) and the sensors it carries. */
export interface Drone {
  /** Name of the drone; the first part of every topic name and of the zenoh keys. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** Sensors on board (at most 1,000). */
  sensors: Sensor[];
}

/** A sensor on board; each of its measured variables is a topic. */
export interface Sensor {
  /** Name of the sensor, unique on the drone. */
  name: Name;
  /** Free text shown in the workbench. */
  description?: Text;
  /** How the sensor is read: generic (a driver publishes through a publisher client) or mavlink (the MAVLink bridge publishes fields of an autopilot's messages, mapped per variable). generic when absent. */
  kind?: "generic" | "mavlink";
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
  /** What the SubBroker fills by itself from the drone's archive after a link outage: off (nothing; a backfill can still be asked for), gaps (the windows missed since the last connection) or mission (every window missed since the running config began). */
  backfill?: "off" | "gaps" | "mission";
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
