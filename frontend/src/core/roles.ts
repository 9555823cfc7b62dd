/**
 * Who may edit what. Mirrors the backend's per-route role checks so the UI
 * can show read-only views; the backend stays the authority.
 *
 * designer: drone, brokers, link, publishers (and what they publish)
 * integrator: sensors and their measured variables (topics)
 * scientist: subscriptions
 * operator: deploys (edits nothing in the model)
 * admin: everything
 *
 * @example canEdit("scientist", "subscriber") // true
 */
import type { ElementKind } from "./ids";
import type { EdgeKind } from "./graph";
import { canonicalJson } from "./canonical";
import { MODEL_PART_OWNERS } from "./contracts.gen";

export type Role = "designer" | "integrator" | "scientist" | "operator" | "admin";
/** The four views of the workbench, one per working role. */
export const VIEW_ROLES = ["designer", "integrator", "scientist", "operator"] as const;
/** A view: one role's, or "admin" (titled "All roles"): everything, for an admin building a model alone. */
export type ViewRole = (typeof VIEW_ROLES)[number] | "admin";

const EDITS: Record<Role, readonly ElementKind[]> = {
  designer: ["drone", "pubBroker", "subBroker", "link", "publisher"],
  integrator: ["sensor", "topic"],
  scientist: ["subscriber"],
  operator: [],
  admin: ["drone", "sensor", "topic", "pubBroker", "subBroker", "link", "publisher", "subscriber"],
};

/** Whether `role` may create, change or delete elements of `kind`. */
export function canEdit(role: Role, kind: ElementKind): boolean {
  return EDITS[role].includes(kind);
}

/** Whether `role` may edit the campaign (its vehicles and channels): the part's owner, the system designer. */
export function canEditCampaign(role: Role): boolean {
  return role === "admin" || PART_OWNERS["/campaign"] === role;
}

/** Whether `role` may edit anything in the model (the operator may not). */
export function editsAnything(role: Role): boolean {
  return EDITS[role].length > 0;
}

/** Whether `role` may add or remove an edge of `kind` (the edge belongs to its source or target owner). */
export function canEditEdge(role: Role, kind: EdgeKind): boolean {
  if (kind === "publishes") return canEdit(role, "publisher");
  if (kind === "subscribes") return canEdit(role, "subscriber");
  if (kind === "link") return canEdit(role, "link");
  return false; // structure (drone → sensor → topic) follows from the elements
}

/** Whether `role` may ask the drone for what the link missed ("Fill gaps"): the
 * scientist for the subscriptions, the operator for the drone (backfill edits no model). */
export function canFillGaps(role: Role): boolean {
  return role === "scientist" || role === "operator" || role === "admin";
}

/** Whether `role` may cut and restore a simulated link (a rehearsed outage). */
export function canRehearse(role: Role): boolean {
  return role === "operator" || role === "admin";
}

export function canDeploy(role: Role): boolean {
  return role === "operator" || role === "admin";
}

/** The views a user with these roles may open (admin opens all, and "All roles" last). */
export function viewsFor(roles: readonly Role[]): ViewRole[] {
  if (roles.includes("admin")) return [...VIEW_ROLES, "admin"];
  return VIEW_ROLES.filter((r) => roles.includes(r));
}

/** What a view describes, for headers and the user guide. */
export const VIEW_TITLES: Record<ViewRole, string> = {
  designer: "System designer",
  integrator: "Sensor integrator",
  scientist: "Scientist",
  operator: "Operator",
  admin: "All roles",
};

/**
 * Top-level parts of a model and the role owning each, as the backend checks
 * them on save (backend/src/modd_backend/roles.py): the drone without its
 * sensors is the platform (designer), `/drone/sensors` the integrator's, the
 * layout any editor's (null). Generated from the schema's `x-owner` (contracts.gen.ts).
 */
export const PART_OWNERS: Readonly<Record<string, Role | null>> = MODEL_PART_OWNERS;

function parts(model: object): Map<string, string> {
  const out = new Map<string, string>();
  for (const [k, v] of Object.entries(model)) {
    if (v === undefined) continue; // an absent part, however it is written
    if (k === "drone" && v && typeof v === "object") {
      const { sensors, ...platform } = v as Record<string, unknown>;
      out.set("/drone", canonicalJson(platform));
      out.set("/drone/sensors", canonicalJson(sensors));
    } else {
      out.set(`/${k}`, canonicalJson(v));
    }
  }
  return out;
}

/** The parts an edit changes that `role` may not change (empty: allowed). Parts are compared
 * by meaning (core/canonical.ts): "5" and "5.0", or keys in another order, are no change. */
export function deniedParts(role: Role, before: object, after: object): string[] {
  if (role === "admin") return [];
  const a = parts(before);
  const b = parts(after);
  const denied: string[] = [];
  for (const part of new Set([...a.keys(), ...b.keys()])) {
    if (a.get(part) === b.get(part)) continue;
    const owner = part in PART_OWNERS ? PART_OWNERS[part] : "designer";
    if (owner === null ? role === "operator" : owner !== role) denied.push(part);
  }
  return denied.sort();
}

/** The parts an edit changes that none of `roles` may change: what a user holding all of
 * them may not do, whichever view they are in (a whole model pasted or dropped). */
export function deniedPartsFor(roles: readonly Role[], before: object, after: object): string[] {
  if (roles.length === 0) return deniedParts("operator", before, after);
  const each = roles.map((r) => new Set(deniedParts(r, before, after)));
  return [...each[0]].filter((part) => each.every((d) => d.has(part))).sort();
}

const PART_WORDS: Readonly<Record<string, string>> = {
  "/drone": "the drone", "/drone/sensors": "the sensors", "/pubBroker": "the PubBroker",
  "/subBroker": "the SubBroker", "/link": "the link", "/publishers": "the publishers",
  "/subscribers": "the subscriptions", "/layout": "the layout",
};

/** A model part in the model's words ("/subscribers" → "the subscriptions"). */
export function partWords(part: string): string {
  return PART_WORDS[part] ?? `the ${part.replace(/^\//, "")}`;
}

/** The role that owns a part ("designer" when the schema says nothing). */
export function partOwner(part: string): Role {
  const owner = part in PART_OWNERS ? PART_OWNERS[part] : "designer";
  return owner ?? "designer";
}

/**
 * Why a whole model from text or a file is refused, and what to do: the parts in the
 * model's words, who owns them, and the two ways out.
 *
 * @example refusalOfParts(["/subscribers"], ["integrator"])
 *   // "This model changes the subscriptions, which your roles (integrator) may not change. ..."
 */
export function refusalOfParts(parts: readonly string[], roles: readonly Role[]): string {
  const words = parts.map(partWords);
  const owners = [...new Set(parts.map(partOwner))].sort();
  const list = words.length > 1 ? `${words.slice(0, -1).join(", ")} and ${words[words.length - 1]}` : words[0];
  return `This model changes ${list}, which your roles (${roles.join(", ") || "none"}) may not change. `
    + `Ask a user with the ${owners.join(" or ")} role (or an admin) to apply it, or import it as a new project from the Projects page.`;
}
