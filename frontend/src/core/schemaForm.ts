/**
 * Inspector forms derived from the metamodel's JSON Schema: for each element
 * kind, the list of fields with their input kind, constraints and the
 * schema's description (shown as help). Nothing here is hand-written per
 * field: a property added to the schema appears in the inspector.
 *
 * Arrays of objects (a drone's sensors, a sensor's variables) are edited on
 * the canvas, not in the form, and are left out. Nested objects (endpoint,
 * ingress) are flattened into dotted fields.
 *
 * @example
 *   formFor(schema, "subscriber").map((f) => f.path.join("."))
 *   // ["name", "endpoint.host", "endpoint.port", "topic", "periodS", "aggregation"]
 */
import type { ElementKind } from "./ids";

/** The subset of JSON Schema the metamodel uses. */
export interface JsonSchema {
  $ref?: string;
  $defs?: Record<string, JsonSchema>;
  type?: string;
  description?: string;
  properties?: Record<string, JsonSchema>;
  required?: string[];
  items?: JsonSchema;
  enum?: string[];
  const?: unknown;
  anyOf?: JsonSchema[];
  examples?: string[];
  pattern?: string;
  minimum?: number;
  maximum?: number;
  minLength?: number;
  maxLength?: number;
  minItems?: number;
  default?: unknown;
}

export type InputKind =
  | "text" | "name" | "integer" | "number" | "decimal" | "enum" | "enumOrText" | "topic" | "topics"
  /** Some of a closed list (an array of an enum: a subscriber's alert roles), as checkboxes. */
  | "choices";

export interface FieldSpec {
  path: string[];
  label: string;
  description: string;
  required: boolean;
  input: InputKind;
  options?: readonly string[];
  pattern?: string;
  minimum?: number;
  maximum?: number;
  minLength?: number;
  maxLength?: number;
  minItems?: number;
  default?: unknown;
  /** What an optional choice's empty option says ("(default: tcp)" when not given). */
  emptyLabel?: string;
}

/** The $defs entry that describes each element kind. */
export const DEF_OF_KIND: Record<ElementKind, string> = {
  drone: "Drone", sensor: "Sensor", topic: "MeasuredVariable",
  pubBroker: "PubBroker", subBroker: "SubBroker", link: "Link",
  publisher: "Publisher", subscriber: "Subscriber",
};

