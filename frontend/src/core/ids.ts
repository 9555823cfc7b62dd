/**
 * Diagram element ids: one stable id per model element, used as xyflow node
 * ids and as keys of `model.layout.nodes`.
 *
 * Topics are keyed by `sensor.variable` (not by the drone name) so that
 * renaming the drone keeps the layout.
 *
 * @example
 *   sensorId("gps")          // "sensor:gps"
 *   topicId("gps", "lat")    // "topic:gps.lat"
 *   parseId("pub:pub_1")     // { kind: "publisher", name: "pub_1" }
 */

export type ElementKind =
  | "drone"
  | "sensor"
  | "topic"
  | "pubBroker"
  | "subBroker"
  | "link"
  | "publisher"
  | "subscriber";

export const DRONE_ID = "drone";
export const PUB_BROKER_ID = "pubBroker";
export const SUB_BROKER_ID = "subBroker";
/** The link is drawn as the edge PubBroker → SubBroker; selecting it edits `model.link`. */
export const LINK_ID = "link";

export const sensorId = (sensor: string): string => `sensor:${sensor}`;
export const topicId = (sensor: string, variable: string): string => `topic:${sensor}.${variable}`;
export const publisherId = (name: string): string => `pub:${name}`;
export const subscriberId = (name: string): string => `sub:${name}`;

export interface ParsedId {
  kind: ElementKind;
  /** Element name; for topics `sensor.variable`. Empty for singletons. */
  name: string;
  sensor?: string;
  variable?: string;
}

/** Parses an element id; returns null for anything that is not one. */
export function parseId(id: string): ParsedId | null {
  if (id === DRONE_ID) return { kind: "drone", name: "" };
  if (id === PUB_BROKER_ID) return { kind: "pubBroker", name: "" };
  if (id === SUB_BROKER_ID) return { kind: "subBroker", name: "" };
  if (id === LINK_ID) return { kind: "link", name: "" };
  const colon = id.indexOf(":");
  if (colon < 0) return null;
  const prefix = id.slice(0, colon);
  const rest = id.slice(colon + 1);
  if (!rest) return null;
  switch (prefix) {
    case "sensor":
      return { kind: "sensor", name: rest, sensor: rest };
    case "topic": {
      const dot = rest.indexOf(".");
      if (dot <= 0 || dot === rest.length - 1) return null;
      return { kind: "topic", name: rest, sensor: rest.slice(0, dot), variable: rest.slice(dot + 1) };
    }
    case "pub":
      return { kind: "publisher", name: rest };
    case "sub":
      return { kind: "subscriber", name: rest };
    default:
      return null;
  }
}

/** Fully qualified topic name `drone.sensor.variable`. */
export const topicName = (drone: string, sensor: string, variable: string): string =>
  `${drone}.${sensor}.${variable}`;

/** Splits `drone.sensor.variable`; null when it does not have three parts. */
export function splitTopicName(name: string): { drone: string; sensor: string; variable: string } | null {
  const parts = name.split(".");
  if (parts.length !== 3 || parts.some((p) => p === "")) return null;
  return { drone: parts[0], sensor: parts[1], variable: parts[2] };
}
