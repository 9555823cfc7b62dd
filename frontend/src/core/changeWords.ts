/**
 * A model diff (core/diff.ts) told in the model's words, one sentence per
 * change, the way a person reviews a deployment:
 *
 * @example
 *   describeChanges(deployed, head)
 *   // ["subscriber sub_8 added: usv.optode.oxygen AVERAGE every 5 s",
 *   //  "subscriber sub_7: period 0.25 s → 0.5 s"]
 *
 * Pure: no React, no network. Pointers come from diffModels, whose named
 * arrays are keyed by element name (/subscribers/sub_1/periodS).
 */
import { diffModels, type Change } from "./diff";
import type { ModdModel, Publisher, Sensor, Subscriber } from "./model.gen";
import { subscriptionLabel, topicLabel } from "./topicLabel";
import { unitLabel } from "./chartData";
import { topicName } from "./ids";

export interface ChangeSentence {
  op: Change["op"];
  /** The element the sentence is about, e.g. "subscriber sub_8". */
  element: string;
  text: string;
  pointer: string;
}

const FIELD_WORDS: Record<string, string> = {
  periodS: "period", aggregation: "aggregation", topic: "topic", topics: "topics", unit: "unit", type: "type",
  host: "host", port: "port", logPath: "log path", configPath: "config path", description: "description",
  transport: "transport", rateBps: "rate (B/s)", maxPacket: "max packet", acceptedDelayS: "accepted delay",
};

const seconds = (p: unknown) => `${String(p)} s`;

function fieldValue(field: string, v: unknown): string {
  if (v === undefined || v === null) return "none";
  if (field === "periodS" || (field.endsWith("S") && typeof v === "string" && /^\d/.test(v))) return seconds(v);
  if (Array.isArray(v)) return v.map(String).join(", ");
  if (typeof v === "object") {
    const o = v as Record<string, unknown>;
    if ("host" in o && "port" in o) return `${String(o.host)}:${String(o.port)}`;
    return JSON.stringify(v);
  }
  return String(v);
}

/** The models a sentence takes units from (core/topicLabel): the newer first. */
type Models = ReadonlyArray<ModdModel | undefined>;

export function subscriberWords(s: Subscriber, models: Models = []): string {
  return subscriptionLabel(models, s);
}

function publisherWords(p: Publisher, models: Models): string {
  return `every ${seconds(p.periodS)}, ${p.topics.length} topic(s): ${p.topics.map((t) => topicLabel(models, t)).join(", ")}`;
}

function sensorWords(s: Sensor, models: Models): string {
  const drone = models.find((m) => m)?.drone.name;
  return s.variables.map((v) => {
    const unit = unitLabel(v.unit);
    return drone ? topicLabel(models, topicName(drone, s.name, v.name)) : unit ? `${v.name} (${unit})` : v.name;
  }).join(", ");
}

function whole(kind: string, value: unknown, models: Models = []): string {
  if (kind === "subscriber") return subscriberWords(value as Subscriber, models);
  if (kind === "publisher") return publisherWords(value as Publisher, models);
  if (kind === "sensor") return sensorWords(value as Sensor, models);
  if (kind === "variable") return unitLabel((value as { unit?: string }).unit) || String((value as { unit?: string }).unit ?? "");
  return fieldValue("", value);
}

/** Splits a pointer into the element it names and the field path inside it. */
function locate(pointer: string): { kind: string; element: string; field: string[] } {
  const p = pointer.split("/").slice(1);
  if (p[0] === "subscribers" && p[1]) return { kind: "subscriber", element: `subscriber ${p[1]}`, field: p.slice(2) };
  if (p[0] === "publishers" && p[1]) return { kind: "publisher", element: `publisher ${p[1]}`, field: p.slice(2) };
  if (p[0] === "drone" && p[1] === "sensors" && p[2]) {
    if (p[3] === "variables" && p[4]) return { kind: "variable", element: `variable ${p[2]}.${p[4]}`, field: p.slice(5) };
    return { kind: "sensor", element: `sensor ${p[2]}`, field: p.slice(3) };
  }
  if (p[0] === "drone") return { kind: "drone", element: "drone", field: p.slice(1) };
  if (p[0] === "pubBroker") return { kind: "broker", element: "PubBroker", field: p.slice(1) };
  if (p[0] === "subBroker") return { kind: "broker", element: "SubBroker", field: p.slice(1) };
  if (p[0] === "link") return { kind: "link", element: "link", field: p.slice(1) };
  return { kind: "model", element: p[0] ?? "model", field: p.slice(1) };
}

