/**
 * The Inspector's campaign form, derived from the schema as the element
 * forms are (core/schemaForm): the campaign's own fields, a shared channel's
 * and a vehicle's (its brokers and link flattened into dotted fields; its
 * channel a choice among the campaign's channels; each field showing the
 * mission's value it replaces as its placeholder), one device field per
 * mission sensor that reads one, and diagnostics placed at the field their
 * `/campaign/...` pointer names.
 *
 * @example
 *   campaignFields(MODD_SCHEMA, m).vehicle.map((f) => f.path.join("."))
 *   // ["name", "description", "channel", "pubBroker.endpoint.host", ..., "link.transport", ...]
 */
import type { ModdModel } from "./model.gen";
import type { Diagnostic } from "./diagnostics";
import { checkField, formForDef, getPath, type FieldSpec, type JsonSchema } from "./schemaForm";

export interface CampaignFields {
  campaign: FieldSpec[];
  channel: FieldSpec[];
  vehicle: FieldSpec[];
}

/** Where a vehicle's broker directory replaces the mission's. */
const BROKER_PATH: Record<string, string> = { pubBroker: "logPath", subBroker: "configPath" };

/** The mission's value a vehicle's field replaces (shown when the vehicle gives none). */
function missionValue(m: ModdModel, path: readonly string[]): unknown {
  const [part, ...rest] = path;
  if (part === "link") return getPath(m.link ?? {}, rest);
  if (part in BROKER_PATH) {
    const broker = part === "pubBroker" ? m.pubBroker : m.subBroker;
    return rest[0] === "path" ? getPath(broker, [BROKER_PATH[part]]) : getPath(broker, rest);
  }
  return undefined;
}

/** The vehicle's fields: the schema's, its channel one of the campaign's, the mission's values as defaults. */
function vehicleFields(root: JsonSchema, m: ModdModel): FieldSpec[] {
  const channels = (m.campaign?.channels ?? []).map((c) => c.name);
  return formForDef(root, "Vehicle").map((f) => {
    if (f.path.join(".") === "channel") return { ...f, input: "enum", options: channels, default: undefined, emptyLabel: "(no shared channel)" };
    const mission = missionValue(m, f.path);
    return mission === undefined ? f : { ...f, default: mission };
  });
}

export function campaignFields(root: JsonSchema, m: ModdModel): CampaignFields {
  return { campaign: formForDef(root, "Campaign"), channel: formForDef(root, "Channel"), vehicle: vehicleFields(root, m) };
}

/** A vehicle's device for one sensor: the schema's device path, the mission's device as its placeholder. */
export function deviceField(root: JsonSchema, sensor: string, mission: string | undefined): FieldSpec {
  const path = formForDef(root, "DeviceOverride").find((f) => f.path[0] === "path")!;
  return { ...path, path: ["devices", sensor], label: `device of ${sensor}`, required: false, default: mission };
}

/** The sensors a vehicle may give a device for: the mission's that read one, and any other it names (an error to fix). */
export function deviceSensors(m: ModdModel, vehicle: number): Array<{ sensor: string; mission?: string }> {
  const own = m.drone.sensors.filter((s) => s.device).map((s) => ({ sensor: s.name, mission: s.device?.path }));
  const named = (m.campaign?.vehicles[vehicle]?.devices ?? []).map((d) => d.sensor).filter((n) => !own.some((o) => o.sensor === n));
  return [...own, ...[...new Set(named)].map((sensor) => ({ sensor }))];
}

/** Whether `pointer` is `at` or inside it. */
export function isUnder(pointer: string | null | undefined, at: string): boolean {
  return pointer === at || (pointer ?? "").startsWith(`${at}/`);
}

/** The messages of the diagnostics at or inside `at`. */
export function messagesAt(diags: readonly Diagnostic[], at: string): string[] {
  return [...new Set(diags.filter((d) => d.severity !== "info" && isUnder(d.pointer, at)).map((d) => d.message))];
}

/** The messages inside `base` that no field of `fields` (pointers) holds: shown at the top of base's section. */
export function messagesElsewhere(diags: readonly Diagnostic[], base: string, fields: readonly string[]): string[] {
  const mine = diags.filter((d) => d.severity !== "info" && isUnder(d.pointer, base) && !fields.some((f) => isUnder(d.pointer, f)));
  return [...new Set(mine.map((d) => d.message))];
}

/** Pointer of a field of the campaign (`["vehicles", "0", "channel"]` → `/campaign/vehicles/0/channel`). */
export const campaignPointer = (path: readonly (string | number)[]): string =>
  ["/campaign", ...path.map((p) => String(p).replace(/~/g, "~0").replace(/\//g, "~1"))].join("/");

/** The campaign's fields checked as typed (the editor's instant checks; the backend stays the authority). */
export function campaignDiagnostics(m: ModdModel, root: JsonSchema): Diagnostic[] {
  const c = m.campaign;
  if (!c) return [];
  const out: Diagnostic[] = [];
  const check = (specs: FieldSpec[], value: object, at: (string | number)[]) => {
    for (const spec of specs) {
      const message = checkField(spec, getPath(value, spec.path));
      if (message) out.push({ severity: "error", message: `${spec.label}: ${message}`, pointer: campaignPointer([...at, ...spec.path]), source: "local" });
    }
  };
  const f = campaignFields(root, m);
  check(f.campaign, c, []);
  (c.channels ?? []).forEach((ch, i) => check(f.channel, ch, ["channels", i]));
  const vehicle = formForDef(root, "Vehicle"); // the schema's own (a channel is a name, checked by the validator)
  c.vehicles.forEach((v, i) => {
    check(vehicle, v, ["vehicles", i]);
    (v.devices ?? []).forEach((d, j) => check(formForDef(root, "DeviceOverride"), d, ["vehicles", i, "devices", j]));
  });
  return out;
}
