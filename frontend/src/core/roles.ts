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

export type Role = "designer" | "integrator" | "scientist" | "operator" | "admin";
/** The four views of the workbench, one per working role. */
export const VIEW_ROLES = ["designer", "integrator", "scientist", "operator"] as const;
export type ViewRole = (typeof VIEW_ROLES)[number];

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

/** Whether `role` may add or remove an edge of `kind` (the edge belongs to its source or target owner). */
export function canEditEdge(role: Role, kind: EdgeKind): boolean {
  if (kind === "publishes") return canEdit(role, "publisher");
  if (kind === "subscribes") return canEdit(role, "subscriber");
  if (kind === "link") return canEdit(role, "link");
  return false; // structure (drone → sensor → topic) follows from the elements
}

export function canDeploy(role: Role): boolean {
  return role === "operator" || role === "admin";
}

/** The views a user with these roles may open (admin opens all). */
export function viewsFor(roles: readonly Role[]): ViewRole[] {
  if (roles.includes("admin")) return [...VIEW_ROLES];
  return VIEW_ROLES.filter((r) => roles.includes(r));
}

/** What a view describes, for headers and the user guide. */
export const VIEW_TITLES: Record<ViewRole, string> = {
  designer: "System designer",
  integrator: "Sensor integrator",
  scientist: "Scientist",
  operator: "Operator",
};