/**
 * Names the field a pointer designates in the model's words, and shows a
 * value of it, for views that list fields one by one (the merge view).
 *
 * @example
 *   fieldInWords("/subscribers/sub_7/periodS")   // "subscriber sub_7: period"
 *   valueInWords("/subscribers/sub_7/periodS", "5") // "5 s"
 */
export function fieldInWords(pointer: string): string {
  const { element, field } = locate(pointer);
  return field.length ? `${element}: ${field.map((f) => FIELD_WORDS[f] ?? f).join(" ")}` : element;
}

export function valueInWords(pointer: string, v: unknown): string {
  if (v === undefined) return "(removed)";
  const { kind, field } = locate(pointer);
  if (field.length === 0 && v !== null && typeof v === "object") return whole(kind, v) || fieldValue("", v);
  return fieldValue(field[field.length - 1] ?? "", v);
}

/** One sentence for one change; topics are named with their units from `models` (the newer first). */
export function sentence(c: Change, models: Models = []): ChangeSentence {
  const { kind, element, field } = locate(c.pointer);
  const name = field.map((f) => FIELD_WORDS[f] ?? f).join(" ");
  let text: string;
  if (field.length === 0 && c.op === "add") text = `${element} added${whole(kind, c.after, models) ? `: ${whole(kind, c.after, models)}` : ""}`;
  else if (field.length === 0 && c.op === "remove") text = `${element} removed (was ${whole(kind, c.before, models)})`;
  else if (field.length === 0) text = `${element}: ${fieldValue("", c.before)} → ${fieldValue("", c.after)}`;
  else if (field[0] === "topics" && Array.isArray(c.before) && Array.isArray(c.after)) {
    const before = new Set(c.before.map(String));
    const after = new Set(c.after.map(String));
    const added = [...after].filter((t) => !before.has(t));
    const removed = [...before].filter((t) => !after.has(t));
    const named = (ts: string[]) => ts.map((t) => topicLabel(models, t)).join(", ");
    text = `${element}: ${[added.length ? `publishes ${named(added)}` : "", removed.length ? `no longer ${named(removed)}` : ""]
      .filter(Boolean).join("; ") || "topics reordered"}`;
  } else {
    const last = field[field.length - 1];
    const value = (v: unknown) => (last === "topic" && typeof v === "string" && v ? topicLabel(models, v) : fieldValue(last, v));
    text = c.op === "add" ? `${element}: ${name} set to ${value(c.after)}`
      : c.op === "remove" ? `${element}: ${name} ${value(c.before)} removed`
        : `${element}: ${name} ${value(c.before)} → ${value(c.after)}`;
  }
  return { op: c.op, element, text, pointer: c.pointer };
}

const ORDER: Record<string, number> = { drone: 0, sensor: 1, variable: 1, PubBroker: 2, SubBroker: 2, link: 2, publisher: 3, subscriber: 4 };
const rank = (s: ChangeSentence) => ORDER[s.element.split(" ")[0]] ?? 5;

/** Every semantic change from `before` to `after` (layout ignored), in words, grouped by kind of element. */
export function describeChanges(before: ModdModel | Record<string, never>, after: ModdModel): ChangeSentence[] {
  // Nothing deployed yet: compare with an empty model of the same drone, so
  // each element reads as one "added" line rather than one JSON blob.
  const base = "drone" in before ? before : {
    schemaVersion: after.schemaVersion, drone: { name: after.drone.name, sensors: [] },
    publishers: [], subscribers: [],
  };
  const changes = diffModels(base, after);
  const models = [after, "drone" in before ? (before as ModdModel) : undefined];
  return changes.map((c) => sentence(c, models)).sort((a, b) => rank(a) - rank(b) || a.element.localeCompare(b.element, undefined, { numeric: true }));
}