const refName = (ref: string): string => ref.replace(/^#\/\$defs\//, "");

/** Follows $ref chains; keeps the first description met (the property's own wins). */
function resolve(root: JsonSchema, s: JsonSchema): { schema: JsonSchema; refs: string[] } {
  const refs: string[] = [];
  let cur = s;
  let guard = 0;
  while (cur.$ref && guard++ < 20) {
    const name = refName(cur.$ref);
    refs.push(name);
    const next = root.$defs?.[name];
    if (!next) throw new Error(`schema: unresolved $ref ${cur.$ref}`);
    cur = { ...next, ...stripRef(cur) };
  }
  return { schema: cur, refs };
}

function stripRef(s: JsonSchema): JsonSchema {
  const { $ref: _ignored, ...rest } = s;
  void _ignored;
  return rest;
}

function label(path: string[]): string {
  return path
    .map((p) => p.replace(/([a-z])([A-Z])/g, "$1 $2").replace(/ S$/, " (s)").toLowerCase())
    .join(" ");
}

function inputOf(root: JsonSchema, prop: JsonSchema, refs: string[], s: JsonSchema): Omit<FieldSpec, "path" | "label" | "description" | "required"> | null {
  if (refs.includes("TopicName")) return { input: "topic", pattern: s.pattern };
  if (s.type === "array") {
    const items = s.items ? resolve(root, s.items) : null;
    if (items?.refs.includes("TopicName")) return { input: "topics", minItems: s.minItems };
    if (items?.schema.enum) return { input: "choices", options: items.schema.enum, minItems: s.minItems };
    return null;
  }
  if (s.anyOf) {
    // A unit offers the symbols people type (the schema's examples: "m s-2", "degC"), not the paper's enum names.
    const options = s.examples ?? s.anyOf.map((a) => resolve(root, a).schema).find((a) => a.enum)?.enum;
    const free = s.anyOf.map((a) => resolve(root, a).schema).find((a) => !a.enum);
    return { input: "enumOrText", options, minLength: free?.minLength, maxLength: free?.maxLength };
  }
  if (s.const !== undefined) return null;
  if (s.enum) return { input: "enum", options: s.enum, default: prop.default ?? s.default };
  if (s.type === "integer") return { input: "integer", minimum: s.minimum, maximum: s.maximum, default: s.default };
  if (s.type === "number") return { input: "number", minimum: s.minimum, maximum: s.maximum, default: s.default };
  if (refs.includes("Decimal")) return { input: "decimal", pattern: s.pattern, default: s.default };
  if (refs.includes("Name")) return { input: "name", pattern: s.pattern };
  if (s.type === "string") return { input: "text", pattern: s.pattern, minLength: s.minLength, maxLength: s.maxLength };
  return null;
}

function fieldsOf(root: JsonSchema, obj: JsonSchema, prefix: string[], parentRequired: boolean): FieldSpec[] {
  const out: FieldSpec[] = [];
  for (const [key, prop] of Object.entries(obj.properties ?? {})) {
    const { schema: s, refs } = resolve(root, prop);
    const path = [...prefix, key];
    const required = parentRequired && (obj.required ?? []).includes(key);
    if (s.type === "object" && s.properties) {
      out.push(...fieldsOf(root, s, path, required));
      continue;
    }
    const input = inputOf(root, prop, refs, s);
    if (!input) continue;
    out.push({ path, label: label(path), description: prop.description ?? s.description ?? "", required, ...input });
  }
  return out;
}

/** The form fields of an element kind, in schema order. */
export function formFor(root: JsonSchema, kind: ElementKind): FieldSpec[] {
  return formForDef(root, DEF_OF_KIND[kind]);
}

/** The form fields of a $defs entry (one that is no diagram element: a campaign's vehicle), in schema order. */
export function formForDef(root: JsonSchema, defName: string): FieldSpec[] {
  const def = root.$defs?.[defName];
  if (!def) throw new Error(`schema: no $defs/${defName}`);
  return fieldsOf(root, def, [], true);
}

/** Where a variable's value comes from, per sensor kind (the variable's property). */
const SOURCE_OF_KIND: Record<string, string> = { mavlink: "source", nmea: "nmea", ascii: "ascii", modbus: "modbus" };
/** A sensor's properties that belong to some kinds only. */
const SENSOR_PART_KINDS: Record<string, readonly string[]> = {
  device: ["nmea", "ascii", "modbus"], line: ["ascii"], clock: ["nmea"], checksum: ["nmea"], fix: ["nmea"],
};

/**
 * The fields the inspector shows for an element: `formFor`, less what does
 * not apply to the sensor's kind: a variable shows only the source of its
 * sensor's kind (MAVLink field, NMEA field, ASCII column or key, Modbus
 * register); a sensor shows its serial device, line format and clock only
 * for the kinds that have them.
 *
 * @example
 *   shownFields(schema, "topic", "generic").some((f) => f.path[0] === "source") // false
 *   shownFields(schema, "sensor", "nmea").some((f) => f.path.join(".") === "device.baud") // true
 */
export function shownFields(root: JsonSchema, kind: ElementKind, sensorKind?: string): FieldSpec[] {
  const all = formFor(root, kind);
  const sensor = sensorKind ?? "generic";
  if (kind === "topic") {
    const mine = SOURCE_OF_KIND[sensor];
    const sources = Object.values(SOURCE_OF_KIND);
    return all.filter((f) => !sources.includes(f.path[0]) || f.path[0] === mine);
  }
  if (kind === "sensor") {
    return all.filter((f) => !(f.path[0] in SENSOR_PART_KINDS) || SENSOR_PART_KINDS[f.path[0]].includes(sensor));
  }
  return all;
}

/** Description of an element kind, from the schema. */
export function kindDescription(root: JsonSchema, kind: ElementKind): string {
  return root.$defs?.[DEF_OF_KIND[kind]]?.description ?? "";
}

/** Reads a field's value from an element. */
export function getPath(value: unknown, path: string[]): unknown {
  let cur: unknown = value;
  for (const seg of path) {
    if (cur === null || typeof cur !== "object") return undefined;
    cur = (cur as Record<string, unknown>)[seg];
  }
  return cur;
}

/**
 * Checks one field value against its spec; returns a message or null.
 * Empty optional fields are fine. Integers arrive as numbers.
 */
export function checkField(spec: FieldSpec, value: unknown): string | null {
  const empty = value === undefined || value === "" || (Array.isArray(value) && value.length === 0);
  if (empty) {
    if (spec.input === "topics" && spec.required && (spec.minItems ?? 0) > 0) return "publishes no topic yet";
    return spec.required ? "required" : null;
  }
  if (spec.input === "integer" || spec.input === "number") {
    if (typeof value !== "number" || !Number.isFinite(value)) return "a number";
    if (spec.input === "integer" && !Number.isInteger(value)) return "a whole number";
    if (spec.minimum !== undefined && value < spec.minimum) return `at least ${spec.minimum}`;
    if (spec.maximum !== undefined && value > spec.maximum) return `at most ${spec.maximum}`;
    return null;
  }
  if (spec.input === "choices" && (!Array.isArray(value) || value.some((v) => !spec.options?.includes(String(v))))) {
    return `some of ${spec.options?.join(", ")}`;
  }
  if (spec.input === "enum" && !spec.options?.includes(String(value))) {
    return `one of ${spec.options?.join(", ")}`;
  }
  if (spec.input === "decimal" && spec.pattern && !new RegExp(spec.pattern).test(String(value))) {
    return "a decimal number such as 0.25";
  }
  if (spec.input === "name" && spec.pattern && !new RegExp(spec.pattern).test(String(value))) {
    return "a letter or _, then letters, digits or _";
  }
  if ((spec.input === "text" || spec.input === "topic") && spec.pattern && !new RegExp(spec.pattern).test(String(value))) {
    return spec.input === "topic" ? "choose a topic" : `must match ${spec.pattern}`;
  }
  if (typeof value === "string" && spec.minLength !== undefined && value.length < spec.minLength) return "required";
  if (typeof value === "string" && spec.maxLength !== undefined && value.length > spec.maxLength) {
    return `at most ${spec.maxLength} characters`;
  }
  return null;
}
